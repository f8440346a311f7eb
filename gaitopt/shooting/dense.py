"""The shooting orbit as the certificate reads it: its RK integrator's dense samples as
:class:`~gaitopt.orbit.certificate.DenseArc` s (:func:`dense_arcs`), and the section's
consistency (:func:`check_section`)."""

from __future__ import annotations

import numpy as np

from ..hybrid import HybridModel
from ..orbit.certificate import DenseArc, constant_input
from ..result import OrbitArc
from .problem import ShootingProblem

__all__ = ["check_section", "dense_arcs"]


def _phase_label(model: HybridModel, problem: ShootingProblem, k: int) -> str:
    name = model.phases[problem.chain[k]].name
    step = f" (step {k // len(model.phases) + 1})" if problem.cycles > 1 else ""
    return f"phase '{name}'{step}"


def dense_arcs(
    model: HybridModel,
    problem: ShootingProblem,
    orbit: list[OrbitArc],
    u: np.ndarray,
    durations: np.ndarray | None = None,
    ends: list[np.ndarray] | None = None,
) -> list[DenseArc]:
    """The shooting orbit's dense samples (the RK integrator's, :meth:`ShootingProblem.orbit`)
    as the certificate reads them: the per-step input held at every sample; ``durations`` the
    shooting's (default: each arc's time span), ``ends`` its solved phase-end states (default:
    the last samples, which a finer sampling integration puts off the solved ends by the
    discretisation error)."""
    out = []
    for k, arc in enumerate(orbit):
        K = arc.x.shape[1]
        duration = float(arc.t[-1] - arc.t[0]) if durations is None else float(durations[k])
        out.append(
            DenseArc(
                arc.phase, _phase_label(model, problem, k), duration, np.asarray(arc.t),
                np.asarray(arc.x, dtype=float), constant_input(u, K),
                None if ends is None else np.asarray(ends[k], dtype=float),
            )
        )  # fmt: skip
    return out


def check_section(x_return, x_star) -> str | None:
    """The return state lies where the section's lift puts it (the model's own consistency)."""
    error = float(np.max(np.abs(np.asarray(x_return).ravel() - x_star)))
    if error > 1e-8 * (1 + np.max(np.abs(x_star))):
        return (
            f"internal inconsistency: the return state leaves the section parametrisation by "
            f"{error:.3g}; the model's section lift does not match its reset"
        )
    return None
