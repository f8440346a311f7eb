"""The independent check of a gait: simulate from its fixed point with the event-located
DOP853 simulator (:func:`gaitopt.simulate`, a different method and step control from the shooting
integrator) and require the return, through the same phases at consistent times."""

from __future__ import annotations

import numpy as np

from ..simulation import simulate

__all__ = ["verify_by_simulation"]


# vaults) the adaptive simulation's event times drift by far more than its states, while the
# shooting durations carry the discretisation-error estimate.  Relative to the period:
_TIMING_TOL = 1e-6


# The verifying simulation's tolerances, (rtol, atol): first the loose pair, whose error at the
# return (1e-13 to 1.4e-10 over the registered models' gaits, measured against the shooting's
# fixed points) stays three orders of magnitude below the 1e-7 it is checked against (``tol *
# 1e3``) in 30-40 % fewer steps; where that check fails, the tight pair decides (near an
# existence boundary, where a rimless wheel barely vaults, the event times need it).
_VERIFY_LOOSE = (1e-10, 1e-12)
_VERIFY_TIGHT = (1e-12, 1e-13)


def verify_by_simulation(model, x_star, durations, steps, u, tol) -> tuple[bool, float, str]:
    """Simulate from the fixed point with SciPy: the return must be within ``tol`` (relative
    to the state's size) of the fixed point, through the same phases at consistent times
    (at the loose tolerances, then, if that fails, at the tight ones)."""
    verdict = _verify_at(model, x_star, durations, steps, u, tol, *_VERIFY_LOOSE)
    if verdict[0]:
        return verdict
    return _verify_at(model, x_star, durations, steps, u, tol, *_VERIFY_TIGHT)


def _verify_at(model, x_star, durations, steps, u, tol, rtol, atol) -> tuple[bool, float, str]:
    sim = simulate(
        model,
        x_star,
        steps=steps,
        inputs=u,
        max_phase_time=float(model.max_phase_time),
        rtol=rtol,
        atol=atol,
    )
    if not sim.success:
        return False, float("inf"), f"the simulation from the fixed point fails: {sim.message}"
    expected = len(durations)
    if len(sim.arcs) != expected:
        return (
            False,
            float("inf"),
            (f"the simulation passes {len(sim.arcs)} phases where the orbit has {expected}"),
        )
    error = float(np.max(np.abs(sim.section_states[-1] - x_star)))
    sim_durations = np.array([a.t1 - a.t0 for a in sim.arcs])
    timing = float(np.max(np.abs(sim_durations - durations)))
    scale = 1 + float(np.max(np.abs(x_star)))
    if error > tol * scale or timing > _TIMING_TOL * (1 + float(np.sum(durations))):
        return (
            False,
            error,
            (
                f"the simulation from the fixed point returns {error:.3g} away (tolerance "
                f"{tol:g}); phase timing differs by {timing:.3g} s"
            ),
        )
    return (
        True,
        error,
        (f"verified by simulation: return error {error:.2g}, timing error {timing:.2g} s"),
    )
