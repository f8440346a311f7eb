"""Orbital stabilisation of gaits by transverse LQR (Manchester, Tobenkin, Levashov & Tedrake
2011; Drake's ``transverseLQR.m``).

* :mod:`~gaitopt.transverse.orbit` — the nominal orbit re-integrated and extended past its
  impacts;
* :mod:`~gaitopt.transverse.linearise` — transverse coordinates on hyperplanes orthogonal to the
  orbit's velocity, the linear time-varying transverse dynamics and the jumps at impacts, the
  monodromy;
* :mod:`~gaitopt.transverse.riccati` — the periodic Riccati differential equation with its jumps;
* :mod:`~gaitopt.transverse.law` — the law ``u*(τ) − K(τ) x⊥`` for :func:`gaitopt.simulate`;
* :mod:`~gaitopt.transverse.design` — :func:`transverse_lqr`: the design and its checks;
* :mod:`~gaitopt.transverse.result` — :class:`TransverseLQR` and its JSON.
"""

from .design import transverse_lqr
from .linearise import TransverseLinearisation, transverse_linearisation
from .orbit import NominalOrbit, nominal_orbit
from .result import TransverseLQR, TransverseTrial

__all__ = [
    "transverse_lqr",
    "TransverseLQR",
    "TransverseTrial",
    "TransverseLinearisation",
    "transverse_linearisation",
    "NominalOrbit",
    "nominal_orbit",
]
