"""Rough terrain and blind running: seeded random ground per step, and the swing-leg law that
makes the SLIP's touchdown angle deadbeat at whatever height the ground turns out to be.

Terrain (for :func:`gaitopt.simulate`'s ``terrain`` option): :class:`RandomTerrain` draws, for
each step, the ground parameter (the SLIP's ``ground_height``, a walker's ``slope``) uniformly
within ``± amplitude`` of its nominal value, from a seeded generator, so a run is reproducible.

Blind running (Ernst, Geyer & Blickhan 2009, "Spring-legged locomotion on uneven ground: a
control approach to keep the running speed constant"; Tedrake, *Underactuated Robotics*, SLIP
section, "deadbeat control on rough terrain"): at an apex of height ``z_a`` the runner cannot
see the ground, but its descent is ballistic, so the time since apex ``t`` at which the foot meets
the ground fixes the ground height: with the leg at angle ``θ(t)``, touchdown at time ``t`` means
the ground is at ``h = z_a − g t²/2 − l0 cos θ(t)``.  :func:`blind_swing_law` tabulates, for
ground heights ``h_j`` over a range, the deadbeat angle ``θ_j`` (``P(z_a, θ_j; h_j) = z*``, by the
deadbeat rootfinder with the ground known) and its touchdown time ``t_j``, and fits the law
``θ(t)`` through the points ``(t_j, θ_j)`` (Chebyshev, degree 8).  Swinging the leg along that
law (:class:`gaitopt.models.slip.SlipSwingLeg`), the runner touches down with the deadbeat angle
for any ground in the range, without knowing where the ground is.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field

import numpy as np
from numpy.polynomial import chebyshev

from .control import Deadbeat, StepController
from .errors import GaitoptInputError
from .hybrid import HybridModel
from .models.slip import SWING_LAW_DEGREE, Slip, SlipSwingLeg

__all__ = [
    "RandomTerrain",
    "random_terrain",
    "terrain_parameter",
    "SwingLaw",
    "blind_swing_law",
    "BlindPolicy",
]

_GROUND_PARAMETERS = ("ground_height", "slope")


def terrain_parameter(model: HybridModel) -> str:
    """The parameter that describes the ground under a step: ``ground_height`` or ``slope``.

    Raises
    ------
    GaitoptInputError
        If the model has neither.
    """
    for name in _GROUND_PARAMETERS:
        if name in model.params:
            return name
    raise GaitoptInputError(
        f"{model.name} has no ground parameter ({' or '.join(_GROUND_PARAMETERS)}): "
        f"rough terrain is not defined for it"
    )


@dataclass
class RandomTerrain:
    """``terrain(step) -> {parameter: nominal + U(−amplitude, amplitude)}``, seeded.

    Attributes
    ----------
    parameter : str
        The ground parameter changed per step.
    nominal : float
        Its nominal value.
    amplitude : float
        Half-width of the uniform distribution (same unit as the parameter).
    seed : int
        Seed of :func:`numpy.random.default_rng`; step k's value is the k-th draw.
    """

    parameter: str
    nominal: float
    amplitude: float
    seed: int
    _values: list[float] = field(default_factory=list, repr=False)

    def value(self, step: int) -> float:
        """The parameter's value for ``step``."""
        if not self._values or len(self._values) <= step:
            rng = np.random.default_rng(self.seed)
            n = max(step + 1, 2 * len(self._values), 64)
            self._values = list(self.nominal + self.amplitude * rng.uniform(-1.0, 1.0, n))
        return self._values[step]

    def __call__(self, step: int) -> Mapping[str, float]:
        return {self.parameter: self.value(step)}


def random_terrain(
    model: HybridModel, seed: int, amplitude: float, *, parameter: str | None = None
) -> RandomTerrain:
    """Seeded random ground for :func:`gaitopt.simulate`: each step's ground parameter drawn
    uniformly within ``± amplitude`` of the model's value.

    Raises
    ------
    GaitoptInputError
        If ``amplitude`` is negative or not finite, or the model has no ground parameter.
    """
    name = parameter or terrain_parameter(model)
    if name not in model.params:
        raise GaitoptInputError(f"`parameter` {name!r} is not a parameter of {model.name}")
    if not (np.isfinite(amplitude) and amplitude >= 0):
        raise GaitoptInputError(f"`amplitude` must be finite and ≥ 0, got {amplitude!r}")
    return RandomTerrain(name, float(model.params[name]), float(amplitude), int(seed))


# -- blind running ------------------------------------------------------------------------------
@dataclass
class SwingLaw:
    """A swing-leg law ``θ(t)`` (rad) of the time since apex, and how well it is deadbeat.

    Attributes
    ----------
    inputs : numpy.ndarray
        The per-step input of :class:`SlipSwingLeg`: ``t_center, t_halfwidth, c0 … c8``.
    times, angles, heights : numpy.ndarray
        The tabulated deadbeat points: touchdown time (s), angle (rad), ground height (m).
    fit_error : float
        Largest |θ(t) − θ_deadbeat| (rad) over the tabulated points and the midpoints between
        them (the midpoints solved afresh).
    success : bool
        Every tabulated height had a deadbeat angle.
    message : str
        What the law covers.
    """

    inputs: np.ndarray
    times: np.ndarray
    angles: np.ndarray
    heights: np.ndarray
    fit_error: float
    success: bool
    message: str

    def angle(self, t: float | np.ndarray) -> np.ndarray:
        """``θ(t)`` (rad), held at its end values outside the fitted window."""
        tc, tw = self.inputs[0], self.inputs[1]
        xi = np.clip((np.asarray(t, dtype=float) - tc) / tw, -1.0, 1.0)
        return chebyshev.chebval(xi, self.inputs[2:])


