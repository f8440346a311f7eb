"""The shooting residual and its Jacobians assembled in NumPy from the per-segment blocks.

Equations and unknowns are those of :class:`gaitopt.shooting.ShootingProblem` (same order): per
phase of the chain, the gaps between segments, the guard at the phase end, the reset linking to
the next phase; then periodicity ``P − s``.  Each segment end ``x_e = Φ(x_start, u, p, T/S)``
contributes its block ``∂Φ/∂[x_start; u; p; hs]`` (``hs = T/S``, so ``∂/∂T = ∂/∂hs / S``); the
first segment start of the chain is ``lift(s, p)``, contributing ``∂lift/∂s`` and ``∂lift/∂p``.

An :class:`Assembly` is evaluated in one C call of the compiled Newton's library where there is
one (:mod:`gaitopt.kernels.newton`: these blocks, the kernels called by address), else as one
CasADi MX function (:meth:`Assembly._assembled`), else block by block in NumPy
(:meth:`Assembly._assemble`, the reference the other two are tested against).
"""

from __future__ import annotations

import threading

import casadi as ca
import numpy as np

from ..fastcall import call
from . import model_kernels, phase_function, phase_residual_function
from .evaluation import Evaluation

__all__ = ["Evaluation", "Assembly"]


class Assembly:
    """The assembled shooting system of a problem (see the module docstring)."""

    def __init__(self, problem, rk_steps: int | None = None):
        kern = model_kernels(problem.model_cls)
        if kern is None:
            raise NotImplementedError("no kernels for this model class")
        self.compiled = kern.compiled
        self.lift = kern.lift
        S = problem.disc.segments
        N = problem.disc.rk_steps if rk_steps is None else rk_steps
        self.S, self.chain, self.m = S, problem.chain, problem.m
        self.size, self.section_index = problem.size, problem.section_index
        phase = {i: phase_function(problem.model_cls, i, S, N) for i in set(self.chain)}
        self.n = [kern.n[i] for i in self.chain]
        self.n_u, self.n_p = kern.n_u, kern.n_p
        # (node offset, duration offset) of each chain element
        self.offsets = [
            (problem.layout[2 * k][2], problem.layout[2 * k + 1][2]) for k in range(len(self.chain))
        ]
        self._model_cls, self._N = problem.model_cls, N
        # One call evaluates the whole chain (one flat output: a call from Python costs more
        # than the kernels of a small model).
        self.chain_function, self.shapes = self._chain(phase)
        # The residual alone (``jacobian=False``), built on first use: the RK steps without
        # their derivatives, the segments' ``D`` left out of the output.
        self._residual: tuple[ca.Function, list] | None = None
        self._buffers = threading.local()

    def compiled_newton(self):
        """The compiled Newton on this system (:class:`gaitopt.kernels.newton.CompiledNewton`),
        built on first use, or None where it cannot be (no compiler, kernels not compiled)."""
        if "_compiled_newton" not in self.__dict__:
            from .newton import CompiledNewton

            self.__dict__["_compiled_newton"] = CompiledNewton.build(self)
        return self.__dict__["_compiled_newton"]

    def _chain(self, phase: dict) -> tuple[ca.Function, list]:
        """The chain's function of ``phase`` (per phase index, a :func:`phase_function` or
        :func:`phase_residual_function`) and its outputs' shapes."""
        S, m = self.S, self.m
        w = ca.MX.sym("w", self.size)
        u, p = ca.MX.sym("u", self.n_u), ca.MX.sym("p", self.n_p)
        outs = list(self.lift(w[:m], p))
        for k, i in enumerate(self.chain):
            n, (off, off_T) = self.n[k], self.offsets[k]
            if k == 0:
                X = ca.horzcat(outs[0], ca.reshape(w[off : off + n * (S - 1)], n, S - 1))
            else:
                X = ca.reshape(w[off : off + n * S], n, S)
            outs += list(phase[i](X, u, p, w[off_T] / S))
        shapes = [o.shape for o in outs]
        return ca.Function("chain", [w, u, p], [ca.vertcat(*map(ca.vec, outs))]), shapes

    def _residual_chain(self) -> tuple[ca.Function, list] | None:
        if self._residual is None:
            phase = {
                i: phase_residual_function(self._model_cls, i, self.S, self._N)
                for i in set(self.chain)
            }
            self._residual = (None, []) if None in phase.values() else self._chain(phase)
        return None if self._residual[0] is None else self._residual

    def __getstate__(self) -> dict:
        # Buffers are per thread; the assembled functions are rebuilt where they are used.
        skip = ("_buffers", "_assembled_jac", "_assembled_res", "_compiled_newton")
        return {k: v for k, v in self.__dict__.items() if k not in skip}

    def __setstate__(self, state: dict) -> None:
        self.__dict__.update(state, _buffers=threading.local())

    def _call(self, f: ca.Function, w, u, p) -> np.ndarray:
        """``f``'s (dense, column-major) output, through a per-thread CasADi buffer
        (``Function.buffer``: no DM built per call) where the arguments fit it."""
        buffers = self._buffers.__dict__
        if id(f) not in buffers:  # f lives as long as self (its chain or residual chain)
            args = [np.zeros(f.nnz_in(i)) for i in range(3)]
            res = np.zeros(f.nnz_out(0))
            buf, call = f.buffer()
            for i, a in enumerate(args):
                buf.set_arg(i, memoryview(a))
            buf.set_res(0, memoryview(res))
            nz = np.array(f.sparsity_out(0).find(), dtype=np.intp)
            buffers[id(f)] = (call, buf, args, res, nz, f.numel_out(0))
        call, _, args, res, nz, numel = buffers[id(f)]
        values = [np.asarray(v, dtype=float).ravel() for v in (w, u, p)]
        if any(v.size != a.size or a.size == 0 for v, a in zip(values, args, strict=True)):
            return np.asarray(f(w, u, p), dtype=float).ravel(order="F")
        for a, v in zip(args, values, strict=True):
            a[:] = v
        call()
        flat = np.zeros(numel)
        flat[nz] = res
        return flat

    def _outputs(self, w, u, p, jacobian: bool = True) -> list[np.ndarray | None]:
        residual = None if jacobian else self._residual_chain()
        f, shapes = residual or (self.chain_function, self.shapes)
        flat = self._call(f, w, u, p)
        out, at = [], 0
        for j, (rows, cols) in enumerate(shapes):
            # The residual alone reads the lift's x and each phase's X_end, g, r, ġ, admissible.
            used = residual is None or j == 0 or (j >= 3 and (j - 3) % 11 in (0, 1, 5, 9, 10))
            out.append(flat[at : at + rows * cols].reshape(rows, cols, order="F") if used else None)
            at += rows * cols
        if residual is not None:  # no segment derivatives D: None in their place
            for k in range(len(self.chain)):
                out.insert(4 + 12 * k, None)
        return out

    def __call__(self, w, u, p, *, jacobian: bool = True) -> Evaluation:
        w = np.asarray(w, dtype=float).ravel()
        u = np.asarray(u, dtype=float).ravel()
        p = np.asarray(p, dtype=float).ravel()
        if w.size == self.size and u.size == self.n_u and p.size == self.n_p and self.size:
            compiled = self.compiled_newton()
            if compiled is not None:  # the same blocks in one C call (kernels/newton.py)
                try:
                    return compiled.evaluate(w, u, p, jacobian=jacobian)
                except RuntimeError:  # a kernel failed: the CasADi evaluation says how
                    pass
            f = self._assembled(jacobian)
            if f is not None:
                return self._read(f, w, u, p, jacobian)
        # A diverging Newton iterate gives non-finite blocks: reported by the caller, not warned.
        with np.errstate(invalid="ignore", over="ignore", divide="ignore"):
            return self._assemble(w, u, p, jacobian)

    # -- the assembly as one CasADi call -------------------------------------------------------
    def _assembled(self, jacobian: bool) -> ca.Function | None:
        """``(w, u, p) -> (F, F_w, F_u, F_p, x_return, ends, rates, admissible)`` (without
        the three Jacobians for ``jacobian=False``): the chain's call and :meth:`_assemble`'s
        arithmetic as one MX function, evaluated through one buffer (no NumPy per block)."""
        key = "_assembled_jac" if jacobian else "_assembled_res"
        if key not in self.__dict__:
            chain = (self.chain_function, self.shapes) if jacobian else self._residual_chain()
            self.__dict__[key] = None if chain is None else self._symbolic(chain, jacobian)
        return self.__dict__[key]

    def _symbolic(self, chain: tuple[ca.Function, list], jacobian: bool) -> ca.Function:
        f, shapes = chain
        w = ca.MX.sym("w", self.size)
        u, p = ca.MX.sym("u", self.n_u), ca.MX.sym("p", self.n_p)
        offsets = np.cumsum([0] + [rows * cols for rows, cols in shapes]).tolist()
        pieces = ca.vertsplit(f(w, u, p), offsets)  # one split (slices cost ms each to build)
        outputs = [
            v if v.size2() == cols else ca.reshape(v, rows, cols)
            for v, (rows, cols) in zip(pieces, shapes, strict=True)
        ]
        if not jacobian:  # the residual chain has no D: a placeholder where _blocks reads it
            for k in range(len(self.chain)):
                outputs.insert(4 + 12 * k, None)
        F, J, Ju, Jp, x_return, ends, rates, adm = _blocks(self, w, outputs, jacobian)
        out = [F, *((J, Ju, Jp) if jacobian else ()), x_return, ca.vertcat(*ends), rates, adm]
        return ca.Function("assembled" if jacobian else "assembled_residual", [w, u, p],
                           [ca.densify(o) for o in out])  # fmt: skip

    def _read(self, f: ca.Function, w, u, p, jacobian: bool) -> Evaluation:
        out = call(f, w, u, p)
        F = out[0].ravel()
        J, Ju, Jp = out[1:4] if jacobian else (None, None, None)
        x_return, ends, rates, adm = (v.ravel() for v in out[-4:])
        split, at = [], 0
        for n in self.n:
            split.append(ends[at : at + n])
            at += n
        durations = w[[off_T for _, off_T in self.offsets]]
        return Evaluation(F, J, Ju, Jp, x_return, split, rates, adm, durations)

    def _assemble(self, w, u, p, jacobian: bool) -> Evaluation:
        w = np.asarray(w, dtype=float).ravel()
        u = np.asarray(u, dtype=float).ravel()
        p = np.asarray(p, dtype=float).ravel()
        S, m, size, nu, np_ = self.S, self.m, self.size, self.n_u, self.n_p
        F = np.empty(size)
        J = np.zeros((size, size)) if jacobian else None
        Ju = np.zeros((size, nu)) if jacobian else None
        Jp = np.zeros((size, np_)) if jacobian else None
        outputs = self._outputs(w, u, p, jacobian)
        x_lift, L_s, L_p = outputs[:3]
        x_lift = x_lift.ravel()
        K = len(self.chain)
        ends, rates, adm, durations = [], np.empty(K), np.empty(K), np.empty(K)
        row = 0
        for k in range(K):
            n = self.n[k]
            off, off_T = self.offsets[k]
            if k == 0:
                X = np.column_stack(
                    [x_lift, w[off : off + n * (S - 1)].reshape(n, S - 1, order="F")]
                )
            else:
                X = w[off : off + n * S].reshape(n, S, order="F")
            T = w[off_T]
            X_end, Ds, g, g_x, g_u, g_p, r, r_x, r_u, r_p, rate, a = outputs[
                3 + 12 * k : 15 + 12 * k
            ]
            q = n + nu + np_ + 1
            durations[k], rates[k], adm[k] = T, float(rate.ravel()[0]), float(a.ravel()[0])
            ends.append(X_end[:, -1])

            def start_col(j: int, k: int = k, off: int = off, n: int = n) -> int | None:
                """Column of ``w`` where segment start j's block begins (None: the lift)."""
                if k == 0:
                    return None if j == 0 else off + n * (j - 1)
                return off + n * j

            def add_state(R: slice, j: int, M: np.ndarray, n: int = n, start_col=start_col) -> None:
                """Add ``M · ∂(segment start j)/∂(w, p)`` to the rows ``R``."""
                c = start_col(j)
                if c is None:
                    J[R, :m] += M @ L_s
                    Jp[R] += M @ L_p
                else:
                    J[R, c : c + n] += M

            # -- close the gaps ------------------------------------------------------------
            F[row : row + n * (S - 1)] = (X[:, 1:] - X_end[:, :-1]).ravel(order="F")
            if jacobian:
                eye = np.eye(n)
                for j in range(S - 1):
                    R = slice(row + j * n, row + (j + 1) * n)
                    D = Ds[:, j * q : (j + 1) * q]
                    add_state(R, j + 1, eye)
                    add_state(R, j, -D[:, :n])
                    J[R, off_T] -= D[:, -1] / S
                    Ju[R] -= D[:, n : n + nu]
                    Jp[R] -= D[:, n + nu : n + nu + np_]
            row += n * (S - 1)
            # -- the end state's derivative, for the guard, the link and periodicity -------
            if jacobian:
                D = Ds[:, (S - 1) * q :]
                E = np.zeros((n, size))
                E_p = D[:, n + nu : n + nu + np_].copy()
                c = start_col(S - 1)
                if c is None:
                    E[:, :m] = D[:, :n] @ L_s
                    E_p += D[:, :n] @ L_p
                else:
                    E[:, c : c + n] = D[:, :n]
                E[:, off_T] += D[:, -1] / S
                E_u = D[:, n : n + nu]
            g = g.ravel()
            R = slice(row, row + g.size)
            F[R] = g
            if jacobian:
                J[R] += g_x @ E
                Ju[R] += g_x @ E_u + g_u
                Jp[R] += g_x @ E_p + g_p
            row += g.size
            r = r.ravel()
            if k + 1 < K:
                n1 = self.n[k + 1]
                off1 = self.offsets[k + 1][0]
                R = slice(row, row + n1)
                F[R] = w[off1 : off1 + n1] - r
                if jacobian:
                    J[R, off1 : off1 + n1] += np.eye(n1)
                    J[R] -= r_x @ E
                    Ju[R] -= r_x @ E_u + r_u
                    Jp[R] -= r_x @ E_p + r_p
                row += n1
            else:
                x_return = r
                sec = self.section_index
                R = slice(row, row + m)
                F[R] = r[sec] - w[:m]
                if jacobian:
                    J[R] += (r_x @ E)[sec]
                    J[R, :m] -= np.eye(m)
                    Ju[R] += (r_x @ E_u + r_u)[sec]
                    Jp[R] += (r_x @ E_p + r_p)[sec]
                row += m
        assert row == size
        return Evaluation(F, J, Ju, Jp, x_return, ends, rates, adm, durations)


