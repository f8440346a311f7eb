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
import pytest

import gaitopt
from gaitopt import testing
from gaitopt.errors import GaitoptInputError
from gaitopt.hybrid import HybridModel, Phase, Section, Symbols, Transition
from gaitopt.parameters import parameter

ALL = list(gaitopt.REGISTRY)
PASSIVE = [name for name, cls in gaitopt.REGISTRY.items() if cls.passive_gait]


def _gait(cycles, name):
    if name not in cycles:
        pytest.skip(f"{name} has no passive gait (actuated only)")
    cycle = cycles[name]
    assert cycle.success, cycle.message
    return cycle


# -- the contract, check by check (gaitopt.testing holds each check, its source and tolerance) ----


@pytest.mark.parametrize("name", ALL)
def test_structure_is_consistent(name):
    # Targets in cycle order, reset dimensions, declared units and inputs: what the shooting and
    # the simulation both rely on (the simulation follows `target`, the shooting the cycle order).
    testing.check_structure(gaitopt.REGISTRY[name])


@pytest.mark.parametrize("name", PASSIVE)
def test_conserved_quantities_are_constant_along_the_flow(name, cycles):
    # Invariant: each declared conserved quantity is constant along its phase's passive flow;
    # rtol 1e-11 over two orbits, tolerance 1e-8 relative (gaitopt.testing.check_conserved).
    testing.check_conserved(_gait(cycles, name))


#: Passive models whose gait has impacts at a foothold, with point masses declared on both sides
#: (``Phase.bodies``).  Every other passive model must have no impact at a foothold (Van der Pol
#: has none; the runners' and hoppers' touchdowns with massless legs change no velocity and are
#: declared ``impact=False``; the jugglers' and the bouncing ball's impacts are not at a
#: foothold), except where :data:`OTHER_IMPULSES` says why angular momentum is not the law.
MOMENTUM = {
    "rimless_wheel", "compass_gait", "simplest_walker", "kneed_walker", "three_link_walker",
}  # fmt: skip
#: Foothold impacts with other impulses acting too, so that the angular momentum about the new
#: foothold is not conserved; their own impact law is tested where the reason points.
OTHER_IMPULSES = {
    "strandbeest": "the pitch hold's impulse acts with the new contact's; the impact conserves "
    "G_nᵀ M₃ q̇ instead (tests/test_strandbeest.py, the closed form of the impact ratios)",
}


@pytest.mark.parametrize("name", PASSIVE)
def test_impacts_conserve_angular_momentum_about_the_new_foothold(name, cycles):
    # Invariant: a plastic impact at a point conserves the angular momentum of the whole system
    # about that point (Goswami et al. 1996, eq. 8); 1e-10 relative (check_impact_momentum).
    cycle = _gait(cycles, name)
    checked = testing.check_impact_momentum(cycle)
    footholds = any(
        tr.impact and tr.foothold for phase in cycle.model.phases for tr in phase.transitions
    )
    if name in MOMENTUM:
        assert checked > 0, f"{name} must declare bodies on both sides of its foothold impacts"
    elif name not in OTHER_IMPULSES:
        assert not footholds, f"{name} has impacts at a foothold: declare bodies, list it above"


@pytest.mark.parametrize("name", PASSIVE)
def test_resets_land_on_the_section_and_the_safe_side_of_guards(name, cycles):
    # After each reset no guard of the next phase fires at once (1e-9), and the state that
    # closes the cycle lies on the section: lift(project(x)) = x, 1e-10 (check_resets).
    testing.check_resets(_gait(cycles, name))


@pytest.mark.parametrize("name", PASSIVE)
def test_multipliers_agree_with_finite_differences_of_the_simulated_map(name, cycles):
    # Two independent methods: AD through the shooting equations (implicit function theorem)
    # vs central differences of the event-located SciPy map (rtol 1e-11, h = 1e-5 relative).
    # Error budget: h² P‴ ~ 1e-10 plus rounding 1e-11 / h ~ 1e-6, relative to the map's scale
    # 1 + max |J|; tolerance 2e-6 (1 + max |J|) on the Jacobian's entries and on the moduli of
    # its eigenvalues.  The largest error seen is 7.9e-7 (1 + max |J|), the simplest walker's.
    testing.check_multipliers(_gait(cycles, name))


@pytest.mark.parametrize("name", ALL)
def test_bad_parameters_and_states_are_refused_clearly(name):
    # One GaitoptInputError (a ValueError) naming the argument: an unknown parameter, a value
    # outside the declared range, a non-number, an unknown state (check_bad_input).
    testing.check_bad_input(gaitopt.REGISTRY[name])


def test_a_contract_check_names_the_model_and_what_failed():
    # The checks fail loudly: a model whose reset gives the wrong number of states is refused
    # with the structure's own message.
    from test_structure import _ball

    with pytest.raises(Exception, match="reset gives 3 states"):
        testing.check_structure(_ball(reset_states=3))


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
        # The whole contract in one call, as another package's tests would run it.
        report = testing.check_model(KickedBall, gait=cycle)
        assert report["impacts_checked"] == 0  # its bounce is not at a foothold
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
