"""Ballistic walking (Mochon & McMahon 1980, "Ballistic walking", J. Biomech. 13:49–57).

The swing phase of human walking, from toe-off to heel strike, with no muscle moments: the stance
leg is a rigid inverted pendulum about the stance foot carrying the body (head, arms and trunk) as
a point mass at the hip, and the swing leg is a free double pendulum — thigh and shank, the knee
free — hanging from the hip.  Three degrees of freedom: ``stance`` (the stance leg's angle from
vertical, positive when the hip is ahead of the foot), ``thigh`` and ``shank`` (the swing thigh's
and shank's angles from the downward vertical, positive forward); the knee flexion is
``thigh − shank`` (positive: flexed).  Lagrange's equations come from the segments' masses and
inertias (:mod:`gaitopt.mechanics`, each segment an equimomental pair of point masses).

It is a boundary-value problem, not a passive limit cycle: the step length ``d`` fixes the
configuration at toe-off (``stance = −α``, ``sin α = d / (2 l)``; the swing knee flexed by
``κ₀`` = ``toe_off_knee`` with the toe on the ground behind) and at heel strike (``stance = +α``,
swing leg straight, ``thigh = shank = +α``, its heel on the ground a step ahead); for a given
swing time the three rates at toe-off are found that reach heel strike at that time
(:meth:`swing`).  A *ballistic* swing is one whose knee never hyperextends (flexion ≥ 0), whose
foot clears the ground in between and whose stance leg pushes on the ground; Mochon & McMahon
found such swings only in a range of step periods for each step length (problems/
ballistic_walking.py computes that range here).

Simplifications against the paper, stated: the toe-off configuration is set by the step length
and a knee flexion κ₀ (the paper takes its toe-off angles from measurements), the foot is a point
at the end of the shank (no ankle: the toe stands in for the foot at toe-off, the heel at heel
strike), and the segment data are Winter's anthropometric fractions (Winter, "Biomechanics and Motor
Control of Human Movement", table 4.1): thigh 0.100 M with centre of mass 0.433 of its length from
the hip and radius of gyration 0.323 of its length; shank with foot 0.061 M, centre of mass at
mid-length (approximate) and radius of gyration 0.302 of its length; the rest of the mass at the
hip.

The hybrid model has one phase, the swing; heel strike (``stance = +α``) ends it.  The double
support and push-off that would start the next swing are not modelled (nor by the paper), so the
model has no passive gait (:attr:`passive_gait` is False): ``find_limit_cycle`` is not the tool
for it; :meth:`swing` is.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import casadi as ca
import numpy as np

from ..hybrid import HybridModel, Phase, Section, Symbols, Transition
from ..mechanics import kinetic_energy, lagrange_acceleration, potential_energy, rigid_link
from ..parameters import gravity_parameter, parameter
from .quantities import state_units

__all__ = ["BallisticWalker", "Swing"]

# Winter, Biomechanics and Motor Control of Human Movement, table 4.1 (fractions of body mass M
# and of segment length L).
THIGH_MASS, THIGH_COM, THIGH_GYRATION = 0.100, 0.433, 0.323
SHANK_MASS, SHANK_COM, SHANK_GYRATION = 0.061, 0.5, 0.302  # leg + foot; COM approximate


@dataclass
class Swing:
    """One ballistic-swing boundary-value solution.

    Attributes
    ----------
    success : bool
        Whether the boundary conditions were met (residual below 1e-9 rad).
    ballistic : bool
        ``success`` and every condition of a ballistic swing holds: knee flexion ≥ 0, swing foot
        above the ground between toe-off and heel strike, the stance leg pushing (vertical ground
        force > 0), the hip moving forward.
    reason : str
        The first condition that fails, or ``""``.
    time : float
        Swing time (s).
    rates : numpy.ndarray
        Rates at toe-off (rad/s): stance, thigh, shank.
    t, x : numpy.ndarray
        Dense samples of the swing (s; states × samples).
    min_knee_flexion, min_foot_height, min_vertical_force : float
        Extremes over the interior of the swing (rad, m, N).
    max_knee_flexion : float
        Largest knee flexion in the swing (rad).
    """

    success: bool
    ballistic: bool
    reason: str
    time: float
    rates: np.ndarray
    t: np.ndarray
    x: np.ndarray
    min_knee_flexion: float
    min_foot_height: float
    min_vertical_force: float
    max_knee_flexion: float = math.nan


@dataclass(frozen=True)
class BallisticWalker(HybridModel):
    """Mochon & McMahon's ballistic swing: states ``stance, thigh, shank`` (rad) and their rates."""

    name = "ballistic_walker"
    #: For ``gaitopt list`` without a build (checked against it).
    declared_states = ("stance", "thigh", "shank", "stance_dot", "thigh_dot", "shank_dot")
    declared_coordinates = ("stance_dot", "thigh_dot", "shank_dot")
    declared_section_doc = (
        "toe-off: stance = −asin(step_length / 2 l), knee flexed by toe_off_knee with the toe on "
        "the ground behind; rates free"
    )
    title = "Ballistic walker (swing phase)"
    reference = "Mochon & McMahon 1980, J. Biomech. 13:49–57"
    state_units = state_units(stance="rad", thigh="rad", shank="rad")
    drawing = (("stance_foot", "hip", "knee", "swing_foot"),)
    passive_gait = False
    mesh = (6, 6)

    mass: float = parameter(
        70.0, unit="kg", doc="body mass M", source="a typical adult", low=1.0, high=300.0
    )
    thigh_length: float = parameter(
        0.45, unit="m", doc="thigh length (hip to knee)", source="a typical adult",
        low=0.05, high=2.0,
    )  # fmt: skip
    shank_length: float = parameter(
        0.45, unit="m", doc="shank length (knee to sole)", source="a typical adult",
        low=0.05, high=2.0,
    )  # fmt: skip
    step_length: float = parameter(
        0.7, unit="m", doc="step length d (foot to foot)", source="normal adult walking",
        low=0.01, high=3.0,
    )  # fmt: skip
    toe_off_knee: float = parameter(
        0.6, unit="rad", doc="knee flexion at toe-off κ₀ (≈ 35°)",
        source="typical human knee flexion at toe-off (Winter, gait data)", low=0.0, high=1.5,
    )  # fmt: skip
    gravity: float = gravity_parameter()

    def check(self) -> None:
        from ..errors import ParameterError

        leg = self.thigh_length + self.shank_length
        if self.step_length >= 2 * leg:
            raise ParameterError(
                f"ballistic_walker: `step_length` = {self.step_length:g} m must be below twice the "
                f"leg length, {2 * leg:g} m; use a shorter step"
            )
        # With the knee flexed by κ₀ the hip-to-toe distance is R; the toe reaches the ground
        # behind only if the hip height l cos α is at most R.
        lt, ls, k0 = self.thigh_length, self.shank_length, self.toe_off_knee
        reach = math.sqrt(lt**2 + ls**2 + 2 * lt * ls * math.cos(k0))
        height = leg * math.sqrt(1 - (self.step_length / (2 * leg)) ** 2)
        if height > reach:
            raise ParameterError(
                f"ballistic_walker: with `toe_off_knee` = {k0:g} rad the toe reaches only "
                f"{reach:.4g} m from the hip, below the hip height {height:.4g} m at "
                f"`step_length` = {self.step_length:g} m: the toe cannot be on the ground at "
                f"toe-off; use a longer step or a smaller `toe_off_knee`"
            )

    # -- geometry ----------------------------------------------------------------------------
    @property
    def leg_length(self) -> float:
        """``l`` = thigh + shank (m)."""
        return self.thigh_length + self.shank_length

    @property
    def alpha(self) -> float:
        """Half the angle between the legs at toe-off and heel strike, ``asin(d / 2l)`` (rad)."""
        return math.asin(self.step_length / (2 * self.leg_length))

    @classmethod
    def _geometry(cls, sym: Symbols, q: ca.SX):
        stance, thigh, shank = q[0], q[1], q[2]
        lt, ls, M = sym.thigh_length, sym.shank_length, sym.mass
        leg = lt + ls
        up = ca.vertcat(ca.sin(stance), ca.cos(stance))  # from the stance foot to the hip
        hip = leg * up
        t_dir = ca.vertcat(ca.sin(thigh), -ca.cos(thigh))  # down the swing thigh
        s_dir = ca.vertcat(ca.sin(shank), -ca.cos(shank))
        knee = hip + lt * t_dir
        foot = knee + ls * s_dir
        m_t, m_s = THIGH_MASS * M, SHANK_MASS * M
        i_t, i_s = m_t * (THIGH_GYRATION * lt) ** 2, m_s * (SHANK_GYRATION * ls) ** 2
        masses = [(M - 2 * (m_t + m_s), hip)]  # head, arms and trunk at the hip
        # Stance leg, straight: thigh and shank along the same axis (foot → hip).
        masses += rigid_link(m_t, hip - THIGH_COM * lt * up, up, i_t)
        masses += rigid_link(m_s, (1 - SHANK_COM) * ls * up, up, i_s)
        masses += rigid_link(m_t, hip + THIGH_COM * lt * t_dir, t_dir, i_t)
        masses += rigid_link(m_s, knee + SHANK_COM * ls * s_dir, s_dir, i_s)
        return masses, hip, knee, foot

    @staticmethod
    def _toe_off(sym, alpha):
        """Thigh and shank angles at toe-off: knee flexed by κ₀, toe on the ground behind.

        ``l_t cos θ_t + l_s cos(θ_t − κ₀) = l cos α`` (the toe at ground level) is
        ``R cos(θ_t − φ) = l cos α`` with ``R = |(A, B)|``, ``φ = atan2(B, A)``, ``A = l_t + l_s
        cos κ₀``, ``B = l_s sin κ₀``; the root behind the hip is ``θ_t = φ − acos(l cos α / R)``."""
        lt, ls, k0 = sym.thigh_length, sym.shank_length, sym.toe_off_knee
        a_, b_ = lt + ls * ca.cos(k0), ls * ca.sin(k0)
        phi = ca.atan2(b_, a_)
        thigh = phi - ca.acos((lt + ls) * ca.cos(alpha) / ca.sqrt(a_**2 + b_**2))
        return thigh, thigh - k0

    @classmethod
    def build(cls, sym: Symbols) -> tuple[tuple[Phase, ...], Section]:
        names = ("stance", "thigh", "shank", "stance_dot", "thigh_dot", "shank_dot")
        x, _ = sym.states(*names)
        q, qd = x[0:3], x[3:6]
        masses, hip, knee, foot = cls._geometry(sym, q)
        qdd = lagrange_acceleration(masses, q, qd, sym.gravity)
        flow = sym.function("flow", x, ca.vertcat(qd, qdd))
        alpha = ca.asin(sym.step_length / (2 * (sym.thigh_length + sym.shank_length)))
        heel_strike = Transition(
            name="heel strike (end of the ballistic swing)",
            guard=sym.function("guard", x, x[0] - alpha),  # stance = +α
            direction=+1,
            reset=None,
            target=None,
            doc="stance = +α: the swing ends; double support is not modelled (nor by the paper)",
        )
        energy = sym.conserved(
            "energy",
            x,
            kinetic_energy(masses, q, qd) + potential_energy(masses, sym.gravity),
        )
        points = ca.Function("points", [x, sym.p], [ca.horzcat(ca.DM.zeros(2, 1), hip, knee, foot)])
        phase = Phase(
            "swing",
            names,
            flow,
            (heel_strike,),
            {"energy": energy},
            points=points,
            point_names=("stance_foot", "hip", "knee", "swing_foot"),
        )
        s = ca.SX.sym("s", 3)
        thigh0, shank0 = cls._toe_off(sym, alpha)
        section = Section(
            ("stance_dot", "thigh_dot", "shank_dot"),
            sym.lift(s, ca.vertcat(-alpha, thigh0, shank0, s)),
            "toe-off: stance = −asin(step_length / 2 l), knee flexed by toe_off_knee with the "
            "toe on the ground behind; rates free",
        )
        return (phase,), section

    # -- the boundary-value problem ----------------------------------------------------------
    def _functions(self):
        phase = self.phases[0]
        p = self.p
        u = np.zeros(0)
        flow = phase.flow
        x_sym = ca.SX.sym("x", 6)
        fun = ca.Function("f", [x_sym], [flow(x_sym, u, p)])
        pts = ca.Function("pts", [x_sym], [phase.points(x_sym, p)])
        return fun, pts

    def toe_off_angles(self) -> tuple[float, float, float]:
        """``(stance, thigh, shank)`` at toe-off (rad)."""
        x = self.lift(np.zeros(3))
        return float(x[0]), float(x[1]), float(x[2])

    def _integrate(self, rates, time, fun, dense: bool = False):
        from scipy.integrate import solve_ivp  # on first use: 0.4 s of every import otherwise

        x0 = np.r_[self.toe_off_angles(), rates]
        sol = solve_ivp(
            lambda t, x: np.asarray(fun(x)).ravel(),
            (0.0, time),
            x0,
            method="DOP853",
            rtol=1e-10,
            atol=1e-12,
            dense_output=dense,
        )
        return sol

    def swing(self, time: float, guess=None, samples: int = 400, continued: bool = False) -> Swing:
        """The ballistic swing of duration ``time`` (s) at this step length.

        Newton's method (``scipy.optimize.root``, hybr) on the three toe-off rates, so that after
        ``time`` seconds ``stance = thigh = shank = +α`` (heel strike, knee straight); the swing
        is then sampled and its ballistic conditions checked (see :class:`Swing`).

        Parameters
        ----------
        time : float
            Swing time (s), positive.
        guess : array_like, optional
            Toe-off rates (rad/s) to start from (e.g. the solution at a nearby time).
        samples : int
            Dense samples for the checks.
        continued : bool
            Internal: do not fall back to continuation in the time (already continuing).
        """
        fun, pts = self._functions()
        a = self.alpha
        _, thigh0, shank0 = self.toe_off_angles()
        from scipy.optimize import root  # on first use

        rough = np.array([2 * a / time, (a - thigh0) / time, (a - shank0) / time])
        if guess is None or not np.all(np.isfinite(guess)):
            guess = rough

        def residual(rates):
            if not np.all(np.isfinite(rates)):
                return np.full(3, 1e3)
            sol = self._integrate(rates, time, fun)
            if not sol.success or not np.all(np.isfinite(sol.y[:3, -1])):
                return np.full(3, 1e3)
            return sol.y[:3, -1] - a

        res = root(residual, np.asarray(guess, dtype=float), method="hybr", tol=1e-13)
        rates = np.asarray(res.x)
        if np.max(np.abs(residual(rates))) > 1e-9 and not continued:
            # Newton from the rough guess missed: continue in the swing time from 0.3 s, where
            # it converges, in steps of 0.05 s.
            path = np.arange(0.3, time, 0.05 if time > 0.3 else -0.05)
            for t_k in path:
                step = self.swing(float(t_k), guess, samples=3, continued=True)
                if step.success and np.all(np.isfinite(step.rates)):
                    guess = step.rates
            rates = np.asarray(root(residual, np.asarray(guess), method="hybr", tol=1e-13).x)
        if not np.all(np.isfinite(rates)):
            rates = np.asarray(guess if np.all(np.isfinite(guess)) else rough, dtype=float)
        sol = self._integrate(rates, time, fun, dense=True)
        err = float(np.max(np.abs(sol.y[:3, -1] - a)))
        t = np.linspace(0.0, time, samples)
        x = sol.sol(t)
        success = bool(res.success or err < 1e-9) and err < 1e-9
        interior = slice(1, -1)
        flexion = x[1] - x[2]
        flexion_rate_end = float(x[4, -1] - x[5, -1])
        foot_y = np.array([float(pts(x[:, k])[1, 3]) for k in range(samples)])
        force = self._vertical_force(x)
        # Interior minima (the ends are on the boundary by construction: knee straight, foot
        # on the ground); a small margin at the ends avoids their roundoff.
        inner = slice(samples // 50 + 1, -(samples // 50) - 1)
        checks = [
            (
                np.min(flexion[inner]) >= -1e-9,
                "the knee hyperextends (flexion < 0) in the swing",
            ),
            (
                flexion_rate_end < 0,
                "the knee reaches full extension flexing (it hyperextended before heel strike)",
            ),
            (np.min(foot_y[inner]) > 0, "the swing foot strikes the ground during the swing"),
            (np.min(force[interior]) > 0, "the stance leg pulls (vertical ground force ≤ 0)"),
            (np.min(x[3]) > 0, "the hip stops or moves backwards"),
        ]
        reason = "" if success else f"boundary conditions not met (error {err:.2g} rad)"
        if success:
            reason = next((why for ok, why in checks if not ok), "")
        return Swing(
            success=success,
            ballistic=success and reason == "",
            reason=reason,
            time=float(time),
            rates=rates,
            t=t,
            x=x,
            min_knee_flexion=float(np.min(flexion[inner])),
            min_foot_height=float(np.min(foot_y[inner])),
            min_vertical_force=float(np.min(force[interior])),
            max_knee_flexion=float(np.max(flexion)),
        )

    def _vertical_force(self, x: np.ndarray) -> np.ndarray:
        """Vertical ground force on the stance foot along the samples ``x`` (N), by Newton's
        second law for the whole system (:func:`gaitopt.mechanics.contact_force`)."""
        if not hasattr(self, "_force_fn"):
            from ..mechanics import contact_force

            sym = Symbols(self.parameter_specs(), ())
            xs = ca.SX.sym("x", 6)
            q, qd = xs[0:3], xs[3:6]
            masses, *_ = self._geometry(sym, q)
            qdd = lagrange_acceleration(masses, q, qd, sym.gravity)
            f = contact_force(masses, q, qd, qdd, sym.gravity)
            object.__setattr__(self, "_force_fn", ca.Function("F", [xs, sym.p], [f[1]]))
        fn = self._force_fn
        return np.array([float(fn(x[:, k], self.p)) for k in range(x.shape[1])])

    def natural_swing_time(self) -> float:
        """Half the period of the swing leg as a rigid compound pendulum about the hip, ``π
        sqrt(I_hip / (m g c))`` (s): a reference time scale for the swing (not a result)."""
        lt, ls, M = self.thigh_length, self.shank_length, self.mass
        m_t, m_s = THIGH_MASS * M, SHANK_MASS * M
        c_t, c_s = THIGH_COM * lt, lt + SHANK_COM * ls
        inertia = m_t * ((THIGH_GYRATION * lt) ** 2 + c_t**2) + m_s * (
            (SHANK_GYRATION * ls) ** 2 + c_s**2
        )
        c = (m_t * c_t + m_s * c_s) / (m_t + m_s)
        return math.pi * math.sqrt(inertia / ((m_t + m_s) * self.gravity * c))

    def existence_note(self) -> str | None:
        """Why there is no passive gait to search for."""
        return (
            "ballistic_walker models only the swing (toe-off to heel strike), a boundary-value "
            "problem in the swing time (BallisticWalker.swing; problems/ballistic_walking.py): "
            "it has no passive limit cycle (Mochon & McMahon 1980)"
        )

    def default_start(self) -> dict[str, float]:
        """Toe-off rates of a swing near the natural swing time (rad/s): a rough guess."""
        rate = 2 * self.alpha / self.natural_swing_time()
        return {"stance_dot": rate, "thigh_dot": 2 * rate, "shank_dot": rate}
