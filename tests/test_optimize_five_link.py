"""The five-link biped's least-effort gaits against OptimTraj's committed solver logs.

Source: Kelly's OptimTraj, ``demo/fiveLinkBiped`` at commit 8c43235 (Kelly 2017, SIAM Review
59(4)): step 0.4 m in 0.6 s on level ground, cost ∫Σu² dt over the step, |u| ≤ 100 N·m,
|q| ≤ π/2 rad, |q̇| ≤ 10 rad/s, no knee limit.  ``TrajOpt_GPOPSIPOPTinfo.txt`` ends at objective
263.69884582 and ``TrajOpt_GPOPSSNOPTinfo.txt`` at 302.25469438: two local minima.  Here start 4
(seed 0) reaches the first and start 0 (the model's default start) the second; both must agree
with the logs to 1e-6 relative (the logs' own mesh error is of that order).
"""

from __future__ import annotations

import numpy as np
import pytest

import gaitopt
from gaitopt.optimize import optimize_gait

GPOPS_IPOPT = 263.69884582  # OptimTraj 8c43235, TrajOpt_GPOPSIPOPTinfo.txt, final objective
GPOPS_SNOPT = 302.25469438  # OptimTraj 8c43235, TrajOpt_GPOPSSNOPTinfo.txt, final objective


@pytest.fixture(scope="module")
def gait():
    model = gaitopt.model("five_link_biped")
    return optimize_gait(
        model,
        period=0.6,
        step_length=0.4,
        bounds={name: high for name, (_, high) in model.input_bounds.items()},
        state_bounds=model.state_bounds,
        starts=[0, 4],
        seed=0,
    )


def test_both_optimtraj_minima(gait):
    assert gait.success, gait.message
    costs = {tuple(m.starts): m.cost for m in gait.minima}
    assert set(costs) == {(0,), (4,)}
    assert costs[(4,)] == pytest.approx(GPOPS_IPOPT, rel=1e-6)
    assert costs[(0,)] == pytest.approx(GPOPS_SNOPT, rel=1e-6)
    # Each minimum is refined (below 1e-8) and verified by simulation, not only the best.
    assert all(m.verified and m.discretisation_error <= 1e-8 for m in gait.minima)
    # The best, refined until its discretisation error is below 1e-8, is the IPOPT log's.
    assert gait.cost == pytest.approx(GPOPS_IPOPT, rel=1e-6)
    assert gait.discretisation_error <= 1e-8


def test_optimum_is_verified_by_simulation(gait):
    assert gait.verified
    # Independent simulation (DOP853, rtol 1e-12) with u(t) as feedforward: same state (1e-7)
    # and cost (1e-8 relative) after one step.
    assert gait.verification["return_error"] <= 1e-7
    assert gait.verification["cost_simulated"] == pytest.approx(gait.cost, rel=1e-8)
    assert gait.step_length == pytest.approx(0.4, rel=1e-10)


def test_multipliers_two_ways(gait):
    ad, fd = np.sort_complex(gait.multipliers), np.sort_complex(gait.multipliers_fd)
    assert ad.size == 9 and fd.size == 9  # 10 states less the section's constraint
    # AD through the collocation vs central differences (h = 1e-6) of the simulated map, whose
    # integrator steps end at the profile's breakpoints (measured gap 1.7e-7 relative to the
    # largest, |μ| ≈ 42): 1e-5 relative to the largest.
    np.testing.assert_allclose(ad, fd, atol=1e-5 * np.max(np.abs(ad)))
    assert gait.stable is False  # open loop: a feedforward torque profile does not stabilise
