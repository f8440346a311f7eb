"""How the two parameters of a curve enter the model: :class:`ParameterPath` (a scalar ``λ`` that
sets model parameters along an affine path) and :class:`Parametrisation` (the parameter vector
and per-step input as affine functions of the two ``λ``, and their scaling)."""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, field

import numpy as np

from ..errors import GaitoptInputError, ParameterError, did_you_mean
from ..hybrid import HybridModel

__all__ = ["ParameterPath", "Parametrisation"]


@dataclass(frozen=True)
class ParameterPath:
    """A curve parameter: a scalar ``λ`` that sets model parameters along an affine path,
    ``parameter_k = offset_k + slope_k · λ``.

    A model parameter continued by itself is the path ``{name: (0, 1)}`` (see :meth:`of`).

    Attributes
    ----------
    name : str
        Name of the curve parameter (a key of the output points), e.g. ``"mass_ratio"``.
    coefficients : mapping of str to (float, float)
        ``parameter -> (offset, slope)``; at least one slope non-zero.
    unit : str
        Unit of ``λ`` (for plots), e.g. ``"1"`` or ``"m"``.
    doc : str
        What ``λ`` is.

    Examples
    --------
    The compass gait's leg-mass position with the leg length held at 1 m, ``b = 1 − a``::

        ParameterPath("a", {"a": (0.0, 1.0), "b": (1.0, -1.0)}, unit="m")
    """

    name: str
    coefficients: Mapping[str, tuple[float, float]]
    unit: str = ""
    doc: str = ""
    _items: tuple[tuple[str, float, float], ...] = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        if not isinstance(self.name, str) or not self.name:
            raise GaitoptInputError(f"ParameterPath: `name` must be a non-empty string, got "
                                    f"{self.name!r}")  # fmt: skip
        items = []
        for key, pair in dict(self.coefficients).items():
            try:
                offset, slope = (float(v) for v in pair)
            except (TypeError, ValueError):
                raise GaitoptInputError(
                    f"ParameterPath {self.name}: coefficients[{key!r}] must be (offset, slope), "
                    f"got {pair!r}"
                ) from None
            if not (math.isfinite(offset) and math.isfinite(slope)):
                raise GaitoptInputError(
                    f"ParameterPath {self.name}: coefficients[{key!r}] = {pair!r} is not finite"
                )
            items.append((str(key), offset, slope))
        if not any(s != 0 for _, _, s in items):
            raise GaitoptInputError(
                f"ParameterPath {self.name}: no coefficient has a non-zero slope; e.g. "
                f"{{'{self.name}': (0, 1)}}"
            )
        object.__setattr__(self, "_items", tuple(items))

    @classmethod
    def of(cls, model: HybridModel, name: str) -> ParameterPath:
        """The path of one model parameter ``name`` (checked: real-valued, known)."""
        specs = {s.name: s for s in model.parameter_specs()}
        if name not in specs:
            raise ParameterError(
                f"{model.name}: unknown parameter {name!r}; {did_you_mean(name, specs)}"
                f"parameters: {', '.join(specs)}"
            )
        if specs[name].integer:
            raise ParameterError(
                f"{model.name}: parameter `{name}` takes integer values and cannot be continued"
            )
        return cls(name, {name: (0.0, 1.0)}, unit=specs[name].unit, doc=specs[name].doc)

    @property
    def parameters(self) -> tuple[str, ...]:
        """The model parameters the path sets."""
        return tuple(k for k, _, _ in self._items)

    def values(self, value: float) -> dict[str, float]:
        """The model parameters at ``λ = value``."""
        return {k: offset + slope * float(value) for k, offset, slope in self._items}

    def value_of(self, model: HybridModel) -> float:
        """``λ`` of a model on the path; raises if the model is not on it."""
        key, offset, slope = next(it for it in self._items if it[2] != 0)
        value = (float(getattr(model, key)) - offset) / slope
        for k, v in self.values(value).items():
            have = float(getattr(model, k))
            if abs(have - v) > 1e-12 * (1 + abs(v)):
                raise GaitoptInputError(
                    f"ParameterPath {self.name}: the model's {k} = {have:g} is not on the path "
                    f"(expected {v:g} at {self.name} = {value:g}); set {k}={v:g}"
                )
        return value