def blind_swing_law(
    solver: Deadbeat,
    z_apex: float,
    *,
    target: float | None = None,
    heights: tuple[float, float] = (-0.1, 0.1),
    nodes: int = 17,
    check: bool = True,
) -> SwingLaw:
    """The swing-leg law from apex ``z_apex`` that is deadbeat (next apex ``target``) for every
    ground height in ``heights``.

    Parameters
    ----------
    solver : Deadbeat
        The SLIP's deadbeat rootfinder (``deadbeat(model).deadbeat_solver``).
    z_apex : float
        Height of the current apex (m, absolute).
    target : float, optional
        Next apex height wanted (m, absolute); default the gait's.
    heights : (low, high)
        Ground heights (m) the law must cover.
    nodes : int
        Chebyshev nodes in ``heights`` (deadbeat solves); the fit has degree
        :data:`SWING_LAW_DEGREE`.
    check : bool
        Also solve at the midpoints between nodes to measure the fit error.
    """
    model = solver.model
    if not isinstance(model, Slip):
        raise GaitoptInputError(f"blind running needs the slip model, got {model.name}")
    lo, hi = map(float, heights)
    if not lo < hi:
        raise GaitoptInputError(f"`heights` must be increasing, got {heights!r}")
    s_t = solver.cycle.section_point if target is None else np.array([float(target)])
    k = np.arange(nodes)
    grid = 0.5 * (lo + hi) - 0.5 * (hi - lo) * np.cos(np.pi * (k + 0.5) / nodes)
    if check:
        grid = np.sort(np.concatenate([grid, 0.5 * (grid[1:] + grid[:-1])]))
    p_index = [s.name for s in model.parameter_specs()].index("ground_height")
    g, l0 = model.gravity, model.rest_length

    def solve(h: float, guess):
        p = model.p.copy()
        p[p_index] = h
        return solver.solve([z_apex], target=s_t, p=p, guess=guess)

    # Solve outwards from the nominal ground so each solve warm-starts the next.
    order = np.argsort(np.abs(grid - model.ground_height))
    angles = np.full(grid.size, np.nan)
    last = {+1: None, -1: None}
    for j in order:
        side = 1 if grid[j] >= model.ground_height else -1
        decision = solve(grid[j], last[side])
        if decision.success:
            angles[j] = float(decision.input[0])
            last[side] = solver.last_solution.copy()
    ok = np.isfinite(angles)
    times = np.full(grid.size, np.nan)
    drop = z_apex - grid - l0 * np.cos(angles)
    times[ok] = np.sqrt(np.maximum(2 * drop[ok] / g, 0.0))
    fit_points = ok if not check else ok & np.isin(np.arange(grid.size), np.arange(0, grid.size, 2))
    if fit_points.sum() < SWING_LAW_DEGREE + 1:
        nominal = np.zeros(SWING_LAW_DEGREE + 3)
        nominal[0], nominal[1], nominal[2] = 0.2, 0.1, float(solver.cycle.inputs[0])
        return SwingLaw(
            nominal,
            times,
            angles,
            grid,
            float("inf"),
            False,
            f"no deadbeat angle for most ground heights in [{lo:g}, {hi:g}] m from apex "
            f"z = {z_apex:.6g} m; the nominal touchdown angle is held",
        )
    t_fit, a_fit = times[fit_points], angles[fit_points]
    t_lo, t_hi = float(t_fit.min()), float(t_fit.max())
    tc, tw = 0.5 * (t_lo + t_hi), max(0.5 * (t_hi - t_lo), 1e-9)
    coef = chebyshev.chebfit((t_fit - tc) / tw, a_fit, SWING_LAW_DEGREE)
    law = SwingLaw(np.concatenate([[tc, tw], coef]), times, angles, grid, 0.0, True, "")
    error = float(np.max(np.abs(law.angle(times[ok]) - angles[ok])))
    law.fit_error = error
    covered = grid[ok]
    law.success = bool(ok.all())
    law.message = (
        f"deadbeat for ground heights in [{covered.min():.4g}, {covered.max():.4g}] m "
        f"(touchdown {t_lo:.4g}–{t_hi:.4g} s after the apex); fit error {error:.2g} rad"
        + ("" if law.success else f"; no deadbeat angle for {int((~ok).sum())} of the heights")
    )
    return law


@dataclass
class BlindPolicy:
    """Policy for :func:`gaitopt.simulate` on :class:`SlipSwingLeg`: at each apex, the swing-leg
    law (:func:`blind_swing_law`) from that apex height back to the target.

    Attributes
    ----------
    controller : StepController
        A SLIP deadbeat controller (its rootfinder and target).
    heights : (low, high)
        Ground heights the law covers (m).
    laws : list of SwingLaw
        The laws used, one per step.
    """

    controller: StepController
    heights: tuple[float, float] = (-0.1, 0.1)
    nodes: int = 17
    laws: list[SwingLaw] = field(default_factory=list)

    def __post_init__(self) -> None:
        if self.controller.deadbeat_solver is None:
            raise GaitoptInputError("`controller` must be a deadbeat controller (kind 'deadbeat')")

    def model(self) -> SlipSwingLeg:
        """The SLIP with a swing-leg law, with the controller's parameters."""
        return SlipSwingLeg(**self.controller.model.params)

    def __call__(self, step: int, x: np.ndarray) -> np.ndarray:
        z = float(np.asarray(x, dtype=float)[1])
        law = blind_swing_law(
            self.controller.deadbeat_solver,
            z,
            target=float(self.controller.target[0]),
            heights=self.heights,
            nodes=self.nodes,
            check=False,
        )
        self.laws.append(law)
        return law.inputs
