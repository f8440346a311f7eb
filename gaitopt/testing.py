"""The model contract as checks a model from any package can run: ``check_model(cls)``.

gaitopt's own test suite runs these checks over every registered model (as SciPy's ``test_ivp``
runs every solver); a model defined in another package gets the same suite in one line of its own
tests::

    from gaitopt.testing import check_model

    def test_my_model_keeps_the_contract():
        check_model(MyModel)

Each check raises :class:`AssertionError` with a message naming the model and what failed, and
needs nothing but NumPy and gaitopt (no pytest).  The checks, with their sources and tolerances:

1. :func:`check_structure`: transitions in cycle order, reset dimensions, declared units,
   sources and unilateral constraints (what the shooting and the simulation both rely on).
2. :func:`check_bad_input`: an unknown parameter (asked for by the registered name), an
   out-of-range, NaN or non-numeric value and an unknown state are each refused with one
   :class:`~gaitopt.errors.GaitoptInputError`.
3. :func:`check_conserved`: each declared conserved quantity is constant along the passive
   flow of the gait (simulated at rtol 1e-11 over two orbits; 1e-8 relative).
4. :func:`check_impact_momentum`: every impact at a declared foothold conserves the angular
   momentum of the whole system about that foothold (Goswami, Thuilot & Espiau 1996, eq. 8;
   1e-10 relative): for models whose phases declare ``bodies`` on both sides.
5. :func:`check_resets`: after each reset no guard of the next phase fires at once, and the
   state that closes the cycle lies on the section (``lift(project(x)) = x``, 1e-10).
6. :func:`check_multipliers`: the return map's Jacobian by AD through the shooting equations
   agrees with central differences of the independent simulated map (h = 1e-5 relative;
   2e-6 (1 + max |J|), the budget of h² P''' plus rounding 1e-11 / h).

Checks 3–6 need the model's passive gait: :func:`check_model` finds it with
:func:`gaitopt.find_limit_cycle` where the class declares one (``passive_gait``).
"""

from __future__ import annotations

from typing import Any

import casadi as ca
import numpy as np

from .errors import GaitoptInputError, ParameterError, StateError
from .hybrid import HybridModel
from .models import REGISTRY
from .models import model as make_model
from .returnmap import return_map
from .shooting import find_limit_cycle
from .simulation import simulate

__all__ = [
    "check_model",
    "check_structure",
    "check_bad_input",
    "check_conserved",
    "check_impact_momentum",
    "check_resets",
    "check_multipliers",
    "angular_momentum",
]


def _require(condition: bool, what: str) -> None:
    if not condition:
        raise AssertionError(what)


def check_structure(cls: type[HybridModel]) -> None:
    """Check 1: the hybrid structure is consistent and every declaration is complete.

    Parameters
    ----------
    cls : type
        A :class:`~gaitopt.hybrid.HybridModel` subclass (registered or not).
    """
    model = cls()
    name = cls.name
    phases = model.phases
    p, u = model.p, model.nominal_input()
    _require(len(u) == len(model.inputs), f"{name}: nominal_input() must give one value per input")
    for i, phase in enumerate(phases):
        cycle_tr = phase.transitions[0]
        _require(cycle_tr.direction in (-1, 1), f"{name}: '{cycle_tr.name}' direction is ±1")
        if cycle_tr.reset is None:
            # A single swing that ends at its transition (the ballistic walker: a boundary-value
            # problem, no cycle) is allowed only for a model that declares no passive gait.
            _require(
                not cls.passive_gait,
                f"{name}: phase '{phase.name}': transitions[0] must continue the gait cycle",
            )
        else:
            _require(
                cycle_tr.target == (i + 1) % len(phases),
                f"{name}: phase '{phase.name}': transitions[0] must target the next phase",
            )
        for tr in phase.transitions:
            if tr.reset is not None:
                x = ca.DM.zeros(phase.n)
                _require(
                    tr.reset(x, u, p).numel() == phases[tr.target].n,
                    f"{name}: '{tr.name}' must give the next phase's {phases[tr.target].n} states",
                )
        _require(
            phase.flow.size1_in(0) == phase.n and phase.flow.numel_out(0) == phase.n,
            f"{name}: phase '{phase.name}': the flow must map its {phase.n} states to as many",
        )
        for c in phase.constraints:
            _require(
                c.function.numel_out(0) == 1 and bool(c.outcome) and bool(c.source),
                f"{name}: constraint '{c.name}' needs a scalar function, an outcome and a source",
            )
    _require(
        set(model.section.coordinates) <= set(model.state_names),
        f"{name}: the section's coordinates must be states of phase 0",
    )
    _require(
        model.section.lift.numel_out(0) == phases[0].n,
        f"{name}: the section lift must give phase 0's {phases[0].n} states",
    )
    for spec in model.parameter_specs():
        _require(
            spec.unit is not None and bool(spec.source),
            f"{name}.{spec.name}: every parameter needs a unit and a source",
        )


