"""Transverse linearisation and transverse LQR (gaitopt.transverse, issue 21).

Sources of the checks: the nontrivial Floquet multipliers of each gait, by the implicit function
theorem on the shooting equations (LimitCycle) or on the Radau collocation (OptimalGait), are an
independent computation of the eigenvalues the transverse monodromy must have (Manchester et al.
2011: a transverse linearisation's monodromy is the linearised Poincaré map on the moving
surface, conjugate to the return map on any other section)."""

from __future__ import annotations

import numpy as np
import pytest

import gaitopt
from gaitopt.transverse import transverse_linearisation


def _match(a: np.ndarray, b: np.ndarray) -> tuple[float, list[complex]]:
    """Largest distance pairing each of ``a`` with the nearest unused one of ``b``, and the
    unpaired rest of ``b``."""
    rest = list(np.asarray(b, complex))
    worst = 0.0
    for z in np.asarray(a, complex):
        j = int(np.argmin([abs(z - y) for y in rest]))
        worst = max(worst, abs(z - rest.pop(j)))
    return worst, rest


@pytest.mark.parametrize("name", ["compass_gait", "kneed_walker", "slip"])
def test_monodromy_has_the_floquet_multipliers(cycles, name):
    gait = cycles[name]
    lin = transverse_linearisation(gait)
    # the shooting's multipliers are accurate to its tol 1e-10; the re-integration's rtol 1e-12
    gap, rest = _match(gait.multipliers, lin.multipliers)
    assert gap < 1e-8
    # the transverse surface has n − 1 dimensions; the others are 0 (the reset's image has
    # lower dimension: the kneed walker's knee strike drops two) or 1 (the SLIP's energy)
    assert len(rest) == lin.dimensions[0] - len(gait.multipliers)
    assert all(min(abs(z), abs(z - 1)) < 1e-9 for z in rest)
    # the kneed walker changes dimension: 5 transverse states before the knee strike, 3 after
    if name == "kneed_walker":
        assert lin.dimensions == [5, 3]
        assert lin.jumps[0].shape == (3, 5) and lin.jumps[1].shape == (5, 3)
    # read on the clock instead of the phase, a constant input changes nothing (and the
    # clock, restarted at the section, adds a 0)
    gap, rest = _match(gait.multipliers, lin.clock_multipliers)
    assert gap < 1e-8


def test_reintegrated_orbit_closes(cycles):
    lin = transverse_linearisation(cycles["compass_gait"])
    # the DOP853 re-integration (rtol 1e-12) against the shooting's orbit (tol 1e-10)
    assert lin.orbit.closure < 1e-9


def test_simulate_with_a_state_feedback(cycles):
    gait = cycles["compass_gait"]
    model = gait.model
    calls = []

    def law(t, x, phase, step):
        calls.append(phase)
        return np.zeros(1)

    plain = gaitopt.simulate(model, gait.x, steps=3)
    fed = gaitopt.simulate(model, gait.x, steps=3, feedback=law)
    # the same passive flow through SciPy's stepper instead of the compiled one, both at
    # rtol 1e-11: the returns agree to the integrators' accuracy
    assert fed.success and calls
    assert np.max(np.abs(fed.section_states - plain.section_states)) < 1e-8
    with pytest.raises(gaitopt.GaitoptInputError, match="feedback"):
        gaitopt.simulate(model, gait.x, steps=1, feedback=law, feedforward=lambda t, k: [0.0])


@pytest.fixture(scope="module")
def passive_lqr(cycles):
    """Transverse LQR on the compass gait's passive orbit (its hip torque as the input),
    Drake's weights (runTransverseCycle.m: Q = diag(10, 5, 1, 0.5), R = 0.1)."""
    from gaitopt.transverse import transverse_lqr

    return transverse_lqr(
        cycles["compass_gait"], Q=[10, 5, 1, 0.5], R=0.1, orbits=12, starts=[[0.0, 0.02, 0.0]]
    )


