"""A last arc collapsed against a phase change inside a step, continued into the next phase
(gaitopt/optimize/collapsed.py), on a structure like the level kneed walker's."""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np

from gaitopt.optimize.collapsed import move_collapsed_arcs
from gaitopt.optimize.radau import COAST, NEGATIVE, POSITIVE, Arc


def _col(structure, thetas, continuous=True):
    """A stand-in for a solved transcription: two phases per step (three-link, two-link), the
    knee (input 1) and the push-off (input 2) idle in the second."""
    return SimpleNamespace(
        structure=structure,
        problem=SimpleNamespace(continuous_inputs=continuous),
        model=SimpleNamespace(phases=(0, 1)),
        chain=(0, 1),
        theta_of=lambda w, k: np.asarray(thetas[k]),
        _idle_inputs=lambda i: [2] if i == 0 else [1, 2],
    )


BANG = Arc(4, (POSITIVE, COAST, NEGATIVE), 0.03, (-1, 0, 0))
SLIVER = Arc(2, (COAST, COAST, NEGATIVE), 1e-3)
COASTING = Arc(4, (COAST, COAST, NEGATIVE), 0.96)
PHASE_1 = [Arc(10, (COAST, NEGATIVE, NEGATIVE), 1.0)]


def test_the_bang_continues_into_the_next_phase():
    # The level kneed walker at 0.8 m/s: the hip at its bound up to a coasting sliver of 1e-6
    # of the three-link phase, coasting after the knee strike.  The sliver goes (its intervals
    # to the bang), the bang becomes the two-link phase's first arc (the knee idle there keeps
    # the phase's own kind), and every phase has as many intervals as before the change.
    col = _col([[COASTING, BANG, SLIVER], PHASE_1], [[0.96, 0.04, 1e-6], [1.0]])
    moved = move_collapsed_arcs(col, None)
    assert moved is not None
    first, second = moved
    assert [a.signs for a in first] == [COASTING.signs, BANG.signs]
    assert first[-1].intervals == BANG.intervals + SLIVER.intervals
    assert second[0].signs == (POSITIVE, NEGATIVE, NEGATIVE)
    assert second[0].bounds == (-1, 0, 0)
    assert second[1].signs == PHASE_1[0].signs
    counts = [sum(a.intervals for a in phase) for phase in moved]
    assert counts[0] == counts[1] == 10 + 2  # the two-link phase gained the continued arc


def test_nothing_to_move():
    # A last arc of a fair share, a step's last phase (inputs may jump at the section), or
    # inputs allowed to jump between phases: the structure stands.
    assert move_collapsed_arcs(_col([[COASTING, BANG], PHASE_1], [[0.9, 0.1], [1.0]]), None) is None
    assert (
        move_collapsed_arcs(
            _col(
                [[COASTING, BANG, SLIVER], PHASE_1], [[0.96, 0.04, 1e-6], [1.0]], continuous=False
            ),
            None,
        )
        is None
    )
    single = _col([[COASTING, BANG, SLIVER]], [[0.96, 0.04, 1e-6]])
    single.chain, single.model = (0,), SimpleNamespace(phases=(0,))
    assert move_collapsed_arcs(single, None) is None
