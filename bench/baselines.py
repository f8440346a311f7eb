"""The baseline of ``make bench``: each gait found the way a user would write it by hand.

Nothing here uses gaitopt's machinery (no CasADi, no :mod:`gaitopt.simulation`): plain Python
right-hand sides and impact maps per model, ``scipy.integrate.solve_ivp`` with a terminal,
directional event for the return map ``P`` on the Poincaré section, ``scipy.optimize.fsolve`` on
``P(s) − s`` from the model's default start, and the multipliers as the eigenvalues of a central
finite-difference Jacobian of the simulated map.  Only plain numbers cross over from gaitopt: the
parameter values, the default start and the names of the section coordinates (so that the two
fixed points can be compared entry by entry).

Choices a careful user would make, stated once:

* ``solve_ivp(method="DOP853", rtol=1e-10, atol=1e-10)``: the 8th-order pair, and the event is
  located on its 7th-order dense output;
* ``fsolve(xtol=1e-10)`` (default: 1.5e-8, too loose for a 1e-8 comparison);
* multipliers from central differences with step ``1e-6`` (truncation ~1e-12, integration noise
  ~1e-10 / 1e-6 = 1e-4: good to about four digits).

A phase that starts on its own guard (Van der Pol's section ``q = 0``, the simplest walker just
after heel strike) makes ``solve_ivp`` fire the event at ``t = 0``; as a user would, those maps
integrate in two legs, first to the half-way event and then to the return.  The compass gait uses
Drake's witness ``max(2γ − stance − swing, swing − stance)``, which stays positive through the
foot scuff.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field

import numpy as np
from scipy.integrate import solve_ivp
from scipy.optimize import fsolve

__all__ = ["HandWritten", "BaselineResult", "BASELINES", "baseline", "solve"]

METHOD = "DOP853"
RTOL = 1e-10
ATOL = 1e-10
XTOL = 1e-10
FD_STEP = 1e-6


class NoReturn(RuntimeError):
    """The simulation from a section point never comes back to the section."""


@dataclass(frozen=True)
class HandWritten:
    """A hand-written return map of one model.

    Attributes
    ----------
    name : str
        The gaitopt model name.
    state_names : tuple of str
        Full state, in gaitopt's order.
    coordinates : tuple of str
        Section coordinates, in gaitopt's order.
    lift : callable
        Section coordinates → full state on the section.
    step : callable
        Full state on the section → (full state on the section one step later, duration of the
        step); flow, event, impact.  Raises :class:`NoReturn` if the event is never reached.
    """

    name: str
    state_names: tuple[str, ...]
    coordinates: tuple[str, ...]
    lift: Callable[[np.ndarray], np.ndarray]
    step: Callable[[np.ndarray], tuple[np.ndarray, float]]

    def section(self, x: np.ndarray) -> np.ndarray:
        """Pick the section coordinates out of a full state."""
        return np.array([x[self.state_names.index(c)] for c in self.coordinates])

    def return_map(self, s: np.ndarray) -> np.ndarray:
        """``P(s)``: one step from section coordinates ``s`` to section coordinates."""
        return self.section(self.step(self.lift(np.asarray(s, dtype=float)))[0])


@dataclass
class BaselineResult:
    """What the hand-written baseline found.

    Attributes
    ----------
    success : bool
        ``fsolve`` reported convergence and the map returned everywhere.
    message : str
        ``fsolve``'s message, or why the map failed.
    fixed_point : dict of str to float
        Full state on the section.
    multipliers : numpy.ndarray
        Eigenvalues of the finite-difference Jacobian of ``P`` (complex), by decreasing modulus.
    period : float
        Duration of the step from the fixed point (evaluated after the timed part).
    map_evaluations : int
        Return-map evaluations (each one a ``solve_ivp`` run), ``fsolve`` and differences.
    solve_time : float
        Wall-clock seconds for the fixed point and its multipliers.
    """

    success: bool
    message: str
    fixed_point: dict[str, float] = field(default_factory=dict)
    multipliers: np.ndarray = field(default_factory=lambda: np.zeros(0, complex))
    period: float = float("nan")
    map_evaluations: int = 0
    solve_time: float = float("nan")

    @property
    def x(self) -> np.ndarray:
        """The fixed point as a vector (state order)."""
        return np.array(list(self.fixed_point.values()))


def _event(fun: Callable, direction: float) -> Callable:
    fun.terminal = True
    fun.direction = direction
    return fun


def _integrate(
    rhs: Callable, x0: np.ndarray, event: Callable, t_max: float
) -> tuple[np.ndarray, float]:
    """Integrate until ``event`` fires; the state there and the time taken."""
    sol = solve_ivp(rhs, (0.0, t_max), x0, method=METHOD, rtol=RTOL, atol=ATOL, events=event)
    if sol.status != 1 or not len(sol.y_events[0]):
        raise NoReturn(f"no event within {t_max:g} time units ({sol.message})")
    return sol.y_events[0][0], float(sol.t_events[0][0])


# -- Van der Pol: q̈ = μ (1 − q²) q̇ − q; section q = 0, q̇ > 0 ---------------------------------
def vanderpol(params: Mapping[str, float]) -> HandWritten:
    mu = params["mu"]

    def rhs(t, x):
        q, v = x
        return [v, mu * (1 - q * q) * v - q]

    down = _event(lambda t, x: x[0], -1)  # q = 0 falling: half-way round
    up = _event(lambda t, x: x[0], +1)  # q = 0 rising: back on the section

    def step(x):
        x_half, t_half = _integrate(rhs, x, down, 100.0)
        x_next, t_rest = _integrate(rhs, x_half, up, 100.0)
        return x_next, t_half + t_rest

    return HandWritten(
        "vanderpol", ("q", "q_dot"), ("q_dot",), lambda s: np.array([0.0, s[0]]), step
    )


# -- Rimless wheel: θ̈ = (g/l) sin θ; θ = γ + α strikes; θ⁺ = θ − 2α, θ̇⁺ = cos 2α θ̇ ----------
def rimless_wheel(params: Mapping[str, float]) -> HandWritten:
    g, length, gamma = params["gravity"], params["length"], params["slope"]
    alpha = math.pi / params["spokes"]

    def rhs(t, x):
        return [x[1], g / length * math.sin(x[0])]

    strike = _event(lambda t, x: x[0] - gamma - alpha, +1)

    def step(x):
        (theta, theta_dot), t = _integrate(rhs, x, strike, 100.0)
        return np.array([theta - 2 * alpha, math.cos(2 * alpha) * theta_dot]), t

    return HandWritten(
        "rimless_wheel",
        ("theta", "theta_dot"),
        ("theta_dot",),
        lambda s: np.array([gamma - alpha, s[0]]),
        step,
    )


# -- Compass gait (Goswami, Thuilot & Espiau 1996; Drake's CompassGait) ------------------------
def compass_gait(params: Mapping[str, float]) -> HandWritten:
    """Lagrange's equations ``M(q) q̈ + h(q, q̇) = 0`` with ``q = (stance, swing)``, absolute
    angles from vertical, and Goswami's impact ``Q⁺ q̇⁺ = Q⁻ q̇⁻`` (eq. 8: angular momentum of
    the whole walker about the striking foot, and of the trailing leg about the hip)."""
    mh, m, a, b = params["mass_hip"], params["mass_leg"], params["a"], params["b"]
    g, gamma = params["gravity"], params["slope"]
    l = a + b  # noqa: E741 — leg length, as in Goswami et al.

    def rhs(t, x):
        st, sw, std, swd = x
        c, s = math.cos(st - sw), math.sin(st - sw)
        m11, m12, m22 = (mh + m) * l * l + m * a * a, -m * l * b * c, m * b * b
        h1 = -m * l * b * s * swd * swd - (mh * l + m * (a + l)) * g * math.sin(st)
        h2 = m * l * b * s * std * std + m * b * g * math.sin(sw)
        det = m11 * m22 - m12 * m12
        return [std, swd, (-m22 * h1 + m12 * h2) / det, (m12 * h1 - m11 * h2) / det]

    # Drake's foot-collision witness: falls through 0 at heel strike with the swing foot ahead.
    strike = _event(lambda t, x: max(2 * gamma - x[0] - x[1], x[1] - x[0]), -1)

    def step(x):
        (st, sw, std, swd), t = _integrate(rhs, x, strike, 10.0)
        c = math.cos(st - sw)  # cos 2α, α the half inter-leg angle
        # Goswami's matrices, velocities ordered (non-stance, stance) before and after.
        q_minus = np.array(
            [[-m * a * b, -m * a * b + (mh * l * l + 2 * m * a * l) * c], [0.0, -m * a * b]]
        )
        q_plus = np.array(
            [
                [m * b * (b - l * c), m * l * (l - b * c) + m * a * a + mh * l * l],
                [m * b * b, -m * b * l * c],
            ]
        )
        new_swd, new_std = np.linalg.solve(q_plus, q_minus @ [swd, std])
        return np.array([sw, st, new_std, new_swd]), t  # the legs swap roles

    return HandWritten(
        "compass_gait",
        ("stance", "swing", "stance_dot", "swing_dot"),
        ("stance", "stance_dot", "swing_dot"),
        lambda s: np.array([s[0], 2 * gamma - s[0], s[1], s[2]]),
        step,
    )


# -- Simplest walker (Garcia, Chatterjee, Ruina & Coleman 1998, eqs. 3–6) ----------------------
def simplest_walker(params: Mapping[str, float]) -> HandWritten:
    gamma = params["slope"]

    def rhs(t, x):
        th, ph, thd, phd = x
        thdd = math.sin(th - gamma)
        return [thd, phd, thdd, thdd + math.sin(ph) * (thd * thd - math.cos(th - gamma))]

    mid_stance = _event(lambda t, x: x[0], -1)  # θ = 0: heel strike counts only after this
    strike = _event(lambda t, x: x[1] - 2 * x[0], +1)  # φ − 2θ = 0 rising (eq. 5)

    def step(x):
        x_mid, t_mid = _integrate(rhs, x, mid_stance, 50.0)
        (th, ph, thd, phd), t_rest = _integrate(rhs, x_mid, strike, 50.0)
        c = math.cos(2 * th)
        return np.array([-th, -2 * th, c * thd, c * (1 - c) * thd]), t_mid + t_rest  # eq. (6)

    def lift(s):
        th, thd = s
        return np.array([th, 2 * th, thd, (1 - math.cos(2 * th)) * thd])

    return HandWritten(
        "simplest_walker",
        ("theta", "phi", "theta_dot", "phi_dot"),
        ("theta", "theta_dot"),
        lift,
        step,
    )


BASELINES: dict[str, Callable[[Mapping[str, float]], HandWritten]] = {
    "vanderpol": vanderpol,
    "rimless_wheel": rimless_wheel,
    "compass_gait": compass_gait,
    "simplest_walker": simplest_walker,
}


def baseline(name: str, params: Mapping[str, float]) -> HandWritten | None:
    """The hand-written map of model ``name``, or None if there is none."""
    build = BASELINES.get(name)
    return None if build is None else build(params)


def solve(hw: HandWritten, start: np.ndarray) -> BaselineResult:
    """Fixed point of ``P`` by ``fsolve`` from ``start``, then multipliers by differences."""
    t0 = time.perf_counter()
    count = [0]

    def P(s):
        count[0] += 1
        return hw.return_map(s)

    def residual(s):
        try:
            return P(s) - s
        except NoReturn:
            return np.full(len(s), 1e3)  # push fsolve away from where the walker falls

    try:
        s_star, _, ier, msg = fsolve(
            residual, np.asarray(start, float), xtol=XTOL, full_output=True
        )
        if ier != 1:
            return BaselineResult(
                False,
                f"fsolve: {msg}",
                map_evaluations=count[0],
                solve_time=time.perf_counter() - t0,
            )
        jac = np.empty((len(s_star), len(s_star)))
        for i in range(len(s_star)):
            e = np.zeros(len(s_star))
            e[i] = FD_STEP
            jac[:, i] = (P(s_star + e) - P(s_star - e)) / (2 * FD_STEP)
    except NoReturn as err:
        return BaselineResult(
            False, str(err), map_evaluations=count[0], solve_time=time.perf_counter() - t0
        )
    mult = np.linalg.eigvals(jac).astype(complex)
    mult = mult[np.argsort(-np.abs(mult))]
    elapsed = time.perf_counter() - t0
    x_star = hw.lift(s_star)
    period = hw.step(x_star)[1]  # outside the timed part
    return BaselineResult(
        True,
        "fsolve converged",
        dict(zip(hw.state_names, map(float, x_star), strict=True)),
        mult,
        period,
        count[0],
        elapsed,
    )
