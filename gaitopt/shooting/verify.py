"""The independent check of a shooting gait: the common referee (:func:`gaitopt.orbit.referee`:
simulate from the fixed point with the event-located DOP853 simulator, a different method and
step control from the shooting integrator, and require the return through the same phases at
consistent times), with the gait's constant per-step input."""

from __future__ import annotations

import numpy as np

from ..orbit.referee import LADDER, referee

__all__ = ["verify_by_simulation"]


def verify_by_simulation(model, x_star, durations, steps, u, tol) -> tuple[bool, float, str]:
    """Simulate from the fixed point with SciPy (:func:`gaitopt.orbit.referee`): the return must
    be within ``tol`` (relative to the state's size) of the fixed point, through the same phases
    at consistent times (at the loose tolerances, then, if that fails, at the tight ones).

    Returns
    -------
    (bool, float, str)
        Verified, the return error (state units) and the verdict in words.
    """
    verdict = referee(
        model, np.asarray(x_star, dtype=float), durations, steps, tol=tol, inputs=u,
        max_phase_time=float(model.max_phase_time), tolerances=LADDER,
    )  # fmt: skip
    return verdict.ok, verdict.return_error, verdict.message
