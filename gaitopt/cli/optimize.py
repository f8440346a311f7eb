"""``gaitopt optimize``: synthesise an optimal actuated gait.

::

    gaitopt optimize MODEL [--set NAME=VALUE ...] [--cost effort|work|cot] [--fix period=S]
                           [--fix step_length=M] [--fix speed=V] [--bound INPUT=MAX ...]
                           [--bound STATE=LOW:HIGH ...] [--constrain LIMIT ...]
                           [--free PARAM ...] [--steps K] [--starts N] [--seed S] [--tol TOL]
                           [--max-multiplier R [--max-roughness S]] [--scheduler ADDRESS]
                           [--stabilise [--q Q] [--r R] [--orbits N]]
                           [--library NAME=FIRST:LAST:COUNT [--cold K]] [--json] [--out DIR]

``--json`` prints one object: ``model``, ``params``, ``success``, ``message``, ``cost_kind``,
``cost``, ``period``, ``step_length``, ``speed``, ``fixed_point``, ``inputs`` (``{"time": [...],
INPUT: [...]}`` over one orbit), ``multipliers`` (``[re, im]``), ``stable``, ``verified``,
``discretisation_error``, ``active_constraints`` and, with ``--starts`` > 1, ``minima`` and
``starts``.  Bounds the model declares (``input_bounds``, ``state_bounds``: the five-link
biped's |u| ≤ 100 N·m, |q| ≤ π/2, |q̇| ≤ 10) apply unless ``--bound`` overrides an input's:
``--bound INPUT=MAX`` for |u| ≤ MAX (0 switches the input off), ``--bound INPUT=LOW:HIGH`` for
LOW ≤ u ≤ HIGH (within what the model declares: Kuo's push-off only pushes).  A name that is a
state (of any phase) bounds the state: ``--bound STATE=LOW:HIGH`` for LOW ≤ x ≤ HIGH (LOW < HIGH;
one side may be left empty, ``--bound q3=0:``), ``--bound STATE=MAX`` for |x| ≤ MAX, in state
units, at every collocation node of each phase with that state and checked on dense samples of
the optimum; it replaces the model's declared bound of that state.  ``--constrain LIMIT``
imposes a limit the model declares (``Phase.limits``; ``--constrain knee_flexion``: the five-link
biped's and the kneed walker's knees must not hyperextend), off unless given.  The JSON's
``active_constraints`` names each active state bound or limit with its phase (``x <= 2
(single support)``) and ``active_spans`` gives when, ``{label: [[t_first, t_last], ...]}`` (s
since the section).  ``--out DIR`` writes
``optimal.json``, ``inputs.csv``, ``orbit.png``, ``inputs.png`` and ``gait.gif``.  Exit status
0 optimal gait found and verified, 1 none (the JSON is still printed), 2 bad input.

Limits, checked before any work (one line and exit 2 beyond them; the Python API checks the
same, :func:`gaitopt.optimize_gait`): ``--steps`` 1 to 4 (the transcription grows faster than
the steps: the five-link biped takes 9 GB at 4), ``--starts`` 1 to 256 (each a full solve),
``--seed`` 0 to 2⁶³ − 1, ``--orbits`` 1 to 1000, ``--cold`` 0 to 200 (a library's most
points); ``--tol`` a positive number (the relative discretisation error the mesh refinement must
reach, default 1e-8; below IPOPT's 1e-11 it is never met and the result says so).

With ``--starts`` > 1 the JSON's ``starts`` lists every start's outcome (``converged`` to the
minimum at index ``minimum``, ``not_converged`` or ``no_start``, with its ``message``): a start
that cannot begin or fails is recorded and the search goes on.  On level ground (``--set
slope=0``) with no ``--fix``, the least effort is standing still, no gait: exit 2 at once.

``--max-multiplier R`` bounds the spectral radius of the optimum's return map inside the NLP
(:func:`gaitopt.optimize_gait`'s ``max_multiplier``): the JSON then has ``max_multiplier``,
``max_roughness`` and ``roughness`` (the input profile's ``∫ Σ u̇² dt``, bounded by
``--max-roughness S``, by default twice that of the optimum without the bound) and
``spectral_radius_fd_extrapolated`` (what the certificate checks), besides ``spectral_radius``
and ``spectral_radius_fd`` (AD and plain finite differences, always given); an
active bound is listed in ``active_constraints`` as ``spectral radius <= R``.  A model whose
section has more than 4 coordinates, or a work cost, cannot take it (exit 2).

``--scheduler local`` (or a Dask address) runs the ``--starts`` on Dask
(:func:`gaitopt.optimize.library.dask_starts`; the same minima as the serial run).

``--stabilise`` designs a per-step input offset for the optimum (step-to-step LQR, weights
``--q``/``--r``; :func:`gaitopt.optimize.stabilise`) and simulates the closed loop for
``--orbits`` orbits from perturbed states: the JSON gains a ``stabilisation`` object (gain,
open- and closed-loop multipliers, the multipliers measured from the simulated closed loop, the
runs); exit 0 only if the optimum and its stabilisation both succeed.

``--library NAME=FIRST:LAST:COUNT`` continues the optimum in ``period``, ``step_length``,
``speed`` or a model parameter over ``COUNT`` values, warm starting each from the last
(:func:`gaitopt.optimize.gait_library`), reports active-set changes and folds located by
bisection, and checks ``--cold K`` points (default 2) against cold starts (on Dask with
``--scheduler``).  The JSON is then one object: ``model``, ``params``, ``cost_kind``,
``success``, ``message``, ``vary``, ``points`` (each: value, cost, period, step length, speed,
fixed point, multipliers, active constraints, reduced Hessian, time), ``events``,
``cold_checks``, ``solve_time``; ``--out`` writes ``library.json`` and ``library.csv``.

The command-line helpers come from :mod:`gaitopt.cli` (imported when called, since that module
registers this one in its ``SUBCOMMANDS``).
"""

