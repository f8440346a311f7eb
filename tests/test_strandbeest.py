"""Jansen's linkage (the Strandbeest leg), ``gaitopt linkage``, and the ``strandbeest`` walker.

Independent computation: the joints by explicit circle intersections written here in NumPy
(each joint from two known points, on the side of the initial assembly), against the module's
Newton continuation with CasADi's rootfinder; the walker's gait by the energy-plus-impact closed
form (rootfinder geometry, quadrature) against simulation of the hybrid model (closed-form dyads,
adaptive ODE integration, event location).
"""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

from gaitopt.cli import main
from gaitopt.errors import GaitoptInputError, ParameterError
from gaitopt.linkage import SIX_PAIR_PHASES, JansenLinkage, linkage, loop_closure

HOLY = dict(a=38, b=41.5, c=39.3, d=40.1, e=55.8, f=39.4, g=36.7, h=65.7, i=49, j=50, k=61.9,
            l=7.8, m=15)  # fmt: skip


@pytest.fixture(scope="module")
def turn():
    return JansenLinkage().turn(720)


# -- an independent solver: circle intersections in NumPy --------------------------------------
def _meet(p1, r1, p2, r2, pick):
    """The intersection of circles (p1, r1), (p2, r2) chosen by ``pick`` (a key function)."""
    d = p2 - p1
    dist = math.hypot(*d)
    along = (r1**2 - r2**2 + dist**2) / (2 * dist)
    h = math.sqrt(r1**2 - along**2)
    mid = p1 + along * d / dist
    n = np.array([-d[1], d[0]]) / dist
    return min((mid + h * n, mid - h * n), key=pick)


def _independent_foot(theta: float) -> np.ndarray:
    """Foot by circle intersections (units of the holy numbers; Wikipedia's figure: upper joint
    above, lower below, back and knee away from the crank, foot below)."""
    L = HOLY
    pivot = np.array([-L["a"], -L["l"]])
    pin = L["m"] * np.array([math.cos(theta), math.sin(theta)])
    upper = _meet(pin, L["j"], pivot, L["b"], lambda q: -q[1])
    lower = _meet(pin, L["k"], pivot, L["c"], lambda q: q[1])
    back = _meet(pivot, L["d"], upper, L["e"], lambda q: q[0])
    knee = _meet(back, L["f"], lower, L["g"], lambda q: q[0])
    return _meet(knee, L["h"], lower, L["i"], lambda q: q[1])


def test_loop_closure_residual_vanishes_along_the_turn(turn):
    # Newton's residual: |X − Y|² − L² (m²) below 1e-13 at every sample of the turn.
    p = turn.linkage.p
    for theta, z in zip(turn.thetas, turn.z, strict=True):
        res = np.asarray(loop_closure(z.ravel(), theta, p), dtype=float)
        assert np.max(np.abs(res)) < 1e-13


def test_turn_closes_on_its_start_assembly(turn):
    # Continuity: after 2π the continuation is back on the initial assembly (not the other
    # branch) to 1e-12 m.
    np.testing.assert_allclose(turn.z[-1], turn.z[0], atol=1e-12)


def test_foot_path_matches_circle_intersections(turn):
    # Independent method (explicit dyads, NumPy): the same foot to 1e-12 m.
    for theta, foot in zip(turn.thetas[::15], turn.foot[::15], strict=True):
        np.testing.assert_allclose(foot, 0.01 * _independent_foot(theta), atol=1e-12)


def test_ad_foot_velocity_matches_finite_differences(turn):
    # AD through the rootfinder (implicit function theorem) vs central differences of the
    # independent foot path, step 1e-5 rad: truncation ~h²·|F'''| ≈ 1e-10 m/rad; tolerance 1e-8.
    h = 1e-5
    for theta, velocity in zip(turn.thetas[::24], turn.foot_velocity[::24], strict=True):
        fd = 0.01 * (_independent_foot(theta + h) - _independent_foot(theta - h)) / (2 * h)
        np.testing.assert_allclose(velocity, fd, atol=1e-8)


