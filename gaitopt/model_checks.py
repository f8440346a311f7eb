"""The checks of a model class's hybrid structure, made once when it is built
(:meth:`gaitopt.hybrid.HybridModel.structure`): :func:`validate_structure` (the cycle, the
dimensions, the section lift) and :func:`check_declared` (the declared structure is the built
one)."""

from __future__ import annotations

import numpy as np

from .errors import ModelDefinitionError
from .phases import Phase, Section

__all__ = ["check_declared", "validate_structure"]


def check_declared(cls: type, phases: tuple[Phase, ...], section: Section) -> None:
    """The structure a class declares (:meth:`HybridModel.declared_structure`) is the one its
    ``build`` made: phase 0's states, the section's coordinates and definition."""
    declared = cls.declared_structure()
    built = (tuple(phases[0].states), tuple(section.coordinates), section.doc)
    if declared is None or tuple(declared) == built:
        return
    what = ("declared_states", "declared_coordinates", "declared_section_doc")
    wrong = [
        f"{name} = {d!r} (built: {b!r})"
        for name, d, b in zip(what, declared, built, strict=True)
        if d != b
    ]
    raise ModelDefinitionError(
        f"model class {cls.__name__}: its declaration differs from its build: {'; '.join(wrong)}"
    )


def validate_structure(cls: type, phases: tuple[Phase, ...], section: Section) -> None:
    """Check a model class's hybrid structure once, when it is built: the cycle's transitions
    enter the next phase in order (the shooting follows the cycle order, the simulation follows
    ``target``: they must agree), resets and guards have the right dimensions, and the section
    lift has phase 0's dimension and leaves its own coordinates unchanged (checked at the
    default parameters and a few section points)."""

    def fail(what: str) -> None:
        raise ModelDefinitionError(f"model class {cls.__name__}: {what}")

    if not phases:
        fail("`build` returned no phases")
    for i, phase in enumerate(phases):
        if not phase.transitions:
            fail(f"phase {phase.name!r} has no transition")
        for j, transition in enumerate(phase.transitions):
            where = f"transition {transition.name!r} of phase {phase.name!r}"
            if transition.direction not in (-1, 1):
                fail(f"{where}: direction must be +1 or -1, got {transition.direction!r}")
            if transition.guard.numel_out(0) != 1:
                fail(f"{where}: the guard must be scalar")
            if transition.reset is None:  # ends the motion (a fall; the ballistic swing's end)
                continue
            if j == 0 and transition.target != (i + 1) % len(phases):
                fail(
                    f"{where} closes the phase in the cycle, so its target must be the next phase "
                    f"({(i + 1) % len(phases)}), got {transition.target!r}"
                )
            if transition.target is None or not 0 <= transition.target < len(phases):
                fail(f"{where}: target {transition.target!r} is not a phase index")
            n_target = phases[transition.target].n
            if transition.reset.numel_out(0) != n_target:
                fail(
                    f"{where}: the reset gives {transition.reset.numel_out(0)} states, the "
                    f"target phase {phases[transition.target].name!r} has {n_target}"
                )
    first = phases[0]
    missing = [c for c in section.coordinates if c not in first.states]
    if missing:
        fail(f"section coordinate(s) {missing} are not states of phase {first.name!r}")
    if section.lift.numel_in(0) != len(section.coordinates) or section.lift.numel_out(0) != first.n:
        fail(
            f"the section lift must map {len(section.coordinates)} coordinate(s) to the "
            f"{first.n} states of phase {first.name!r}"
        )
    p = np.array([spec.default for spec in cls.parameter_specs()], dtype=float)
    index = [first.states.index(c) for c in section.coordinates]
    for scale in (0.01, 0.1):
        s = scale * np.arange(1, len(index) + 1, dtype=float)
        x = np.asarray(section.lift(s, p), dtype=float).ravel()
        if np.all(np.isfinite(x)) and np.max(np.abs(x[index] - s), initial=0.0) > 1e-12:
            fail(
                f"the section lift moves its own coordinates (lift(s)[{section.coordinates}] = "
                f"{x[index]} at s = {s}): it must return them unchanged"
            )
