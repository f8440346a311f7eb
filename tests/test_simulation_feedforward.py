"""A time-varying input (a feedforward u(t), as an optimal gait's torque profile) reaches every
event function, not only the flow: a stance foot's normal force depends on the torque applied at
that instant, so the verification must check the constraint with u(t), not the step's constant."""

import numpy as np

import gaitopt
from gaitopt.simulation.phase import PhaseFunctions


def test_events_see_the_feedforward_input_at_their_time():
    model = gaitopt.model("compass_gait")
    phase = model.phases[0]
    assert phase.constraints, "the compass gait declares its stance contact"
    x = model.lift(model.section_vector({}))
    p = model.p
    funcs = PhaseFunctions(phase, np.zeros(1), p)
    k = len(phase.transitions)  # the first constraint's event index

    def feedforward(tau, step):
        return np.array([40.0 * np.sin(7.0 * tau)])  # N·m, any profile that varies

    funcs._drive = (feedforward, 0.0, 0)
    for t in (0.0, 0.1, 0.23):
        # Independent: the constraint function called directly with u(t) (exact: same function).
        expected = float(phase.constraints[0].function(x, feedforward(t, 0), p))
        assert funcs.signed_guard(k, x, t) == -expected  # constraints fire falling: direction −1
    # ... and the constant input is not what it sees: the torque changes the normal force.
    constant = float(phase.constraints[0].function(x, np.zeros(1), p))
    assert abs(funcs.signed_guard(k, x, 0.23) + constant) > 1e-6


# -- the fast path (a vectorised feedforward: one CasADi call per DOP853 step) against the plain
# callable (SciPy's DOP853 calling the feedforward once per stage): the same simulation ----------

_TOL = {"rtol": 1e-12, "atol": 1e-13}  # the optimal gaits' verification tolerances


class _Sine:
    """``u(t) = a sin(5 t + step)`` N·m, with the vectorised evaluation of the fast path."""

    def __init__(self, amplitude):
        self.amplitude, self.vectorised_calls = amplitude, 0

    def __call__(self, t, step):
        return np.array([self.amplitude * np.sin(5.0 * t + step)])

    def vectorised(self, t, step):
        self.vectorised_calls += 1
        return self.amplitude * np.sin(5.0 * np.asarray(t) + step)[None, :]


def _both(feedforward, steps=2):
    """The compass gait from its default start, with ``feedforward`` (fast path) and with a plain
    callable that wraps it (SciPy's path)."""
    model = gaitopt.model("compass_gait")
    x0 = model.lift(model.default_start())
    fast = gaitopt.simulate(model, x0, steps=steps, feedforward=feedforward, **_TOL)
    plain = gaitopt.simulate(
        model, x0, steps=steps, feedforward=lambda t, k: feedforward(t, k), **_TOL
    )
    return fast, plain


def _assert_same(fast, plain, tol):
    assert (fast.status, fast.success) == (plain.status, plain.success)
    assert [e.transition for e in fast.events] == [e.transition for e in plain.events]
    for a, b in zip(fast.events, plain.events, strict=True):
        assert abs(a.t - b.t) <= tol
        np.testing.assert_allclose(a.state_before, b.state_before, rtol=0, atol=tol)
    np.testing.assert_allclose(fast.section_states, plain.section_states, rtol=0, atol=tol)


def test_fast_path_matches_the_plain_callable_on_a_smooth_feedforward():
    # Independent: SciPy's DOP853 with the feedforward called per stage (the plain path), same
    # tolerances.  Same method and steps up to rounding in the error estimate: measured 3e-15 s
    # in the event times and 6e-14 in the states; 1e-10 allows for the step-size rounding.
    ff = _Sine(1.0)
    fast, plain = _both(ff)
    assert fast.success and len(fast.events) == 2  # two steps walked
    assert ff.vectorised_calls > 0  # the fast path was taken (the plain lambda has no method)
    _assert_same(fast, plain, 1e-10)


