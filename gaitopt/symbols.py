"""The symbols a model's ``build`` works with (:class:`Symbols`): its parameters and inputs as
CasADi symbols, and helpers that make its functions."""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import casadi as ca

from .parameters import ParameterSpec
from .phases import Constraint

__all__ = ["Symbols"]


class Symbols:
    """Symbolic parameters and helpers for a model's ``build`` classmethod.

    ``sym.p`` is the parameter vector (CasADi SX); ``sym.slope`` etc. its named entries (a
    parameter wins over an input of the same name); ``sym.u`` the per-step input vector and
    ``sym.input(name)`` one of its entries.
    """

    def __init__(self, specs: Sequence[ParameterSpec], inputs: Sequence[str]):
        self.p = ca.SX.sym("p", len(specs))
        self.u = ca.SX.sym("u", len(inputs))
        self._names = {s.name: i for i, s in enumerate(specs)}
        self._inputs = {name: i for i, name in enumerate(inputs)}

    def __getattr__(self, name: str) -> ca.SX:
        if name.startswith("_"):
            raise AttributeError(name)
        if name in self._names:
            return self.p[self._names[name]]
        if name in self._inputs:
            return self.u[self._inputs[name]]
        raise AttributeError(f"model has no parameter or input named {name!r}")

    def input(self, name: str) -> ca.SX:
        """The per-step input ``name`` (unambiguous where a parameter has the same name, as the
        SLIP's touchdown angle: ``sym.touchdown_angle`` is the parameter)."""
        if name not in self._inputs:
            raise AttributeError(f"model has no per-step input named {name!r}")
        return self.u[self._inputs[name]]

    @staticmethod
    def states(*names: str) -> tuple[ca.SX, list[ca.SX]]:
        """A state vector and its named elements."""
        x = ca.SX.sym("x", len(names))
        return x, [x[i] for i in range(len(names))]

    def function(self, name: str, x: ca.SX, expr: Any) -> ca.Function:
        """``name(x, u, p) -> expr``."""
        return ca.Function(name, [x, self.u, self.p], [ca.SX(expr)], ["x", "u", "p"], [name])

    def constraint(
        self, name: str, x: ca.SX, expr: Any, outcome: str, **options: Any
    ) -> Constraint:
        """The unilateral condition ``expr ≥ 0`` (see :class:`Constraint` for ``options``)."""
        return Constraint(name, self.function("constraint", x, expr), outcome, **options)

    def conserved(self, name: str, x: ca.SX, expr: Any) -> ca.Function:
        """``name(x, p) -> expr`` (no input: conserved only along the passive flow)."""
        return ca.Function(name, [x, self.p], [ca.SX(expr)], ["x", "p"], [name])

    def lift(self, s: ca.SX, x_expr: Any) -> ca.Function:
        """``lift(s, p) -> x``."""
        return ca.Function("lift", [s, self.p], [ca.SX(x_expr)], ["s", "p"], ["x"])
