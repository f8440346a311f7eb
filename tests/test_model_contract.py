"""The model contract, tested over every registered model (as SciPy's ``test_ivp`` runs every
solver and diffrax's tests run ``all_ode_solvers``).

A model gets these tests by being registered: the structure is consistent; conserved quantities
are constant along its flows; impacts with a declared foothold conserve the angular momentum
about it; resets land on the section and on the safe side of the next phase's guards; the section
lift is a right inverse of the projection; the multipliers by AD agree with finite differences of
the simulated map; bad input is refused with one clear error.  The last test defines a small model
here, registers it with :func:`gaitopt.register`, and runs it through the same checks and the CLI.
"""

from __future__ import annotations

import json
from dataclasses import dataclass

import casadi as ca
import numpy as np
import pytest

import gaitopt
from gaitopt.errors import GaitoptInputError, ParameterError, StateError
from gaitopt.hybrid import HybridModel, Phase, Section, Symbols, Transition
from gaitopt.parameters import parameter
from gaitopt.returnmap import return_map

ALL = list(gaitopt.REGISTRY)
PASSIVE = [name for name, cls in gaitopt.REGISTRY.items() if cls.passive_gait]


def _gait(cycles, name):
    if name not in cycles:
        pytest.skip(f"{name} has no passive gait (actuated only)")
    cycle = cycles[name]
    assert cycle.success, cycle.message
    return cycle


# -- structure -----------------------------------------------------------------------------------


@pytest.mark.parametrize("name", ALL)
def test_structure_is_consistent(name):
    # Targets in cycle order, reset dimensions, declared units and inputs: what the shooting and
    # the simulation both rely on (the simulation follows `target`, the shooting the cycle order).
    model = gaitopt.model(name)
    phases = model.phases
    p, u = model.p, model.nominal_input()
    assert len(u) == len(model.inputs)
    for i, phase in enumerate(phases):
        cycle_tr = phase.transitions[0]
        assert cycle_tr.direction in (-1, 1)
        if cycle_tr.reset is None:
            # A single swing that ends at its transition (the ballistic walker: a boundary-value
            # problem, no cycle) is allowed only for a model that declares no passive gait.
            assert not type(model).passive_gait, "transitions[0] continues the gait cycle"
        else:
            assert cycle_tr.target == (i + 1) % len(phases), "targets follow the cycle order"
        for tr in phase.transitions:
            if tr.reset is not None:
                x = ca.DM.zeros(phase.n)
                assert tr.reset(x, u, p).numel() == phases[tr.target].n
        assert phase.flow.size1_in(0) == phase.n and phase.flow.numel_out(0) == phase.n
        for c in phase.constraints:
            assert c.function.numel_out(0) == 1 and c.outcome and c.source
    assert set(model.section.coordinates) <= set(model.state_names)
    assert model.section.lift.numel_out(0) == phases[0].n
    for spec in model.parameter_specs():
        assert spec.unit is not None and spec.source, f"{name}.{spec.name} needs unit and source"


# -- invariants along the gait -------------------------------------------------------------------


@pytest.mark.parametrize("name", PASSIVE)
def test_conserved_quantities_are_constant_along_the_flow(name, cycles):
    # Invariant: each declared conserved quantity is constant along its phase's passive flow
    # (u = 0 inside phases for every passive model).  Simulated at rtol 1e-11 over two orbits;
    # tolerance 1e-8 relative to the quantity's size.
    cycle = _gait(cycles, name)
    model = cycle.model
    sim = gaitopt.simulate(model, cycle.x, steps=2 * cycle.steps, inputs=cycle.inputs)
    assert sim.success, sim.message
    for arc in sim.arcs:
        phase = model.phases[arc.phase]
        _, X = arc.sample(200)
        for qname, c in phase.conserved.items():
            values = np.array([float(c(X[:, j], model.p)) for j in range(X.shape[1])])
            assert np.ptp(values) < 1e-8 * (1 + np.max(np.abs(values))), (name, qname)


def _angular_momentum(bodies, x, p, point) -> float:
    m, r, v = (np.atleast_2d(np.asarray(a, dtype=float)) for a in bodies(x, p))
    r = r.reshape(2, -1) - np.asarray(point, dtype=float).reshape(2, 1)
    v = v.reshape(2, -1)
    return float(np.sum(m.ravel() * (r[0] * v[1] - r[1] * v[0])))