def test_fast_path_matches_the_plain_callable_where_a_constraint_fails():
    # A torque of 3 N·m amplitude lifts the stance foot off in the second step (its normal force
    # falls through 0 mid-step): both paths must stop there, with the same event (1e-10 as above;
    # measured 3e-14 s).
    ff = _Sine(3.0)
    fast, plain = _both(ff)
    assert fast.status == "fell" and fast.events[-1].transition == "stance foot lifts off"
    _assert_same(fast, plain, 1e-10)


def test_fast_path_with_a_jumping_profile_matches_the_plain_callable():
    # A piecewise-linear profile that jumps at its breaks (as the collocation's inputs do): the
    # fast path ends its steps at the breaks, SciPy's path steps across them and shrinks its
    # steps there; both resolve the jumps to their tolerance (measured gaps 5e-12 s in the
    # event times, 4e-11 in the states; 1e-9 is 20× that, still 1000× below the jumps' effect).
    from gaitopt.optimize.profile import InputProfile
    from gaitopt.optimize.verify import feedforward_of

    breaks = np.array([0.0, 0.15, 0.3, 0.5, 0.7])  # s; the step lasts about 0.69 s
    coefficients = np.array([[[0.0], [1.0]], [[4.0], [-2.0]], [[-3.0], [0.5]], [[0.0], [2.0]]])
    profile = InputProfile(breaks, coefficients)  # N·m: slopes and values per piece
    assert profile(0.15) != profile(np.nextafter(0.15, 0))  # it does jump
    fast, plain = _both(feedforward_of([profile]))
    assert fast.success
    _assert_same(fast, plain, 1e-9)
    # ... and no step of the fast path straddles a break: each break inside an arc (in the time
    # since its step's section) is one of the arc's step ends.
    for arc in fast.arcs:
        section = fast.section_times[fast.section_times <= arc.t0][-1]
        inside = section + breaks[(section + breaks > arc.t0) & (section + breaks < arc.t1)]
        assert inside.size and np.all(np.isin(inside, arc.solution.ts))


def test_a_jump_that_lifts_the_foot_off_is_caught_at_the_jump():
    # The hip torque jumps from 0 to −3000 N·m at 0.2 s: the stance foot's normal force is
    # positive before and negative from that instant (the event functions see the input at their
    # time, the value from the jump on), so the foot lifts off at 0.2 s in both paths (brentq
    # brackets the jump to 1e-15 s; 1e-12 allows for the dense output's bracket ends).
    from gaitopt.optimize.profile import InputProfile
    from gaitopt.optimize.verify import feedforward_of

    profile = InputProfile(np.array([0.0, 0.2, 0.7]), np.array([[[0.0], [0.0]], [[0.0], [-3e3]]]))
    fast, plain = _both(feedforward_of([profile]))
    for sim in (fast, plain):
        assert sim.status == "fell" and sim.events[-1].transition == "stance foot lifts off"
        assert abs(sim.events[-1].t - 0.2) < 1e-12
    _assert_same(fast, plain, 1e-10)


def test_profile_vectorised_equals_its_scalar_evaluation():
    # Exact: the same clipping, interval and Horner arithmetic at every time, including the
    # breaks, the last time before each, and before 0 and after the end (held values).
    from gaitopt.optimize.profile import InputProfile

    rng = np.random.default_rng(0)
    starts = np.cumsum(np.r_[0.0, rng.uniform(0.01, 0.05, 9)])
    lengths = np.diff(np.r_[starts, starts[-1] + 0.03])
    tau = np.array([0.1, 0.5, 0.9, 1.0])
    profile = InputProfile.from_nodes(
        starts, lengths, tau, [rng.normal(size=(3, 4)) for _ in starts]
    )
    b = profile.breaks
    times = np.r_[-0.1, b, np.nextafter(b, -1.0), rng.uniform(-0.1, 0.5, 200), 1.0]
    expected = np.array([profile(t) for t in times]).T
    assert np.array_equal(profile.vectorised(times), expected)