def test_numbers_against_an_independent_computation(turn):
    # Width, height, ground fraction and ripples from 36 000 samples of the NumPy dyads (crank
    # step 1.7e-4 rad): extents to 1e-6 m (second-order sampling error), the ground fraction to
    # 1e-4 (one sample is 2.8e-5 of a turn), ripples to 2e-6 m.
    thetas = np.linspace(0, 2 * math.pi, 36000, endpoint=False)
    feet = 0.01 * np.array([_independent_foot(t) for t in thetas])
    numbers = turn.numbers()
    assert numbers["width"] == pytest.approx(np.ptp(feet[:, 0]), abs=1e-6)
    assert numbers["height"] == pytest.approx(np.ptp(feet[:, 1]), abs=1e-6)
    y_min = feet[:, 1].min()
    fraction = np.mean(feet[:, 1] <= y_min + 0.005)
    assert numbers["ground_fraction"] == pytest.approx(fraction, abs=1e-4)

    def y_at(t):  # periodic lookup on the sample grid (36000 samples = 6 × 6000)
        return feet[np.round(np.mod(t, 2 * math.pi) / (2 * math.pi) * 36000).astype(int) % 36000, 1]

    def ripple(phases):
        ys = [y_at(thetas + ph) for ph in phases] + [y_at(math.pi - thetas - ph) for ph in phases]
        return np.ptp(-np.min(ys, axis=0))

    assert numbers["ripple_six_pairs"] == pytest.approx(ripple(SIX_PAIR_PHASES), abs=2e-6)
    assert numbers["ripple_one_pair"] == pytest.approx(ripple((0.0,)), abs=2e-6)
    # The measured values (README): width 0.6791 m, height 0.2246 m, ground 36.6 %.
    assert numbers["width"] == pytest.approx(0.679084, abs=1e-6)
    assert numbers["height"] == pytest.approx(0.224572, abs=1e-6)


def test_mirror_pair_is_symmetric(turn):
    # The mirror leg's foot at θ is the leg's at π − θ reflected: ride heights of one pair are
    # symmetric about θ = π/2 (θ ↦ π − θ swaps the legs) to 1e-12 m.
    thetas = np.linspace(0, 2 * math.pi, 97)
    ride = turn.ride_height((0.0,), thetas)
    ride_swapped = turn.ride_height((0.0,), math.pi - thetas)
    np.testing.assert_allclose(ride, ride_swapped, atol=1e-12)


def test_unassemblable_lengths_are_refused_naming_the_parameter():
    with pytest.raises(ParameterError, match=r"parameter `b` = 0.2 m.*crank angle"):
        JansenLinkage(b=0.2).turn(180)
    with pytest.raises(ParameterError, match=r"`j` = 0.3 m.*initial assembly"):
        JansenLinkage(j=0.3).turn(180)
    with pytest.raises(GaitoptInputError, match="unknown linkage 'jansn'; did you mean 'jansen'"):
        linkage("jansn")
    with pytest.raises(ParameterError, match="out of range"):
        JansenLinkage(m=-1)


# -- CLI -----------------------------------------------------------------------------------------
def test_cli_json_keys_and_exit_status(capsys):
    status = main(["linkage", "jansen", "--json", "--samples", "360"])
    out = json.loads(capsys.readouterr().out)
    assert status == 0 and out["success"] is True
    assert {"width", "height", "ground_fraction", "ripple_six_pairs", "ripple_one_pair"} <= set(out)
    assert out["units"]["width"] == "m" and out["width"] == pytest.approx(0.679084, abs=1e-6)


def test_cli_set_changes_a_length(capsys):
    status = main(["linkage", "jansen", "--set", "h=0.6", "--json", "--samples", "360"])
    out = json.loads(capsys.readouterr().out)
    assert status == 0 and out["params"]["h"] == 0.6 and out["width"] != pytest.approx(0.679084)


@pytest.mark.parametrize(
    ("argv", "expected"),
    [
        (["linkage", "jansn"], "LINKAGE 'jansn' is not a linkage; did you mean 'jansen'?"),
        (["linkage", "jansen", "--set", "x=1"], "--set x=1: jansen has no parameter 'x'"),
        (["linkage", "jansen", "--set", "j=abc"], "'abc' is not a number"),
        (["linkage", "jansen", "--set", "j=-1"], "out of range"),
        (["linkage", "jansen", "--set", "b=0.2"], "parameter `b` = 0.2 m: the leg cannot be"),
    ],
)
def test_cli_bad_input_is_one_line_exit_2(capsys, argv, expected):
    status = main([*argv, "--samples", "180"])
    out, err = capsys.readouterr()
    assert status == 2 and out == ""
    assert err.startswith("gaitopt: error: ") and err.count("\n") == 1 and expected in err