@pytest.mark.parametrize("name", PASSIVE)
def test_impacts_conserve_angular_momentum_about_the_new_foothold(name, cycles):
    # Invariant: a plastic impact at a point conserves the angular momentum of the whole system
    # about that point (Goswami et al. 1996, eq. 8).  For every impact with a declared foothold
    # and bodies on both sides: L about the foothold before equals L about the new contact (the
    # new phase's origin) after.  Tolerance 1e-10 relative.
    cycle = _gait(cycles, name)
    model = cycle.model
    sim = gaitopt.simulate(model, cycle.x, steps=cycle.steps, inputs=cycle.inputs)
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
        before = _angular_momentum(phase.bodies, event.state_before, model.p, foothold)
        after = _angular_momentum(target.bodies, event.state_after, model.p, [0.0, 0.0])
        assert after == pytest.approx(before, rel=1e-10, abs=1e-12)
        checked += 1
    if not checked:
        pytest.skip(f"{name} declares no impact with a foothold and bodies")


@pytest.mark.parametrize("name", PASSIVE)
def test_resets_land_on_the_section_and_the_safe_side_of_guards(name, cycles):
    # After each reset the next phase's guards are on their pre-crossing side or admissibly
    # excluded (none fires at once), and the state that closes the cycle lies on the section:
    # lift(project(x)) = x, 1e-10.
    cycle = _gait(cycles, name)
    model = cycle.model
    sim = gaitopt.simulate(model, cycle.x, steps=cycle.steps, inputs=cycle.inputs)
    u, p = cycle.inputs, model.p
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
            assert g <= 1e-9 or excluded, (name, tr.name, guard_tr.name)
    for x in sim.section_states:
        lifted = model.lift(model.section_coordinates_of(x))
        np.testing.assert_allclose(lifted, x, atol=1e-10 * (1 + np.max(np.abs(x))))


@pytest.mark.parametrize("name", PASSIVE)
def test_multipliers_agree_with_finite_differences_of_the_simulated_map(name, cycles):
    # Two independent methods: AD through the shooting equations (implicit function theorem)
    # vs central differences of the event-located SciPy map (rtol 1e-11, h = 1e-5 relative).
    # Error budget: h² P''' ~ 1e-10 plus rounding 1e-11 / h ~ 1e-6, relative to the map's scale
    # 1 + max |J|; tolerance 2e-6 (1 + max |J|) on the Jacobian's entries and on the moduli of
    # its eigenvalues (the multipliers).  The largest error seen is 7.9e-7 (1 + max |J|), the
    # simplest walker's.  One test for every model: the model test files do not repeat it.
    cycle = _gait(cycles, name)
    model, s = cycle.model, cycle.section_point
    J = np.zeros((s.size, s.size))
    for j in range(s.size):
        e = np.zeros(s.size)
        e[j] = 1e-5 * (1 + abs(s[j]))
        forward = return_map(model, s + e, steps=cycle.steps, inputs=cycle.inputs)
        backward = return_map(model, s - e, steps=cycle.steps, inputs=cycle.inputs)
        J[:, j] = (forward - backward) / (2 * e[j])
    tol = 2e-6 * (1 + np.max(np.abs(J)))
    np.testing.assert_allclose(cycle.jacobian, J, atol=tol)
    fd_moduli = np.sort(np.abs(np.linalg.eigvals(J)))
    assert fd_moduli == pytest.approx(np.sort(np.abs(cycle.multipliers)), abs=tol)


# -- bad input -----------------------------------------------------------------------------------


@pytest.mark.parametrize("name", ALL)
def test_bad_parameters_and_states_are_refused_clearly(name):
    # One GaitoptInputError (a ValueError) naming the argument: an unknown parameter, a value
    # outside the declared range, a non-number, an unknown state.
    cls = gaitopt.REGISTRY[name]
    spec = cls.parameter_specs()[0]
    with pytest.raises(ParameterError, match="nonsense"):
        gaitopt.model(name, nonsense=1.0)
    if np.isfinite(spec.high):
        with pytest.raises(ParameterError, match=spec.name):
            gaitopt.model(name, **{spec.name: spec.high + 1 + abs(spec.high)})
    with pytest.raises(ParameterError, match=spec.name):
        gaitopt.model(name, **{spec.name: float("nan")})
    model = gaitopt.model(name)
    with pytest.raises(StateError):
        model.section_vector({"no_such_state": 1.0})
    with pytest.raises(GaitoptInputError):
        model.replace(**{spec.name: "abc"})


