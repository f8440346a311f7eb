"""The batched closed loop (gaitopt.control.closed_loop_batch) against the per-start closed loop
(gaitopt.control.closed_loop, the referee), on seeded random ground: the same steps survived,
the same way of ending, and the same apex heights and inputs.

Tolerance 1e-9 (m, rad): both run the same compiled DOP853 arcs with each step's input and
ground, but the batch integrates each step from time 0 where the referee carries the time on, so
the step sizes' last bits differ and the states agree to the integrator's tolerance (rtol 1e-11
over up to 40 steps of an unstable map: measured ≤ 4e-14 for the SLIP here), not bit for bit.
The outcomes are the same: a step that begins at an apex with ż ≈ 1e-16 far from t = 0 once
stopped the referee's integrator (a short-excursion step bound of 1e-17 s, below 10 ulp of t;
gaitopt.simulation.phase._short_excursion now leaves out excursions that cannot arm a guard), so
it is a fall in both."""

from __future__ import annotations

import numpy as np
import pytest

import gaitopt
from gaitopt import control as gc
from gaitopt import terrain as gt

TOL = 1e-9


@pytest.fixture(scope="module")
def slip_design():
    slip = gaitopt.model("slip")
    deadbeat = gc.deadbeat(slip, target={"z": 1.0})
    return slip, deadbeat, gc.lqr(deadbeat.linearisation, Q=1.0, R=1.0)


def _agree(policy, model, ground, starts, seeds, amplitude, steps, target):
    """Batch and referee over the seeds; returns the batch."""
    batch = gc.closed_loop_batch(
        policy, model, starts, steps=steps, target=target,
        terrain=[gt.random_terrain(ground, s, amplitude) for s in seeds],
    )  # fmt: skip
    for i, seed in enumerate(seeds):
        x0 = dict(zip(model.section.coordinates, starts[i], strict=True))
        ref = gc.closed_loop(policy, model, x0, steps=steps, target=np.asarray(target, float),
                             terrain=gt.random_terrain(ground, seed, amplitude))  # fmt: skip
        assert batch.survived[i] == ref.survived, (seed, batch.message(i), ref.simulation.message)
        assert batch.status[i] == ref.simulation.status, (seed, ref.simulation.message)
        if ref.simulation.status == "fell":
            assert batch.message(i).split(" at t")[0] == ref.simulation.message.split(" at t")[0]
        k = ref.survived
        np.testing.assert_allclose(batch.section[i, : k + 1], ref.section, rtol=TOL, atol=TOL)
        np.testing.assert_allclose(batch.errors[i, : k + 1], ref.errors, rtol=TOL, atol=TOL)
        np.testing.assert_allclose(batch.inputs[i, : len(ref.inputs)], ref.inputs, rtol=TOL,
                                   atol=TOL)  # fmt: skip
        assert np.all(np.isnan(batch.section[i, k + 1 :]))
    return batch


def test_slip_controllers_on_rough_ground_agree_with_closed_loop(slip_design):
    """SLIP on ±10 cm random ground from apex 1.03 m, 6 seeds: open loop (falls within a few
    steps), LQR (vectorised policy) and deadbeat (a rootfinder per start) over 25 steps."""
    slip, deadbeat, lqr = slip_design
    starts = np.full((6, 1), 1.03)
    nominal = deadbeat.linearisation.nominal_input
    fell = _agree(nominal, slip, slip, starts, range(6), 0.1, 25, [1.0])
    assert np.all(fell.status == "fell") and fell.survived.max() < 6  # unstable open loop
    for policy in (lqr, deadbeat):
        run = _agree(policy, slip, slip, starts, range(6), 0.1, 25, [1.0])
        assert np.all(run.survived == 25)
    # at ±15 cm the runners fall at different steps, each as the referee
    run = _agree(lqr, slip, slip, starts, range(6), 0.15, 25, [1.0])
    assert len(set(run.survived.tolist())) > 1