def test_transverse_lqr_closed_loop(passive_lqr):
    res = passive_lqr
    assert res.success, res.message
    # the Riccati iteration reaches its 1e-11 fixed point; the closed loop is faster than the
    # passive gait (|λ|max 0.5806)
    assert res.riccati.converged
    assert np.max(np.abs(res.closed_loop_multipliers)) < np.max(np.abs(res.open_loop_multipliers))
    # the closed-loop monodromy against central differences (h = 1e-5) of the simulated
    # closed-loop map: independent methods, agreement to the differences' 1e-4
    assert res.multiplier_gap is not None and res.multiplier_gap < 1e-4
    trial = res.trials[0]
    assert trial.converged and trial.saturated == 0
    data = res.to_json()
    assert data["gains"][0]["K"] and len(data["closed_loop_multipliers"]) == 3


def test_riccati_solution_solves_the_differential_equation(passive_lqr):
    """S(τ) from the Hamiltonian transition against the Riccati ODE itself, by central
    differences in τ (step 1e-5 s: truncation ~1e-10 relative, well below the 1e-6 tolerance),
    and the jump condition S⁻ = Jᵀ S⁺ J at the heel strike (periodic: S⁺ is the start's)."""
    ric, lin = passive_lqr.riccati, passive_lqr.linearisation
    frame = lin.frames[0]
    Q = passive_lqr.Q[0]
    R_inv = np.linalg.inv(passive_lqr.R)
    for tau in (0.1, 0.37, 0.6):
        d = frame.at(tau)
        S = ric.cost_matrix(0, tau)
        h = 1e-5
        S_dot = (ric.cost_matrix(0, tau + h) - ric.cost_matrix(0, tau - h)) / (2 * h)
        A, B, Pi = d["A_perp"], d["B_perp"], d["Pi"]
        rhs = -(A.T @ S + S @ A - S @ B @ R_inv @ B.T @ S + Pi @ Q @ Pi.T)
        assert np.max(np.abs(S_dot - rhs)) < 1e-6 * np.max(np.abs(rhs))
    J = lin.jumps[0]
    S_end = ric.cost_matrix(0, frame.stage.duration)
    assert np.allclose(S_end, J.T @ ric.cost_matrix(0, 0.0) @ J, rtol=1e-9, atol=1e-9)


def test_transverse_lqr_bad_input(cycles):
    from gaitopt.transverse import transverse_lqr

    gait = cycles["compass_gait"]
    for kwargs, word in (
        ({"R": 0.0}, "`R`"),
        ({"R": -1.0}, "`R`"),
        ({"Q": [1, 2, 3]}, "`Q`"),
        ({"Q": -np.eye(4)}, "`Q`"),
        ({"Q": np.ones((3, 3))}, "`Q`"),
    ):
        with pytest.raises(gaitopt.GaitoptInputError, match=word):
            transverse_lqr(gait, **kwargs)
    with pytest.raises(gaitopt.GaitoptInputError, match="no inputs"):
        transverse_lqr(cycles["rimless_wheel"])


def _cli(*argv: str) -> int:
    from gaitopt.cli import main

    return main(list(argv))


@pytest.mark.parametrize(
    "argv, word",
    [
        (["--transverse", "--r", "0"], "--r 0"),
        (["--transverse", "--q", "1,2"], "--q 1,2"),
        (["--transverse", "--compare"], "--compare"),
        ([], "--transverse"),
    ],
)
def test_cli_stabilise_bad_input(capsys, argv, word):
    assert _cli("stabilise", "compass_gait", *argv) == 2
    err = capsys.readouterr().err.strip()
    assert err.count("\n") == 0 and word in err and "Traceback" not in err


def test_cli_stabilise_model_without_inputs(capsys):
    assert _cli("stabilise", "rimless_wheel", "--transverse") == 2
    assert "no inputs" in capsys.readouterr().err


