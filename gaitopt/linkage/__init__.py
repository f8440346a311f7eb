"""Theo Jansen's leg linkage (the Strandbeest): loop closure, foot path, ride height.

Geometry (Jansen, *The Great Pretender*, 2007; the lettering of Wikipedia's "Jansen's linkage"
figure, with the joints named here by what they are).  The frame carries the crank axle ``O`` at
the origin and the fixed pivot ``B = (−a, −l)``; the crank ``m`` turns the crank pin
``P = m (cos θ, sin θ)``, θ the crank angle (rad, counter-clockwise).  Five joints close the loops,
each joined to two known points by two links (a *dyad*):

===========  =======================  ======================  =================================
joint        joined to (link)         and to (link)           side in the initial assembly
===========  =======================  ======================  =================================
``upper``    crank pin ``P`` (j)      fixed pivot ``B`` (b)   above the line P→B
``lower``    crank pin ``P`` (k)      fixed pivot ``B`` (c)   below the line P→B
``back``     fixed pivot ``B`` (d)    ``upper`` (e)           away from the crank (outer)
``knee``     ``back`` (f)             ``lower`` (g)           outer
``foot``     ``knee`` (h)             ``lower`` (i)           below
===========  =======================  ======================  =================================

so that ``B, upper, back`` (sides b, e, d) and ``lower, knee, foot`` (sides g, h, i) are the two
rigid triangles.  The holy numbers (a 38, b 41.5, c 39.3, d 40.1, e 55.8, f 39.4, g 36.7,
h 65.7, i 49, j 50, k 61.9, l 7.8, m 15) are used at Robin Deits' scale, 0.01 m per unit (Drake's
``examples/multibody/strandbeest``, PVC links 0.476 kg/m).

Method.  The ten loop-closure equations ``|X − Y|² = L²`` (one per link, unknowns the five joints)
are solved by Newton's method (CasADi ``rootfinder``) and *continued* in θ: each solve starts
from the previous one, predicted along the tangent ``dz/dθ = −(∂r/∂z)⁻¹ ∂r/∂θ`` (implicit
function theorem, by CasADi's algorithmic differentiation through the rootfinder), so the branch
is chosen by continuity from the stated initial assembly.  A turn that would have to pass a dead
point (a dyad stretched straight, ``∂r/∂z`` singular) or change the side of a joint is refused:
the linkage cannot be assembled through a whole crank turn.

The foot velocity per unit crank rate ``dr_foot/dθ`` (m/rad) comes from the same AD.  By virtual
work, ``τ δθ = F · δr_foot``: a force ``F`` on the foot needs the crank torque ``τ = F · dr/dθ``,
so ``dx/dθ`` and ``dy/dθ`` are the crank torques per unit horizontal and vertical foot force
(N·m/N = m) — the mechanical advantage, in its inverse form.

The machine: leg *pairs* on one crank; a pair is a leg and its mirror image about the vertical
through the crank axle, sharing the crank pin.  The mirror of a leg at crank angle θ is the leg
at π − θ reflected (its pin reflects to the pin at θ), so its foot height is ``y(π − θ)``.  With
the frame level and the ground flat, the crank axle rides at ``−min y`` over the ground (the
lowest foot carries the machine): the *ride height*; its peak-to-peak over a turn is the ripple.
Deits' and Drake's machine has six pairs at crank phases 0, 2π/3, 4π/3, π/3, π, 5π/3.

Modules: :mod:`~gaitopt.linkage.closure` (the loop-closure equations, Newton's method and the
closed-form joints), :mod:`~gaitopt.linkage.jansen` (:class:`JansenLinkage`: lengths, assembly,
a crank turn), :mod:`~gaitopt.linkage.turn` (:class:`Turn`: the foot path's numbers); here the
linkages by name (:data:`LINKAGES`, :func:`linkage`).
"""

from __future__ import annotations

from ..errors import ParameterError, did_you_mean
from .closure import DYADS, JOINTS, closed_form_joints
from .closure import loop_closure as loop_closure  # public, not in __all__ (as before)
from .jansen import JansenLinkage
from .turn import GROUND_BAND, SIX_PAIR_PHASES, Turn

__all__ = [
    "JansenLinkage",
    "Turn",
    "LINKAGES",
    "linkage",
    "JOINTS",
    "DYADS",
    "SIX_PAIR_PHASES",
    "GROUND_BAND",
    "closed_form_joints",
]

#: The linkages ``gaitopt linkage`` knows.
LINKAGES: dict[str, type[JansenLinkage]] = {"jansen": JansenLinkage}


def linkage(name: str, **lengths: float) -> JansenLinkage:
    """A linkage by name with some lengths changed (m).

    Raises
    ------
    ParameterError
        For an unknown linkage or length, or a length out of range.
    """
    if name not in LINKAGES:
        raise ParameterError(
            f"unknown linkage {name!r}; {did_you_mean(name, LINKAGES)}available: "
            f"{', '.join(LINKAGES)}"
        )
    cls = LINKAGES[name]
    known = [s.name for s in cls.parameter_specs()]
    for key in lengths:
        if key not in known:
            raise ParameterError(
                f"{name}: unknown parameter {key!r}; {did_you_mean(key, known)}"
                f"parameters: {', '.join(known)}"
            )
    return cls(**lengths)
