"""Orbital stabilisation of gaits by transverse LQR (Manchester, Tobenkin, Levashov & Tedrake
2011; Drake's ``transverseLQR.m``).

* :mod:`~gaitopt.transverse.orbit` — the nominal orbit re-integrated and extended past its
  impacts;
* :mod:`~gaitopt.transverse.linearise` — transverse coordinates on hyperplanes orthogonal to the
  orbit's velocity, the linear time-varying transverse dynamics and the jumps at impacts, the
  monodromy;
"""

from .linearise import TransverseLinearisation, transverse_linearisation
from .orbit import NominalOrbit, nominal_orbit

__all__ = [
    "TransverseLinearisation",
    "transverse_linearisation",
    "NominalOrbit",
    "nominal_orbit",
]