# -- a model defined here gets all of the above by registering -----------------------------------


@dataclass(frozen=True)
class KickedBall(HybridModel):
    """A ball dropped on a table: restitution e and a kick Δv at each bounce,
    ``v⁺ = e (−v⁻) + Δv``.  Section just after a bounce, coordinate ``v`` (m/s, up); the
    return map ``P(v) = e v + Δv`` has the fixed point ``v* = Δv / (1 − e)``, multiplier ``e``,
    period ``2 v* / g``."""

    name = "kicked_ball"
    title = "Kicked ball (contract-test example)"
    reference = "tests/test_model_contract.py"
    state_units = {"y": "m", "v": "m/s"}

    restitution: float = parameter(
        0.5, unit="1", doc="coefficient of restitution e", source="example", low=0.0, high=1.0,
        high_open=True,
    )  # fmt: skip
    kick: float = parameter(
        2.0, unit="m/s", doc="velocity added at each bounce Δv", source="example", low=0.0,
        high=100.0, low_open=True,
    )  # fmt: skip
    gravity: float = parameter(
        9.81, unit="m/s^2", doc="gravitational acceleration g", source="standard gravity",
        low=0.0, high=100.0, low_open=True,
    )  # fmt: skip

    @classmethod
    def build(cls, sym: Symbols):
        x, (y, v) = sym.states("y", "v")
        bounce = Transition(
            name="bounce",
            guard=sym.function("guard", x, y),
            direction=-1,
            reset=sym.function("reset", x, ca.vertcat(0, -sym.restitution * v + sym.kick)),
            target=0,
            doc="y = 0 falling; v⁺ = −e v⁻ + Δv",
        )
        above = sym.constraint(
            "ball above the table", x, y, "ball below the table", at_start=True, at_end=True,
            unit="m", source="the table is solid",
        )  # fmt: skip
        flight = Phase(
            "flight",
            ("y", "v"),
            sym.function("flow", x, ca.vertcat(v, -sym.gravity)),
            (bounce,),
            {"energy": sym.conserved("energy", x, 0.5 * v**2 + sym.gravity * y)},
            constraints=(above,),
        )
        s = ca.SX.sym("s", 1)
        section = Section(("v",), sym.lift(s, ca.vertcat(0, s[0])), "just after a bounce: y = 0")
        return (flight,), section

    def default_start(self):
        return {"v": 3.0}


def test_a_registered_model_gets_the_contract_and_the_cli(capsys):
    # Closed form: v* = Δv / (1 − e) = 4 m/s, multiplier e = 0.5, period 2 v*/g; 1e-9.
    gaitopt.register(KickedBall)
    try:
        cycle = gaitopt.find_limit_cycle(gaitopt.model("kicked_ball"))
        assert cycle.success and cycle.stable
        assert cycle.fixed_point["v"] == pytest.approx(4.0, abs=1e-9)
        assert cycle.multipliers[0].real == pytest.approx(0.5, abs=1e-9)
        assert cycle.period == pytest.approx(8.0 / 9.81, abs=1e-9)
        cycles = {"kicked_ball": cycle}
        test_structure_is_consistent("kicked_ball")
        test_conserved_quantities_are_constant_along_the_flow("kicked_ball", cycles)
        test_resets_land_on_the_section_and_the_safe_side_of_guards("kicked_ball", cycles)
        test_multipliers_agree_with_finite_differences_of_the_simulated_map("kicked_ball", cycles)
        test_bad_parameters_and_states_are_refused_clearly("kicked_ball")
        from gaitopt.cli import main

        assert main(["solve", "kicked_ball", "--set", "kick=1", "--json"]) == 0
        out = json.loads(capsys.readouterr().out)
        assert out["fixed_point"]["v"] == pytest.approx(2.0, abs=1e-9)  # Δv/(1 − e) = 2
        # Registering the same class again is a no-op (an entry point's loader does, after the
        # module's @register); another class under the same name is refused (one meaning per name).
        assert gaitopt.register(KickedBall) is KickedBall
        with pytest.raises(GaitoptInputError, match="kicked_ball"):
            gaitopt.register(type("KickedBall", (KickedBall,), {}))
    finally:
        gaitopt.unregister("kicked_ball")
    assert "kicked_ball" not in gaitopt.REGISTRY
