"""What makes an orbit a gait, whichever transcription found it: the certificate
(:mod:`~gaitopt.orbit.certificate`: the physical checks on dense samples, one tolerance rule) and
the referee (:mod:`~gaitopt.orbit.referee`: the independent simulation).  Both
:func:`gaitopt.find_limit_cycle` (multiple shooting) and :func:`gaitopt.optimize_gait` (Radau
collocation) use them; they sit below ``gaitopt.shooting`` and ``gaitopt.optimize`` and import
neither.

The orbit layer, folder by job:

* :mod:`~gaitopt.orbit.transcription` — the :class:`Transcription` protocol (rules 1–9) that
  multiple shooting (:class:`gaitopt.shooting.transcription.ShootingTranscription`) and Radau
  collocation (:class:`gaitopt.optimize.transcription.CollocationTranscription`) implement;
  :mod:`~gaitopt.orbit.layout` — its named blocks (:class:`Layout`);
* :mod:`~gaitopt.orbit.newton` (square Newton) and :mod:`~gaitopt.orbit.ipopt` (IPOPT with
  bounds and an objective) — solvers on any transcription;
* :mod:`~gaitopt.orbit.solve` — :func:`solve_gait`: solve → refine → certify → referee;
* :mod:`~gaitopt.orbit.certificate` and :mod:`~gaitopt.orbit.referee` — what makes an orbit a
  gait.
"""

from .certificate import CONSTRAINT_TOL, DenseArc, certify_orbit
from .layout import Block, Layout
from .referee import Verdict, referee
from .solve import OrbitSolution, solve_gait
from .transcription import Bounds, ReturnMap, Symbols, Transcription

__all__ = [
    "CONSTRAINT_TOL",
    "Block",
    "Bounds",
    "DenseArc",
    "Layout",
    "OrbitSolution",
    "ReturnMap",
    "Symbols",
    "Transcription",
    "Verdict",
    "certify_orbit",
    "referee",
    "solve_gait",
]
