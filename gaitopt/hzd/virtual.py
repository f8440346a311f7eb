"""Virtual constraints as a controller: the closed loop of any actuated model, as a HybridModel.

Westervelt, Grizzle & Koditschek 2003 (IEEE TAC 48(1), "Hybrid zero dynamics of planar biped
walkers"); Westervelt et al. 2007 (*Feedback Control of Dynamic Bipedal Robot Locomotion*),
§5.2 and §6.3.  For a plant ``D(q) q̈ = rhs(q, q̇, u) = B u − C(q, q̇) q̇ − G(q)`` with ``N``
configuration coordinates and ``N − 1`` torques, a *phase variable* ``θ(q) = c·q``, monotonic
over a step from ``θ⁺`` to ``θ⁻``, and its normalisation ``s = (θ − θ⁺)/(θ⁻ − θ⁺) ∈ [0, 1]``,
the outputs (one per actuated coordinate ``q_a``, eq. (6.15))::

    y = q_a − h_d(s(θ), α),   h_d,j(s) = Σ_k α_{j,k} C(M, k) s^k (1 − s)^(M − k),

are zeroed by input–output linearisation (Isidori 1995, §5.1)::

    u = (L_g L_f y)⁻¹ (−L_f² y − K_p y − K_d L_f y),   K_p = ω_n²,  K_d = 2 ζ ω_n,

so ``ÿ + K_d ẏ + K_p y = 0`` along the flow.  The closed loop is a :class:`HybridModel` built by
:func:`virtual_constraint_model`: its parameters are the plant's, ``omega_n``, ``zeta``, the phase
range ``theta_plus``, ``theta_minus`` and the Bézier coefficients ``alpha_<joint>_<k>``, so
``find_limit_cycle``, the Floquet multipliers, continuation and the independent simulation work
on it unchanged.  Guards, resets, falls and the section are the plant model's own (phase 0,
whose guards and resets see the feedback torques); the unilateral conditions are the plant's own
where the plant is an open loop in the torques (its ``inputs`` are them: the five-link biped),
else the plant's ground reaction ``N ≥ 0`` with the closed loop's ``q̈`` (the three-link walker,
itself a closed loop).

**The plant protocol.**  A model class is a plant if it declares :meth:`manipulator`
(``(q, q̇, u, p) -> (D, rhs)``, rhs affine in ``u``), ``actuated_coordinates`` (names of ``N − 1``
configuration states: the first ``N`` states are ``q``, the next ``N`` their rates),
``plant_parameters`` (the parameters the plant's functions use; a model that is itself a closed
loop — the three-link walker — has others), optionally ``phase_variable`` (``{state: c_i}``)
and ``ground_reaction`` (``(q, q̇, q̈, p) -> N``, newtons).
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Mapping
from typing import Any, ClassVar

import casadi as ca
import numpy as np

from ..errors import GaitoptInputError, ParameterError
from ..hybrid import HybridModel, Phase, Section, Symbols
from ..mechanics import solve_small
from ..parameters import parameter
from .bezier import bezier

__all__ = [
    "MIN_DEGREE",
    "MAX_DEGREE",
    "VirtualConstraintModel",
    "virtual_constraint_model",
    "plant_of",
    "alpha_name",
]

#: Degrees of the Bézier outputs accepted (Westervelt et al. 2007 use 4–6; above ~20 the
#: Bernstein coefficients C(M, k) pass 1e5 and the constraints are ill-conditioned).
MIN_DEGREE, MAX_DEGREE = 1, 20
_SOURCE = "Westervelt, Grizzle & Koditschek 2003 (IEEE TAC 48(1)); Westervelt et al. 2007, §6.3"
_CLASSES: dict[tuple[type, int, tuple[float, ...]], type] = {}


def alpha_name(joint: str, k: int) -> str:
    """The parameter name of the Bézier coefficient ``α_{joint,k}`` (rad)."""
    return f"alpha_{joint}_{k}"


def plant_of(model: HybridModel | type) -> type:
    """The plant class of ``model`` (a model or a class), checked against the plant protocol
    (module docstring); :class:`~gaitopt.errors.GaitoptInputError` naming what is missing."""
    cls = model if isinstance(model, type) else type(model)
    missing = [
        k
        for k in ("manipulator", "actuated_coordinates", "plant_parameters")
        if not hasattr(cls, k)
    ]
    if missing:
        raise GaitoptInputError(
            f"model: {cls.name!r} is not an actuated model with a manipulator form (it declares "
            f"no {missing[0]}); virtual constraints need one, e.g. three_link_walker"
        )
    return cls


def _phase_vector(cls: type, phase_variable: Mapping[str, float] | None) -> tuple[float, ...]:
    """``c`` of ``θ = c·q`` from ``{state: coefficient}`` (default: the plant's own)."""
    states = cls.declared_states or cls.structure().phases[0].states
    n = len(states) // 2
    config = states[:n]
    given = dict(phase_variable if phase_variable is not None else cls.phase_variable)
    unknown = [k for k in given if k not in config]
    if unknown or not given:
        raise GaitoptInputError(
            f"phase_variable: {unknown[0] if unknown else given!r} is not a configuration "
            f"coordinate of {cls.name}; use some of {', '.join(config)}, e.g. {config[0]}=1"
        )
    c = tuple(float(given.get(k, 0.0)) for k in config)
    if not all(math.isfinite(v) for v in c) or not any(c):
        raise GaitoptInputError(f"phase_variable: {given!r} must be finite and not all zero")
    return c


class VirtualConstraintModel(HybridModel):
    """Base of the closed loops :func:`virtual_constraint_model` makes (not a model itself).

    Class attributes set by the factory: ``plant`` (the plant class), ``degree`` (M),
    ``phase`` (``c``), ``joints`` (the actuated coordinates, one Bézier output each).
    """

    plant: ClassVar[type]
    degree: ClassVar[int]
    phase: ClassVar[tuple[float, ...]]
    joints: ClassVar[tuple[str, ...]]
    _functions: ClassVar[dict[str, ca.Function]]

    def check(self) -> None:
        if self.theta_minus == self.theta_plus:
            raise ParameterError(
                f"{self.name}: theta_plus = theta_minus = {self.theta_plus:g}: the phase needs "
                f"a range; set theta_minus to the phase variable at the impact"
            )

    # -- parameters by role --------------------------------------------------------------------
    @property
    def alpha(self) -> dict[str, np.ndarray]:
        """The Bézier coefficients by joint (rad), ``(M + 1,)`` each."""
        return {
            j: np.array([getattr(self, alpha_name(j, k)) for k in range(self.degree + 1)])
            for j in self.joints
        }

    def with_alpha(
        self, alpha: Mapping[str, np.ndarray], **changes: float
    ) -> VirtualConstraintModel:
        """A copy with the coefficients of ``alpha`` (by joint, rad) and other ``changes``."""
        values = {alpha_name(j, k): float(v) for j, col in alpha.items() for k, v in enumerate(col)}
        return self.replace(**values, **changes)

    @property
    def plant_model(self) -> HybridModel:
        """The plant model with this closed loop's plant parameters."""
        return self.plant(**{k: getattr(self, k) for k in self.plant.plant_parameters})

    def default_start(self) -> dict[str, float]:
        return self.plant_model.default_start()

    def existence_note(self) -> str | None:
        return (
            "a gait of the closed loop exists where its zero dynamics carry the phase variable "
            "from theta_plus to theta_minus (gaitopt.hzd.restricted_map: the energy condition of "
            "Westervelt, Grizzle & Koditschek 2003, Thm 3)"
        )

    # -- numeric functions ---------------------------------------------------------------------
    def _call(self, name: str, *args: Any) -> Any:
        self.structure()
        return self._functions[name](*args, self.p)

    def torques(self, x: np.ndarray) -> np.ndarray:
        """The controller's torques at state(s) ``x`` ((2N,) or (2N, K)), N·m."""
        X = np.asarray(x, dtype=float)
        n = X.shape[0]
        out = np.asarray(self._call("torques", X.reshape(n, -1)), dtype=float)
        return out.ravel() if X.ndim == 1 else out

    def outputs(self, x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """The outputs ``y`` (rad) and ``ẏ = L_f y`` (rad/s) at one state ``x``."""
        y, dy = self._call("outputs", np.asarray(x, dtype=float))
        return np.asarray(y, dtype=float).ravel(), np.asarray(dy, dtype=float).ravel()

    def phase_value(self, x: np.ndarray) -> np.ndarray:
        """``θ = c·q`` (rad) at state(s) ``x``."""
        X = np.asarray(x, dtype=float)
        n = len(self.phase)
        return np.asarray(self.phase) @ X[:n]

    def max_torque(self, cycle: Any, states: Any = None) -> float:
        """``max |u_i|`` (N·m) on a gait's dense samples (or on ``states``, one per column)."""
        arrays = [arc.x for arc in cycle.orbit] if states is None else list(states)
        return float(max(np.max(np.abs(self.torques(X))) for X in arrays))

    @classmethod
    def build(cls, sym: Symbols) -> tuple[tuple[Phase, ...], Section]:
        plant = cls.plant
        base = plant.structure()
        phase0 = base.phases[0]
        states = phase0.states
        n = len(states) // 2
        x, _ = sym.states(*states)
        q, qd = x[:n], x[n:]
        # The plant's parameter vector: this loop's symbols for the plant's parameters, the
        # plant's defaults for its other parameters (which its plant functions do not use).
        pb = ca.vertcat(
            *[
                getattr(sym, s.name) if s.name in plant.plant_parameters else s.default
                for s in plant.parameter_specs()
            ]
        )
        manipulator = plant.manipulator()
        m_in = manipulator.size1_in(2)
        u = ca.SX.sym("u", m_in)
        M, rhs = manipulator(q, qd, u, pb)
        Bm = ca.jacobian(rhs, u)
        rhs0 = ca.substitute(rhs, u, ca.SX.zeros(m_in))
        drift = solve_small(M, rhs0)  # a = D⁻¹ (−C q̇ − G)
        gain = ca.horzcat(*[solve_small(M, Bm[:, k]) for k in range(m_in)])  # A = D⁻¹ B
        theta = ca.dot(ca.DM(cls.phase), q)
        s = (theta - sym.theta_plus) / (sym.theta_minus - sym.theta_plus)
        idx = [states.index(j) for j in cls.joints]
        y = ca.vertcat(
            *[
                q[i] - bezier([getattr(sym, alpha_name(j, k)) for k in range(cls.degree + 1)], s)
                for i, j in zip(idx, cls.joints, strict=True)
            ]
        )
        J = ca.jacobian(y, q)
        dy = J @ qd  # L_f y
        ddy = ca.jtimes(dy, q, qd) + J @ drift  # L_f² y
        decoupling = J @ gain  # L_g L_f y
        kp, kd = sym.omega_n**2, 2 * sym.zeta * sym.omega_n
        torque = ca.cse(solve_small(decoupling, -ddy - kp * y - kd * dy))
        qdd = ca.cse(drift + gain @ torque)
        flow = sym.function("flow", x, ca.vertcat(qd, qdd))

        # A plant whose own inputs are the torques (an open-loop model: the five-link biped)
        # has phase functions of u: they see the feedback torques, and its constraints carry
        # over.  A plant that is itself a closed loop (the three-link walker, no inputs) has
        # functions of the state only; its one constraint is rebuilt from ground_reaction.
        open_loop = len(plant.inputs) == m_in
        u0 = torque if open_loop else ca.DM.zeros(len(plant.inputs), 1)

        def wrap(name: str, f: ca.Function | None) -> ca.Function | None:
            return None if f is None else sym.function(name, x, f(x, u0, pb))

        transitions = tuple(
            dataclasses.replace(
                t,
                guard=wrap("guard", t.guard),
                reset=wrap("reset", t.reset),
                admissible=wrap("admissible", t.admissible),
            )
            for t in phase0.transitions
        )
        constraints: tuple = ()
        if open_loop:
            constraints = tuple(
                dataclasses.replace(c, function=wrap("constraint", c.function))
                for c in phase0.constraints
            ) + _friction(sym, phase0, x, ca.vertcat(qd, qdd), pb, plant)
        elif hasattr(plant, "ground_reaction"):
            push = plant.ground_reaction()(q, qd, qdd, pb)
            constraints = (
                sym.constraint(
                    "stance foot pushes on the ground", x, push, "stance foot lifts off",
                    unit="N", source="a ground contact can only push (unilateral normal force)",
                ),
            )  # fmt: skip
        p = sym.p

        def on_x(name: str, f: ca.Function | None) -> ca.Function | None:
            if f is None:
                return None
            outs = f(x, pb)
            outs = outs if isinstance(outs, tuple) else (outs,)
            return ca.Function(name, [x, p], list(outs), ["x", "p"], f.name_out())

        phase = Phase(
            phase0.name,
            states,
            flow,
            transitions,
            {},  # the torques do work: nothing is conserved along the closed loop
            points=on_x("points", phase0.points),
            point_names=phase0.point_names,
            bodies=on_x("bodies", phase0.bodies),
            constraints=constraints,
        )
        sc = ca.SX.sym("s", len(base.section.coordinates))
        section = Section(
            base.section.coordinates, sym.lift(sc, base.section.lift(sc, pb)), base.section.doc
        )
        cls._functions = {
            "torques": ca.Function("torques", [x, p], [torque], ["x", "p"], ["u"]),
            "outputs": ca.Function("outputs", [x, p], [y, dy], ["x", "p"], ["y", "dy"]),
            "decoupling": ca.Function("decoupling", [x, p], [ca.det(decoupling)], ["x", "p"],
                                      ["det"]),
        }  # fmt: skip
        return (phase,), section


def _friction(sym: Symbols, phase0: Phase, x: ca.SX, xdot: ca.SX, pb: ca.SX, plant: type) -> tuple:
    """The stance foot's friction cone ``|F_t| ≤ μ F_n`` as two unilateral constraints
    ``μ F_n ∓ F_t ≥ 0`` (N), with the contact force of the whole walker (Newton's second law,
    ``F = Σ m_i (r̈_i + g ŷ)``, ``r̈_i = ∂v_i/∂x · ẋ`` along the closed loop) resolved on the
    ground line of slope ``γ`` (normal ``(sin γ, cos γ)``, tangent ``(cos γ, −sin γ)``); none for a
    plant without point masses (``Phase.bodies``)."""
    if phase0.bodies is None:
        return ()
    m, _, v = phase0.bodies(x, pb)
    specs = [s.name for s in plant.parameter_specs()]
    g = pb[specs.index("gravity")] if "gravity" in specs else 9.81
    gamma = pb[specs.index("slope")] if "slope" in specs else 0.0
    acc = ca.reshape(ca.jtimes(ca.vec(v), x, xdot), v.shape[0], v.shape[1])
    force = (acc + ca.repmat(ca.vertcat(0, g), 1, v.shape[1])) @ m
    normal = ca.sin(gamma) * force[0] + ca.cos(gamma) * force[1]
    tangent = ca.cos(gamma) * force[0] - ca.sin(gamma) * force[1]
    mu = sym.friction_coefficient
    source = "Coulomb friction at the stance foot (Westervelt et al. 2007, §6.6.2: |F_T| ≤ μ F_N)"
    return (
        sym.constraint("stance foot does not slip forward", x, mu * normal - tangent,
                       "stance foot slips", unit="N", source=source),
        sym.constraint("stance foot does not slip backward", x, mu * normal + tangent,
                       "stance foot slips", unit="N", source=source),
    )  # fmt: skip


def virtual_constraint_model(
    plant: HybridModel | type,
    degree: int,
    phase_variable: Mapping[str, float] | None = None,
) -> type[VirtualConstraintModel]:
    """The closed-loop model class of ``plant`` under Bézier virtual constraints of ``degree``.

    Parameters
    ----------
    plant : HybridModel or type
        A model (or model class) that declares the plant protocol (module docstring).
    degree : int
        Bézier degree ``M`` of every output, 1 to :data:`MAX_DEGREE`.
    phase_variable : mapping, optional
        ``{configuration state: c_i}`` of ``θ = c·q`` (rad); default the plant's
        ``phase_variable``.

    Returns
    -------
    type
        A :class:`VirtualConstraintModel` subclass (one per plant, degree and phase variable,
        built once), not registered.  Its parameters: the plant's, ``omega_n`` (rad/s), ``zeta``
        (1), ``theta_plus``, ``theta_minus`` (rad) and ``alpha_<joint>_<k>`` (rad), defaults
        from ``plant.virtual_constraint_defaults(degree)`` where the plant declares it.
    """
    cls = plant_of(plant)
    if (
        isinstance(degree, bool)
        or not isinstance(degree, (int, np.integer))
        or not (MIN_DEGREE <= degree <= MAX_DEGREE)
    ):
        raise GaitoptInputError(
            f"degree: {degree!r} is not an integer from {MIN_DEGREE} to {MAX_DEGREE}; Bézier "
            f"virtual constraints of degree 4 to 6 are usual (Westervelt et al. 2007), e.g. 4"
        )
    degree = int(degree)
    c = _phase_vector(cls, phase_variable)
    key = (cls, degree, c)
    if key in _CLASSES:
        return _CLASSES[key]
    defaults = dict(cls.virtual_constraint_defaults(degree)) if hasattr(
        cls, "virtual_constraint_defaults"
    ) else {}  # fmt: skip
    joints = tuple(cls.actuated_coordinates)
    fields: list[tuple[str, type, Any]] = []
    specs = {s.name: s for s in cls.parameter_specs()}
    for name in cls.plant_parameters:
        spec = specs[name]
        fields.append((name, float, dataclasses.field(default=spec.default,
                                                      metadata={"gaitopt": spec})))  # fmt: skip
    angle = {"unit": "rad", "source": _SOURCE, "low": -2 * math.pi, "high": 2 * math.pi}
    fields += [
        ("omega_n", float, parameter(defaults.get("omega_n", 10.0), unit="rad/s",
                                     doc="natural frequency ω_n of ÿ + 2ζω_n ẏ + ω_n² y = 0 "
                                     "(K_p = ω_n², K_d = 2ζω_n)", source=_SOURCE, low=0.0,
                                     high=1e4, low_open=True)),
        ("zeta", float, parameter(defaults.get("zeta", 1.0), unit="1",
                                  doc="damping ratio ζ of the output dynamics", source=_SOURCE,
                                  low=0.0, high=100.0, low_open=True)),
        ("theta_plus", float, parameter(defaults.get("theta_plus", -0.3), doc="phase variable θ "
                                        "at the start of a step (s = 0)", **angle)),
        ("theta_minus", float, parameter(defaults.get("theta_minus", 0.3), doc="phase variable "
                                         "θ at the end of a step (s = 1)", **angle)),
    ]  # fmt: skip
    if len(cls.inputs) == cls.manipulator().size1_in(2):  # an open loop: its friction cone
        fields.append(("friction_coefficient", float, parameter(
            defaults.get("friction_coefficient", 0.6), unit="1", doc="Coulomb friction "
            "coefficient μ of the stance foot (|F_t| ≤ μ F_n)", source="RABBIT's μ = 0.6 (FROST)",
            low=0.0, high=100.0)))  # fmt: skip
    for j in joints:
        for k in range(degree + 1):
            name = alpha_name(j, k)
            fields.append((name, float, parameter(
                float(defaults.get(name, 0.0)), doc=f"Bézier coefficient α_{k} of the output "
                f"of {j} (h_d = Σ α_k C(M,k) s^k (1−s)^(M−k))", **angle)))  # fmt: skip
    tag = "" if c == _phase_vector(cls, None) else "_phase" + "_".join(f"{v:g}" for v in c)
    name = f"{cls.name}_vc{degree}{tag}"
    namespace = {
        "name": name,
        "title": f"{cls.title or cls.name} under Bézier virtual constraints (degree {degree})",
        "reference": _SOURCE,
        "plant": cls,
        "degree": degree,
        "phase": c,
        "joints": joints,
        "state_units": dict(cls.state_units),
        "drawing": cls.drawing,
        "mesh": cls.mesh,
        "__module__": __name__,
    }
    new = dataclasses.make_dataclass(
        "".join(w.title() for w in name.split("_")),
        fields,
        bases=(VirtualConstraintModel,),
        namespace=namespace,
        frozen=True,
    )

    _CLASSES[key] = new
    return new