# -- the walker ----------------------------------------------------------------------------------
@pytest.fixture(scope="module")
def walker():
    from gaitopt.models.strandbeest import Strandbeest

    return Strandbeest()


def test_energy_is_conserved_along_the_flow(walker):
    # E = ½ M θ̇² + V − τ θ is a first integral of each support phase: its spread over each
    # simulated arc below 1e-9 of its scale (simulation rtol 1e-11).  With a torque too.
    import gaitopt

    for model in (walker, walker.replace(slope=0.0, torque=5.0)):
        sim = gaitopt.simulate(model, {"theta_dot": 6.0}, steps=1)  # six phases
        assert len(sim.arcs) >= 6
        for arc in sim.arcs:
            energy = model.phases[arc.phase].conserved["energy"]
            _, X = arc.sample(40)
            values = np.array([float(energy(X[:, j], model.p)) for j in range(X.shape[1])])
            assert np.ptp(values) < 1e-9 * (1 + np.max(np.abs(values)))


def test_gait_matches_the_energy_and_impact_closed_form(walker):
    # Closed form (rootfinder geometry, energy equation, impact ratios, Gauss–Legendre period)
    # vs simulation of the hybrid model from the closed-form fixed point over one period (six
    # support phases): return to 1e-8 rad/s, period to 1e-9 s; the multiplier from the
    # simulated return map by central differences (±1e-3 rad/s) to 1e-6.
    import gaitopt

    cf = walker.closed_form()
    assert cf["exists"]
    x0 = cf["theta_dot"]

    def ret(w):
        sim = gaitopt.simulate(walker, {"theta_dot": w}, steps=1)  # one period
        return sim.section_states[-1][1], sim.section_times[-1] - sim.section_times[0]

    back, period = ret(x0)
    assert back == pytest.approx(x0, abs=1e-8)
    assert period == pytest.approx(cf["period"], abs=1e-9)
    slope = (ret(x0 + 1e-3)[0] - ret(x0 - 1e-3)[0]) / 2e-3
    assert slope == pytest.approx(cf["multiplier"], abs=1e-6)
    # The model's own affine energy map (its energy functions and resets) agrees too.
    assert math.sqrt(walker.energy_map_fixed_point()) == pytest.approx(x0, rel=1e-10)


def test_support_series_match_the_exact_linkage_off_grid():
    # The flow, guards and resets use Chebyshev series of each support phase's M_s, M_s', the
    # centre of mass's rate and the guards and impact ratios (support_series).  Against the
    # closed-form dyads of all twelve legs (_support_exact) at 101 points between the
    # interpolation nodes and the fit's own check points: relative error below 1e-10 (each
    # quantity against its largest magnitude on the interval; the guards, differences of
    # foot heights, against GUARD_SCALE = 0.1 m).
    import casadi as ca

    from gaitopt.models import strandbeest as sb

    feet, _ = sb.contact_sequence()
    theta = ca.SX.sym("theta")
    for k in range(len(feet)):
        _, a, b, _ = sb.support_series(k)
        series = sb._series(theta, k)
        approx = ca.Function("approx", [theta], [ca.vertcat(*series.values())])
        thetas = np.linspace(a, b, 101) + 0.37 * (b - a) / 101  # off the Chebyshev nodes
        thetas = thetas[thetas < b]
        exact = np.asarray(sb._support_exact(k).map(thetas.size)(thetas.reshape(1, -1)))
        got = np.asarray(approx.map(thetas.size)(thetas.reshape(1, -1)))
        scale = np.max(np.abs(exact), axis=1)
        for q in ("guard", "guard_back"):
            i = sb.SERIES_QUANTITIES.index(q)
            scale[i] = max(scale[i], sb.GUARD_SCALE)
        error = np.max(np.abs(got - exact), axis=1) / scale
        assert np.all(error < 1e-10), (k, dict(zip(sb.SERIES_QUANTITIES, error, strict=True)))


