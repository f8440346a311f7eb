"""The accumulation of impacts (Zeno): a motion that strikes ever faster ends as "standing"."""

from __future__ import annotations

import numpy as np

__all__ = ["accumulation"]


# -- accumulation of impacts (Zeno) ------------------------------------------------------------
# A rimless wheel that rocks to rest strikes spoke after spoke with intervals shrinking by a
# constant factor (cos 2α per impact pair, Tedrake's rocking branch): infinitely many impacts in
# finite time.  Integration cannot follow it to the end (the excursions fall below the guards'
# arming threshold and the wheel would sink through the ground), so the accumulation is detected
# and the motion ends as "standing".  The test is generic, on event times only: the last
# _ZENO_WINDOW intervals (between events, or between every second event for motions that
# alternate between two contacts) shrink by a factor r < 1 that is constant to within
# _ZENO_SPREAD·(1 − r) — a transient whose intervals converge to a positive period has ratios
# tending to 1, with (1 − r) shrinking geometrically, and is not taken for one.
_ZENO_WINDOW = 5
_ZENO_SPREAD = 0.1


def accumulation(times: list[float]) -> tuple[float, float] | None:
    """Geometric accumulation of event times: ``(ratio per event, accumulation time)`` or None.

    For lag 1 and lag 2, the intervals ``dₖ = tₖ₊L − tₖ`` (every L-th) of the last events must all
    shrink, with ratios ``rₖ = dₖ₊₁/dₖ`` within ``_ZENO_SPREAD·(1 − r̄)`` of their mean ``r̄ < 1``;
    the accumulation time is then ``t_last + d_last · r̄/(1 − r̄)`` (the geometric series)."""
    for lag in (1, 2):
        needed = lag * (_ZENO_WINDOW + 1) + 1
        if len(times) < needed:
            return None
        t = np.asarray(times[-needed:], dtype=float)[::-1][::lag][::-1]
        d = np.diff(t)
        if not np.all(d > 0):
            continue
        r = d[1:] / d[:-1]
        mean = float(np.mean(r))
        if mean < 1.0 and np.all(np.abs(r - mean) <= _ZENO_SPREAD * (1.0 - mean)):
            return mean ** (1.0 / lag), float(t[-1] + d[-1] * mean / (1.0 - mean))
    return None