def test_compass_gait_on_random_slopes_agrees_with_closed_loop():
    """Passive compass gait (no controller) on a slope drawn per step within ±30 % of its own,
    from perturbed starts: a second model, slope as the ground parameter."""
    compass = gaitopt.model("compass_gait")
    centre = compass.section_vector(compass.default_start())
    starts = centre * (1 + 0.02 * np.arange(4))[:, None]
    _agree(None, compass, compass, starts, range(4), 0.3 * compass.slope, 8, centre)


def test_apex_errors_and_bad_input(slip_design):
    """The RMS and largest error per run over the returns after the first (numpy on the
    errors), and one-line errors naming the argument."""
    slip, deadbeat, lqr = slip_design
    run = gc.closed_loop_batch(
        lqr,
        slip,
        [[1.03], [1.05]],
        steps=5,
        terrain=[gt.random_terrain(slip, s, 0.05) for s in (0, 1)],
    )
    rms, peak = run.apex_errors()
    for i in range(2):
        e = run.errors[i, 1:]
        assert rms[i] == pytest.approx(np.sqrt(np.mean(e**2)), rel=1e-14)
        assert peak[i] == np.max(e)
    with pytest.raises(gaitopt.GaitoptInputError, match="`terrain` must give one callable"):
        gc.closed_loop_batch(lqr, slip, [[1.03], [1.05]], steps=2, terrain=[None])
    with pytest.raises(gaitopt.GaitoptInputError, match="`target` is needed"):
        gc.closed_loop_batch(None, slip, [[1.03]], steps=2)
    with pytest.raises(gaitopt.GaitoptInputError, match="unknown parameter 'height'"):
        gc.closed_loop_batch(lqr, slip, [[1.03]], steps=2, terrain=lambda k: {"height": 0.1})
    with pytest.raises(gaitopt.GaitoptInputError, match="`controller` as a constant input"):
        gc.closed_loop_batch([0.1, 0.2], slip, [[1.03]], steps=2, target=[1.0])


def test_a_policy_with_batch_is_called_once_per_step(slip_design):
    """A policy with ``batch(step, states)`` is evaluated for all running starts at once (one
    call per step), with the same runs as calling it start by start (exact: the same inputs,
    the same simulation)."""
    slip, deadbeat, lqr = slip_design

    class Counted:
        def __init__(self):
            self.calls = 0

        def __call__(self, k, x):
            return lqr(k, x)

        def batch(self, k, states):
            self.calls += 1
            return np.array([lqr(k, x) for x in states])

    terrain = [gt.random_terrain(slip, s, 0.05) for s in range(3)]
    policy = Counted()
    together = gc.closed_loop_batch(policy, slip, np.full((3, 1), 1.03), steps=6,
                                    terrain=terrain, target=[1.0])  # fmt: skip
    assert policy.calls == 6
    one_by_one = gc.closed_loop_batch(lambda k, x: lqr(k, x), slip, np.full((3, 1), 1.03),
                                      steps=6, terrain=terrain, target=[1.0])  # fmt: skip
    np.testing.assert_array_equal(together.section, one_by_one.section)


def test_a_step_from_an_apex_late_in_a_run_ends_in_the_fall_not_an_integrator_failure(slip_design):
    """SLIP with LQR on ±15 cm ground, seed 0: its tenth step begins at an apex with ż ≈ 1e-16
    at t ≈ 5.4 s.  The short-excursion step bound for that guard was ~1e-17 s, under the
    smallest step at that time (10 ulp of t), and the run ended "integrator failed" after 9
    steps (results/slip_rough_terrain before this fix).  An excursion of depth ż²/(2 z̈) ~ 1e-33 m
    cannot arm the guard, so no bound: the runner's fall is found, as from t = 0."""
    slip, _, lqr = slip_design
    run = gc.closed_loop(lqr, slip, {"z": 1.03}, steps=40, target=np.array([1.0]),
                         terrain=gt.random_terrain(slip, 0, 0.15))  # fmt: skip
    assert run.survived == 9
    assert run.simulation.status == "fell", run.simulation.message
    assert run.simulation.message.startswith("apex below touchdown height")