def _refused(call: Any, kind: type[Exception], match: str, what: str) -> None:
    try:
        call()
    except kind as error:
        _require(match in str(error), f"{what}: the error must name {match!r}, got {error}")
        return
    raise AssertionError(f"{what}: expected {kind.__name__}, nothing was raised")


def check_bad_input(cls: type[HybridModel]) -> None:
    """Check 2: bad parameters and states are refused with one clear error naming them."""
    name = cls.name
    spec = cls.parameter_specs()[0]
    if REGISTRY.get(name) is cls:  # by name, as users and the CLI make models
        _refused(
            lambda: make_model(name, nonsense=1.0),
            ParameterError,
            "nonsense",
            f"{name}: unknown parameter",
        )
    if np.isfinite(spec.high):
        _refused(
            lambda: cls(**{spec.name: spec.high + 1 + abs(spec.high)}),
            ParameterError,
            spec.name,
            f"{name}: {spec.name} above its range",
        )
    _refused(
        lambda: cls(**{spec.name: float("nan")}), ParameterError, spec.name, f"{name}: NaN value"
    )
    model = cls()
    _refused(
        lambda: model.section_vector({"no_such_state": 1.0}),
        StateError,
        "no_such_state",
        f"{name}: unknown state",
    )
    _refused(
        lambda: model.replace(**{spec.name: "abc"}),
        GaitoptInputError,
        spec.name,
        f"{name}: a non-numeric value",
    )


def check_conserved(gait: Any) -> None:
    """Check 3: each declared conserved quantity is constant along the gait's passive flow."""
    model = gait.model
    sim = simulate(model, gait.x, steps=2 * gait.steps, inputs=gait.inputs)
    _require(sim.success, f"{model.name}: the gait's simulation failed: {sim.message}")
    for arc in sim.arcs:
        phase = model.phases[arc.phase]
        _, X = arc.sample(200)
        for qname, c in phase.conserved.items():
            values = np.array([float(c(X[:, j], model.p)) for j in range(X.shape[1])])
            _require(
                np.ptp(values) < 1e-8 * (1 + np.max(np.abs(values))),
                f"{model.name}: '{qname}' varies by {np.ptp(values):.3g} along '{phase.name}'",
            )


def angular_momentum(bodies: Any, x: np.ndarray, p: np.ndarray, point: Any) -> float:
    """Σ mᵢ (rᵢ − point) × vᵢ (kg·m²/s, about ``point``) of a phase's declared point masses."""
    m, r, v = (np.atleast_2d(np.asarray(a, dtype=float)) for a in bodies(x, p))
    r = r.reshape(2, -1) - np.asarray(point, dtype=float).reshape(2, 1)
    v = v.reshape(2, -1)
    return float(np.sum(m.ravel() * (r[0] * v[1] - r[1] * v[0])))


