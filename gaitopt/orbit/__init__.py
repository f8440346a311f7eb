"""What makes an orbit a gait, whichever transcription found it: the certificate
(:mod:`~gaitopt.orbit.certificate`: the physical checks on dense samples, one tolerance rule) and
the referee (:mod:`~gaitopt.orbit.referee`: the independent simulation).  Both
:func:`gaitopt.find_limit_cycle` (multiple shooting) and :func:`gaitopt.optimize_gait` (Radau
collocation) use them; they sit below ``gaitopt.shooting`` and ``gaitopt.optimize`` and import
neither."""

from .certificate import CONSTRAINT_TOL, DenseArc, certify_orbit
from .referee import Verdict, referee

__all__ = ["CONSTRAINT_TOL", "DenseArc", "Verdict", "certify_orbit", "referee"]