from __future__ import annotations

import argparse
import sys

from ..errors import GaitoptInputError
from .optimize_advice import for_the_cli
from .optimize_files import write_optimal
from .optimize_options import add_arguments, tolerance
from .optimize_parse import lqr_weights, parse_problem
from .optimize_report import print_report

__all__ = ["add_arguments", "for_the_cli", "run", "HELP"]

HELP = "synthesise an optimal gait (least effort, work or cost of transport) with input profiles"
#: The older private names (``gaitopt stabilise`` imports them).
_tolerance, _parse = tolerance, parse_problem


def run(args: argparse.Namespace) -> int:
    """``gaitopt optimize``: the optimal gait, verified by simulation, with its multipliers."""
    from ..optimize import optimize_gait
    from .common import EXIT_BAD_INPUT, EXIT_NOT_FOUND, EXIT_OK, InputError, build_model
    from .output import _print_json, _solver_output_to_stderr, write_outputs

    model = build_model(args.model, args.set)
    options = parse_problem(args, model)
    weights = lqr_weights(args)
    if args.library is not None:
        from .optimize_library import run_library

        return run_library(args, model, options)
    try:
        with _solver_output_to_stderr():
            gait = optimize_gait(
                model,
                args.cost,
                steps=args.steps,
                starts=args.starts,
                seed=args.seed,
                scheduler=args.scheduler,
                **options,
            )
    except GaitoptInputError as exc:
        raise InputError(for_the_cli(str(exc))) from None
    except OSError as exc:  # a Dask scheduler that cannot be reached
        if args.scheduler in (None, "local"):
            raise
        raise InputError(f"--scheduler {args.scheduler}: cannot reach it ({exc})") from None
    report = gait.to_json(minima=args.starts > 1)
    if gait.active_spans is not None:  # when the state bounds and limits bind
        report["active_spans"] = gait.active_spans
    report["message"] = for_the_cli(report["message"])
    for entry in (*report.get("minima", ()), *report.get("starts", ())):
        entry["message"] = for_the_cli(entry["message"])
    stabilised = True
    if args.stabilise:
        from ..optimize import stabilise

        if gait.success:
            with _solver_output_to_stderr():
                result = stabilise(gait, **weights, orbits=args.orbits)
            report["stabilisation"] = result.to_json()
            stabilised = result.success
        else:
            report["stabilisation"] = {"success": False, "message": "no optimum to stabilise"}
            stabilised = False
    lost = write_outputs(args.out, lambda folder: write_optimal(gait, report, folder))
    if args.json:
        _print_json(report)
    else:
        print_report(report, gait.model)
    if lost is not None:  # --out failed after the run: the files went elsewhere, said on stderr
        print(lost, file=sys.stderr)
        return EXIT_BAD_INPUT
    return EXIT_OK if gait.success and stabilised else EXIT_NOT_FOUND
