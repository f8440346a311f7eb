"""The deadbeat policy as C: one CasADi function (single shooting + ``fast_newton``), generated,
compiled with the system's C compiler and cached by the source's hash."""

from __future__ import annotations

import hashlib
import os
import shutil
import subprocess
import tempfile
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Protocol

import casadi as ca
import numpy as np

from ..errors import GaitoptInputError
from ..integrators import segment_function


class DeadbeatSolver(Protocol):
    """What the generated policy uses of a :class:`~gaitopt.control.deadbeat_solver.Deadbeat`:
    that module sits above this one (its ``policy_function``/``codegen`` call this module's),
    so the functions here name the solver by the members they read."""

    cycle: Any
    model: Any
    shooting: Any
    m: int
    n_u: int


def policy_function(solver: DeadbeatSolver, steps: Sequence[int] | None = None) -> ca.Function:
    """The deadbeat policy as one CasADi function ``u, T, residual = policy(s, s_target, p)``.

    Single shooting through the phase chain (unknowns: the phase durations and ``u``; each
    phase integrated by ``steps[k]`` fixed RK8 steps), solved by CasADi's ``fast_newton``
    (code generation supported) from the first-order prediction of the solution about the
    gait.  ``T`` (phase durations, all positive for a valid step) and ``residual`` (NaN when
    Newton diverged, far from the gait) let the caller reject a failed decision.  ``steps``
    defaults to the fewest steps per phase (1, 2, 4, …) whose end state on the gait changes
    by less than 1e-9 (relative) when they are doubled; a ballistic flight needs one.
    """
    model, shooting = solver.model, solver.shooting
    phases = [model.phases[i] for i in shooting.chain]
    steps = list(steps) if steps is not None else _policy_steps(solver)
    if len(steps) != len(phases):
        raise GaitoptInputError(f"`steps` needs {len(phases)} entries, got {len(steps)}")
    n_p = model.p.size
    T = ca.SX.sym("T", len(phases))
    u = ca.SX.sym("u", solver.n_u)
    s = ca.SX.sym("s", solver.m)
    s_t = ca.SX.sym("s_target", solver.m)
    p = ca.SX.sym("p", n_p)
    x = model.section.lift(s, p)
    eq = []
    for k, phase in enumerate(phases):
        x = segment_function(phase.flow, steps[k])(x, u, p, T[k])
        tr0 = phase.transitions[0]
        eq.append(tr0.guard(x, u, p))  # each phase ends on its guard
        x = tr0.reset(x, u, p)
    eq.append(x[shooting.section_index] - s_t)  # the next return is the target
    v = ca.vertcat(T, u)
    F = ca.Function("deadbeat_single_shooting", [v, s, s_t, p], [ca.vertcat(*eq)])
    newton = ca.rootfinder(
        "deadbeat_newton",
        "fast_newton",
        F,
        {"abstol": 1e-13, "max_iter": 30, "error_on_fail": False},
    )
    # First-order predictor from the gait (implicit function theorem on F(v, s, s_t) = 0):
    # Newton starts at v* + dv/ds δs + dv/ds_t δs_t, so a few iterations suffice.
    v_star = np.concatenate([np.asarray(solver.cycle.durations, float), solver.cycle.inputs])
    s_star, p_star = solver.cycle.section_point, solver.model.p
    jac = ca.Function(
        "predictor", [v, s, s_t, p], [ca.jacobian(F(v, s, s_t, p), ca.vertcat(v, s, s_t))]
    )
    J = np.asarray(jac(v_star, s_star, s_star, p_star), dtype=float)
    n_v = v.numel()
    sens = -np.linalg.solve(J[:, :n_v], J[:, n_v:])  # dv/d(s, s_t)
    v0 = v_star + ca.mtimes(ca.DM(sens), ca.vertcat(s - s_star, s_t - s_star))
    sol = newton(v0, s, s_t, p)
    residual = ca.norm_2(F(sol, s, s_t, p))  # NaN if Newton failed
    return ca.Function(
        "deadbeat_policy",
        [s, s_t, p],
        [sol[len(phases) :], sol[: len(phases)], residual],
        ["s", "s_target", "p"],
        ["u", "T", "residual"],
    )


def _policy_steps(solver: DeadbeatSolver, tol: float = 1e-9) -> list[int]:
    steps = []
    u, p = np.asarray(solver.cycle.inputs, float), solver.model.p
    for arc, T in zip(solver.cycle.orbit, solver.cycle.durations, strict=True):
        flow = solver.model.phases[arc.phase].flow
        x0 = arc.x[:, 0]
        n, prev = 1, None
        while n <= 256:
            end = np.asarray(segment_function(flow, n)(x0, u, p, T), float).ravel()
            if prev is not None and np.max(np.abs(end - prev)) < tol * (1 + np.max(np.abs(end))):
                break
            prev, n = end, 2 * n
        steps.append(max(1, n // 2))
    return steps


def compile_policy(
    solver: DeadbeatSolver,
    directory: str | os.PathLike | None = None,
    *,
    steps: Sequence[int] | None = None,
) -> GeneratedPolicy:
    """Generate C for :meth:`policy_function` and compile it (``cc -O3 -shared``), cached by
    the source's hash in ``directory`` (default: ``<tmp>/gaitopt-codegen``).

    Returns
    -------
    GeneratedPolicy
        The C source, the shared library and the function loaded from it
        (``casadi.external``).

    Raises
    ------
    RuntimeError
        If no C compiler is found or compiling fails.
    """
    policy = policy_function(solver, steps)
    root = Path(directory or Path(tempfile.gettempdir()) / "gaitopt-codegen")
    root.mkdir(parents=True, exist_ok=True)
    with tempfile.TemporaryDirectory(dir=root) as scratch:
        name = "deadbeat_policy.c"
        generator = ca.CodeGenerator(name, {"with_header": True, "with_mem": False})
        generator.add(policy)
        generator.generate(f"{scratch}{os.sep}")  # a prefix: no change of directory
        source = Path(scratch, name).read_text()
        header = Path(scratch, "deadbeat_policy.h").read_text()
    digest = hashlib.sha256(source.encode()).hexdigest()[:16]
    folder = root / digest
    folder.mkdir(exist_ok=True)
    c_file, h_file = folder / "deadbeat_policy.c", folder / "deadbeat_policy.h"
    library = folder / "deadbeat_policy.so"
    if not library.exists():
        c_file.write_text(source)
        h_file.write_text(header)
        compiler = shutil.which(os.environ.get("CC", "cc")) or shutil.which("gcc")
        if compiler is None:
            raise RuntimeError("no C compiler (cc or gcc) found for the generated policy")
        tmp = folder / f".{digest}.{os.getpid()}.so"
        proc = subprocess.run(
            [compiler, "-O3", "-fPIC", "-shared", str(c_file), "-o", str(tmp), "-lm"],
            capture_output=True,
            text=True,
        )
        if proc.returncode != 0:
            raise RuntimeError(f"compiling the generated policy failed: {proc.stderr[-500:]}")
        os.replace(tmp, library)
    return GeneratedPolicy(c_file, library, ca.external("deadbeat_policy", str(library)))


@dataclass(frozen=True)
class GeneratedPolicy:
    """A compiled deadbeat policy: ``function(s, s_target, p) -> (u, T, residual)``.

    Attributes
    ----------
    source : pathlib.Path
        The generated C file (its header beside it).
    library : pathlib.Path
        The shared library compiled from it.
    function : casadi.Function
        The library loaded with ``casadi.external``.
    """

    source: Path
    library: Path
    function: ca.Function