def check_impact_momentum(gait: Any) -> int:
    """Check 4: impacts at a declared foothold conserve the angular momentum about it.

    Returns
    -------
    int
        How many impacts were checked (0: the model declares no impact at a foothold with
        ``bodies`` on both sides, or its contact is not the frame's origin, as with rolling feet).
    """
    model = gait.model
    sim = simulate(model, gait.x, steps=gait.steps, inputs=gait.inputs)
    checked = 0
    for event in sim.events:
        phase = model.phases[event.phase]
        tr = next(t for t in phase.transitions if t.name == event.transition)
        target = model.phases[tr.target] if tr.target is not None else None
        if not (tr.impact and tr.foothold and phase.bodies is not None and target is not None):
            continue
        if target.bodies is None or "foot_radius" in model.params and model.foot_radius > 0:
            continue  # rolling feet: the contact is not the frame's origin
        points = np.asarray(phase.points(event.state_before, model.p))
        foothold = points[:, phase.point_names.index(tr.foothold)]
        before = angular_momentum(phase.bodies, event.state_before, model.p, foothold)
        after = angular_momentum(target.bodies, event.state_after, model.p, [0.0, 0.0])
        _require(
            abs(after - before) <= 1e-10 * abs(before) + 1e-12,
            f"{model.name}: '{tr.name}' changes the angular momentum about the foothold "
            f"from {before!r} to {after!r} kg·m²/s",
        )
        checked += 1
    return checked


def check_resets(gait: Any) -> None:
    """Check 5: resets land on the safe side of the next guards, and on the section."""
    model = gait.model
    sim = simulate(model, gait.x, steps=gait.steps, inputs=gait.inputs)
    u, p = gait.inputs, model.p
    for event in sim.events:
        phase = model.phases[event.phase]
        tr = next(t for t in phase.transitions if t.name == event.transition)
        nxt = model.phases[tr.target]
        for guard_tr in nxt.transitions:
            g = guard_tr.direction * float(guard_tr.guard(event.state_after, u, p))
            excluded = (
                guard_tr.admissible is not None
                and float(guard_tr.admissible(event.state_after, u, p)) <= 0
            )
            _require(
                g <= 1e-9 or excluded,
                f"{model.name}: after '{tr.name}', '{guard_tr.name}' fires at once",
            )
    for x in sim.section_states:
        lifted = model.lift(model.section_coordinates_of(x))
        _require(
            np.max(np.abs(lifted - x)) <= 1e-10 * (1 + np.max(np.abs(x))),
            f"{model.name}: the state closing a step is not on the section",
        )


def check_multipliers(gait: Any) -> None:
    """Check 6: AD multipliers agree with finite differences of the simulated return map."""
    model, s = gait.model, gait.section_point
    J = np.zeros((s.size, s.size))
    for j in range(s.size):
        e = np.zeros(s.size)
        e[j] = 1e-5 * (1 + abs(s[j]))
        forward = return_map(model, s + e, steps=gait.steps, inputs=gait.inputs)
        backward = return_map(model, s - e, steps=gait.steps, inputs=gait.inputs)
        J[:, j] = (forward - backward) / (2 * e[j])
    tol = 2e-6 * (1 + np.max(np.abs(J)))
    gap = float(np.max(np.abs(np.asarray(gait.jacobian) - J)))
    _require(gap <= tol, f"{model.name}: AD and finite-difference Jacobians differ by {gap:.3g}")
    fd = np.sort(np.abs(np.linalg.eigvals(J)))
    ad = np.sort(np.abs(np.asarray(gait.multipliers)))
    _require(
        float(np.max(np.abs(fd - ad))) <= tol,
        f"{model.name}: multiplier moduli {ad} by AD, {fd} by finite differences",
    )


def check_model(cls: type[HybridModel], gait: Any = None) -> dict[str, Any]:
    """Run the whole model contract (checks 1–6 of :mod:`gaitopt.testing`) on ``cls``.

    Parameters
    ----------
    cls : type
        The model class.
    gait : LimitCycle, optional
        Its passive gait at the defaults, if the caller has it; else found with
        :func:`gaitopt.find_limit_cycle` (only where ``cls.passive_gait``).

    Returns
    -------
    dict
        ``{"gait": the gait or None, "impacts_checked": int}``.

    Raises
    ------
    AssertionError
        Naming the model and the check that failed.
    """
    check_structure(cls)
    check_bad_input(cls)
    if not cls.passive_gait:
        return {"gait": None, "impacts_checked": 0}
    if gait is None:
        gait = find_limit_cycle(cls())
    _require(gait.success, f"{cls.name}: no passive gait at the defaults: {gait.message}")
    check_conserved(gait)
    checked = check_impact_momentum(gait)
    check_resets(gait)
    check_multipliers(gait)
    return {"gait": gait, "impacts_checked": checked}