def test_shooting_finds_the_closed_form_gait(walker):
    # Multiple shooting of the registered model (series flow) against the energy-plus-impact
    # closed form (rootfinder geometry, Gauss–Legendre period): θ̇* = 6.223232504417 rad/s,
    # multiplier 0.97125350499, period 0.164696781280 s at slope 0.02 rad, each to 1e-9.
    import gaitopt

    cf = walker.closed_form()
    cycle = gaitopt.find_limit_cycle(gaitopt.model("strandbeest"))
    assert cycle.success and cycle.verified, cycle.message
    assert cycle.fixed_point["theta_dot"] == pytest.approx(cf["theta_dot"], abs=1e-9)
    (multiplier,) = np.asarray(cycle.multipliers)
    assert multiplier.real == pytest.approx(cf["multiplier"], abs=1e-9)
    assert cycle.period == pytest.approx(cf["period"], abs=1e-9)
    assert cf["theta_dot"] == pytest.approx(6.223232504417, abs=1e-12)
    assert cf["multiplier"] == pytest.approx(0.97125350499, abs=1e-11)
    assert cf["period"] == pytest.approx(0.164696781280, abs=1e-12)


def test_drawn_handovers_land_on_the_drawn_ground(walker):
    # The animation's ground is y = −x tan γ (downhill towards +x): each handover's next foot,
    # drawn relative to the stance foot (on the same or the mirror side of the machine), is on
    # it to 1e-9 m (the guard: equal heights in the slope frame), and over a period the crank
    # axle moves downhill (+x, down by tan γ per metre: the frame stays level on level feet).
    import gaitopt
    from gaitopt.animation import walker_frames

    sim = gaitopt.simulate(walker, {"theta_dot": walker.closed_form()["theta_dot"]}, steps=1)
    assert sim.success and len(sim.events) >= 6, sim.message
    for event in sim.events[:6]:
        phase = walker.phases[event.phase]
        pts = np.asarray(phase.points(event.state_before, walker.p))
        step = pts[:, phase.point_names.index("next_foot")]
        assert abs(step[0]) > 0.01
        assert step[1] == pytest.approx(-step[0] * math.tan(walker.slope), abs=1e-9)
    start, end = walker_frames(walker, sim, [sim.arcs[0].t0, sim.arcs[-1].t1])
    for frame in (start, end):
        x, y = frame["contact"]
        assert y == pytest.approx(-x * math.tan(walker.slope), abs=1e-9)
    moved = end["mass"][:, 0] - start["mass"][:, 0]
    assert moved[0] > 0.05
    assert moved[1] == pytest.approx(-moved[0] * math.tan(walker.slope), abs=1e-9)


def test_the_animation_draws_the_linkage(walker):
    """The GIF shows the machine, not spokes: every phase declares all joints of the twelve legs
    and the drawing has each leg's ten rods and its crank.  Rigid rods are an invariant of the
    drawing: each drawn rod is its holy number × 0.01 m long (Jansen 2007; gaitopt.linkage) to
    1e-12 m, at any crank angle; the stance foot is drawn at the contact (the origin)."""
    from gaitopt.models.strandbeest import RODS

    lengths = JansenLinkage().params
    assert len(walker.drawing) == 12 * (len(RODS) + 1)
    for phase in walker.phases:
        for theta in (0.3, 1.7, 4.0):
            pts = np.asarray(phase.points(np.array([theta, 2.0]), walker.p))
            at = {name: pts[:, i] for i, name in enumerate(phase.point_names)}
            np.testing.assert_allclose(at["foot"], 0.0, atol=1e-15)
            for leg in range(12):
                for a, b, letter in RODS:
                    length = np.linalg.norm(at[f"leg{leg}_{a}"] - at[f"leg{leg}_{b}"])
                    assert length == pytest.approx(lengths[letter], abs=1e-12)
                crank = np.linalg.norm(at[f"leg{leg}_pin"] - at["axle"])
                assert crank == pytest.approx(lengths["m"], abs=1e-12)