def _placed(block, col: int, width: int):
    """``block`` at columns ``col…`` of a ``width``-column matrix (structural zeros elsewhere)."""
    rows, cols = block.size1(), block.size2()
    left, right = ca.MX(rows, col), ca.MX(rows, width - col - cols)
    return ca.horzcat(left, block, right)


def _blocks(asm: Assembly, w: ca.MX, outputs: list, jacobian: bool) -> tuple:
    """:meth:`Assembly._assemble`'s equations and Jacobians on the chain's MX outputs (the same
    blocks, row block by row block, each a sum of blocks placed at their columns: no slice
    assignment, whose MX graphs take milliseconds each to build): ``(F, F_w, F_u, F_p,
    x_return, ends, rates, admissible)``."""
    S, m, size, nu, np_ = asm.S, asm.m, asm.size, asm.n_u, asm.n_p
    K = len(asm.chain)
    F: list = []
    J_rows: list = []
    Ju_rows: list = []
    Jp_rows: list = []
    x_lift, L_s, L_p = outputs[:3]
    ends, rates, adm = [], [], []
    x_return = None
    for k in range(K):
        n = asm.n[k]
        off, off_T = asm.offsets[k]
        if k == 0:
            X = ca.horzcat(x_lift, ca.reshape(w[off : off + n * (S - 1)], n, S - 1))
        else:
            X = ca.reshape(w[off : off + n * S], n, S)
        X_end, Ds, g, g_x, g_u, g_p, r, r_x, r_u, r_p, rate, a = outputs[3 + 12 * k : 15 + 12 * k]
        q = n + nu + np_ + 1
        rates.append(rate)
        adm.append(a)
        ends.append(X_end[:, -1])

        def start_col(j: int, k: int = k, off: int = off, n: int = n) -> int | None:
            if k == 0:
                return None if j == 0 else off + n * (j - 1)
            return off + n * j

        def state(j: int, M, start_col=start_col) -> tuple:
            """``M · ∂(segment start j)/∂(w, p)``: (its w-columns, its p-columns or None)."""
            c = start_col(j)
            if c is None:
                return _placed(ca.mtimes(M, L_s), 0, size), ca.mtimes(M, L_p)
            return _placed(M, c, size), None

        F.append(ca.vec(X[:, 1:] - X_end[:, :-1]))
        if jacobian:
            for j in range(S - 1):
                D = Ds[:, j * q : (j + 1) * q]
                J1, P1 = state(j + 1, ca.DM.eye(n))
                J0, P0 = state(j, -D[:, :n])
                J_rows.append(J1 + J0 - _placed(D[:, -1] / S, off_T, size))
                Ju_rows.append(-D[:, n : n + nu])
                Jp = -D[:, n + nu : n + nu + np_]
                for extra in (P1, P0):
                    Jp = Jp if extra is None else Jp + extra
                Jp_rows.append(Jp)
            D = Ds[:, (S - 1) * q :]
            E_p = D[:, n + nu : n + nu + np_]
            c = start_col(S - 1)
            if c is None:
                E = _placed(ca.mtimes(D[:, :n], L_s), 0, size)
                E_p = E_p + ca.mtimes(D[:, :n], L_p)
            else:
                E = _placed(D[:, :n], c, size)
            E = E + _placed(D[:, -1] / S, off_T, size)
            E_u = D[:, n : n + nu]
        F.append(ca.vec(g))
        if jacobian:
            J_rows.append(ca.mtimes(g_x, E))
            Ju_rows.append(ca.mtimes(g_x, E_u) + g_u)
            Jp_rows.append(ca.mtimes(g_x, E_p) + g_p)
        r = ca.vec(r)
        if k + 1 < K:
            n1 = asm.n[k + 1]
            off1 = asm.offsets[k + 1][0]
            F.append(w[off1 : off1 + n1] - r)
            if jacobian:
                J_rows.append(_placed(ca.DM.eye(n1), off1, size) - ca.mtimes(r_x, E))
                Ju_rows.append(-(ca.mtimes(r_x, E_u) + r_u))
                Jp_rows.append(-(ca.mtimes(r_x, E_p) + r_p))
        else:
            x_return = r
            sec = asm.section_index
            F.append(r[sec] - w[:m])
            if jacobian:
                J_rows.append(ca.mtimes(r_x, E)[sec, :] - _placed(ca.DM.eye(m), 0, size))
                Ju_rows.append((ca.mtimes(r_x, E_u) + r_u)[sec, :])
                Jp_rows.append((ca.mtimes(r_x, E_p) + r_p)[sec, :])
    J, Ju, Jp = (ca.vertcat(*rows) if jacobian else None for rows in (J_rows, Ju_rows, Jp_rows))
    return ca.vertcat(*F), J, Ju, Jp, x_return, ends, ca.vertcat(*rates), ca.vertcat(*adm)