@pytest.mark.slow
def test_cli_stabilise_json(capsys):
    import json

    code = _cli(
        "stabilise", "compass_gait", "--transverse", "--q", "10,5,1,0.5", "--r", "0.1",
        "--orbits", "10", "--perturbation", "0.02", "--json",
    )  # fmt: skip
    data = json.loads(capsys.readouterr().out)
    assert code == 0 and data["success"], data["message"]
    assert data["gait"]["kind"] == "limit cycle"
    assert len(data["gains"]) == 1 and len(data["gains"][0]["K"]) == 21
    assert data["multiplier_gap"] < 1e-4 and not data["saturated"]
    assert {"gait_s", "linearise_s", "riccati_s", "trials_s"} <= set(data["timings"])
    assert all(t["converged"] for t in data["trials"])


def test_optimal_compass_gait_monodromy():
    """The level-ground least-effort compass optimum (0.3 m in 0.8 s; open-loop multiplier
    −1.34).  With its profile read on the clock (the feedforward its multipliers are of), the
    transverse monodromy has the AD multipliers through the Radau collocation: measured 2e-7
    apart, the collocation's own derivative accuracy at its discretisation error 1e-10 (its
    finite-difference check agrees to 1e-6), so the tolerance is 1e-6.  Read on the phase,
    ``u*(τ)`` (the transverse law's feedforward, a different map: −1.196), it agrees with
    central differences (h = 1e-5) of the simulated map under that law with zero gain, to
    their 1e-4."""
    from gaitopt.transverse.design import measured_closed_loop
    from gaitopt.transverse.law import TransverseLaw

    gait = gaitopt.optimize_gait(
        gaitopt.model("compass_gait", slope=0.0), "effort", period=0.8, step_length=0.3
    )
    assert gait.success
    lin = transverse_linearisation(gait)
    gap, rest = _match(gait.multipliers, lin.clock_multipliers)
    assert gap < 1e-6 and len(rest) == 1 and abs(rest[0]) < 1e-9
    law = TransverseLaw.build(lin, None, np.array([-np.inf]), np.array([np.inf]))
    measured = np.linalg.eigvals(measured_closed_loop(gait, law))
    gap, _ = _match(measured, lin.multipliers)
    assert gap < 1e-4
    assert abs(lin.multipliers[0]) > 1  # unstable either way


def test_saturation_is_applied_and_counted(passive_lqr):
    """With bounds of ±0.05 N·m the law clips its input and says so: the demanded peak exceeds
    the bound, the applied one does not (to the bit), and the clipped calls are counted."""
    from gaitopt.transverse.design import trial
    from gaitopt.transverse.law import TransverseLaw

    res = passive_lqr
    law = TransverseLaw.build(res.linearisation, res.riccati, np.array([-0.05]), np.array([0.05]))
    gait = res.gait
    s_star = gait.model.section_coordinates_of(gait.x)
    tr = trial(gait, law, s_star + np.array([0.0, 0.02, 0.0]), 2)
    assert tr.status == "completed"
    assert tr.saturated > 0 and tr.calls > tr.saturated
    assert tr.peak_demanded[0] > 0.05 and tr.peak_applied[0] <= 0.05


@pytest.mark.slow
def test_transverse_lqr_on_the_kneed_walker(cycles):
    """The kneed walker's state changes dimension at the knee strike (5 transverse states, then
    3); its light shank makes the swing's Hamiltonian stiff (spectral radius ~1700 /s), which the
    Riccati solution's sub-intervals keep well conditioned.  Hip and knee torques, Q = I, R = I:
    the closed-loop monodromy against central differences of the simulated closed loop (1e-4),
    and a perturbed walker returns."""
    from gaitopt.transverse import transverse_lqr

    res = transverse_lqr(cycles["kneed_walker"], Q=1, R=1, orbits=12, starts=[[0.01, 0, 0]])
    assert res.success, res.message
    assert res.multiplier_gap < 1e-4
    # two of the five closed-loop eigenvalues are the 0s of the knee strike's rank drop
    assert sum(abs(z) < 1e-9 for z in res.closed_loop_multipliers) == 2
    assert np.max(np.abs(res.closed_loop_multipliers)) < np.max(np.abs(res.open_loop_multipliers))