@dataclass(frozen=True)
class Parametrisation:
    """How the two curve parameters set the parameter vector and the per-step input:
    ``p = p_base + K λ``, ``u = u_base + D λ`` (affine, exact), ``λ = scale ⊙ ℓ``."""

    model: HybridModel
    paths: tuple[ParameterPath, ParameterPath]
    p_base: np.ndarray
    K: np.ndarray
    u_base: np.ndarray
    D: np.ndarray
    scale: np.ndarray
    lam0: np.ndarray

    @classmethod
    def build(
        cls, model: HybridModel, paths: tuple[ParameterPath, ParameterPath], u0: np.ndarray
    ) -> Parametrisation:
        names = [s.name for s in model.parameter_specs()]
        touched = [k for path in paths for k in path.parameters]
        for k in touched:
            if k not in names:
                raise ParameterError(
                    f"{model.name}: unknown parameter {k!r} in a parameter path; "
                    f"{did_you_mean(k, names)}parameters: {', '.join(names)}"
                )
        if len(set(touched)) != len(touched):
            raise GaitoptInputError(
                f"the two curve parameters {paths[0].name!r} and {paths[1].name!r} set the same "
                f"model parameter; choose two independent parameters"
            )
        lam0 = np.array([path.value_of(model) for path in paths])
        p_base = model.p.copy()
        K = np.zeros((len(names), 2))
        for i, path in enumerate(paths):
            for k, offset, slope in path._items:
                p_base[names.index(k)] = offset
                K[names.index(k), i] = slope
        u0 = np.asarray(u0, dtype=float)
        D = np.zeros((u0.size, 2))
        nominal = model.nominal_input()
        if u0.size and np.allclose(u0, nominal, rtol=1e-9, atol=1e-12):
            # A nominal input that is a parameter (the SLIP's touchdown angle) moves with it;
            # nominal inputs are affine in the parameters (as in gaitopt.continuation), so a
            # large difference step is exact up to rounding.
            u0 = nominal
            for i, path in enumerate(paths):
                h = 1e-2 * max(abs(lam0[i]), 1e-3)
                try:
                    up = model.replace(**path.values(lam0[i] + h)).nominal_input()
                    D[:, i] = (up - nominal) / h
                except ParameterError:
                    down = model.replace(**path.values(lam0[i] - h)).nominal_input()
                    D[:, i] = (nominal - down) / h
        u_base = u0 - D @ lam0
        scale = np.maximum(np.abs(lam0), 1e-3)
        return cls(model, paths, p_base, K, u_base, D, scale, lam0)

    def p(self, lam: np.ndarray) -> np.ndarray:
        """Parameter vector at ``λ``."""
        return self.p_base + self.K @ np.asarray(lam, dtype=float)

    def u(self, lam: np.ndarray) -> np.ndarray:
        """Per-step input at ``λ``."""
        return self.u_base + self.D @ np.asarray(lam, dtype=float)

    def model_at(self, lam: np.ndarray) -> HybridModel | None:
        """The model at ``λ``, or None where a parameter leaves its valid range."""
        changes: dict[str, float] = {}
        for path, value in zip(self.paths, lam, strict=True):
            changes.update(path.values(value))
        try:
            return self.model.replace(**changes)
        except ParameterError:
            return None

    def inputs(self) -> dict[str, np.ndarray]:
        """The numeric inputs of the augmented function (everything but ``w, ℓ, b, c``)."""
        return {"p_base": self.p_base, "K": self.K, "u_base": self.u_base, "D": self.D,
                "scale": self.scale}  # fmt: skip
