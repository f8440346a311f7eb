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
import math
import sys
from typing import Any

from ..errors import GaitoptInputError, did_you_mean
from .optimize_advice import for_the_cli
from .optimize_files import write_optimal

__all__ = ["add_arguments", "run", "HELP"]

HELP = "synthesise an optimal gait (least effort, work or cost of transport) with input profiles"
_FIXABLE = ("period", "step_length", "speed")


def _tolerance(text: str) -> float:
    """An argparse ``type`` for ``--tol``: a positive finite number."""
    try:
        value = float(text)
    except ValueError:
        value = math.nan
    if not (math.isfinite(value) and value > 0):
        raise argparse.ArgumentTypeError(
            f"expected a positive relative error, got {text!r}; e.g. --tol 1e-6"
        )
    return value


def _bound_value(option: str, example: str) -> Any:
    """An argparse ``type`` for ``--max-multiplier`` and ``--max-roughness``: a positive finite
    number."""

    def parse(text: str) -> float:
        try:
            value = float(text)
        except ValueError:
            value = math.nan
        if not (math.isfinite(value) and value > 0):
            raise argparse.ArgumentTypeError(
                f"expected a positive finite number, got {text!r}; e.g. {option} {example}"
            )
        return value

    return parse


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """Declare the arguments of ``gaitopt optimize``."""
    from ..optimize.problem import MAX_STEPS
    from ..optimize.solve import MAX_SEED, MAX_STARTS
    from .common import _count, _model_arguments, _scheduler_address

    why_steps = (
        "the transcription grows faster than the number of steps (the five-link biped: 9 GB at "
        f"4); use --steps {MAX_STEPS} or fewer"
    )
    why_starts = (
        "each start is a full solve (1-3 s on the five-link biped) and each minimum it finds is "
        f"refined and simulated; use --starts {MAX_STARTS} or fewer, or several runs with other "
        f"--seed values"
    )

    _model_arguments(parser)
    parser.add_argument(
        "--cost",
        choices=("effort", "work", "cot"),
        default="effort",
        help="∫Σu² dt (default), positive actuator work, or cost of transport",
    )
    parser.add_argument(
        "--fix",
        action="append",
        metavar="NAME=VALUE",
        help="fix period=S (s), step_length=M (m) or speed=V (m/s); repeatable",
    )
    parser.add_argument(
        "--bound",
        action="append",
        metavar="NAME=LOW:HIGH",
        help="INPUT=MAX: |INPUT| <= MAX at every collocation point (input units; 0 switches the "
        "input off), INPUT=LOW:HIGH; or STATE=LOW:HIGH (STATE=MAX: |STATE| <= MAX), a joint or "
        "rate limit in state units; repeatable",
    )
    parser.add_argument(
        "--constrain",
        action="append",
        metavar="LIMIT",
        help="impose a path constraint the model declares, e.g. knee_flexion (five_link_biped, "
        "kneed_walker: knees that do not hyperextend); repeatable",
    )
    parser.add_argument(
        "--free", action="append", metavar="PARAM", help="optimise this parameter too"
    )
    parser.add_argument(
        "--steps",
        type=_count(1, MAX_STEPS, why_steps),
        default=1,
        metavar="K",
        help=f"steps per orbit (default 1, at most {MAX_STEPS})",
    )
    parser.add_argument(
        "--starts",
        type=_count(1, MAX_STARTS, why_starts),
        default=1,
        metavar="N",
        help=f"seeded multi-start (default 1, at most {MAX_STARTS})",
    )
    parser.add_argument(
        "--seed",
        type=_count(0, MAX_SEED, "seeds are non-negative 64-bit integers; e.g. --seed 0"),
        default=0,
        metavar="S",
        help="seed of the multi-start (default 0)",
    )
    parser.add_argument(
        "--tol",
        type=_tolerance,
        default=1e-8,
        metavar="TOL",
        help="target of the relative discretisation error of cost and orbit under mesh "
        "refinement, a positive number (default 1e-8)",
    )
    parser.add_argument(
        "--max-multiplier",
        type=_bound_value("--max-multiplier", "1"),
        metavar="R",
        help="bound the spectral radius of the return map's Jacobian, |multiplier| <= R, inside "
        "the optimisation (R < 1: open-loop stable by design)",
    )
    parser.add_argument(
        "--max-roughness",
        type=_bound_value("--max-roughness", "120"),
        metavar="S",
        help="with --max-multiplier: bound on the integral of the squared input rates over the "
        "orbit ((input unit)^2/s; default: twice that of the optimum without the bound)",
    )
    parser.add_argument(
        "--scheduler",
        type=_scheduler_address,
        default=None,
        metavar="ADDRESS",
        help="run the --starts (or the --library's cold checks) on Dask: 'local' or a scheduler "
        "address (default: serial)",
    )
    parser.add_argument(
        "--stabilise",
        action="store_true",
        help="stabilise the optimum by an input offset per step (LQR) and simulate the closed loop",
    )
    parser.add_argument(
        "--q", metavar="Q", help="--stabilise: LQR state weight, a number or a diagonal (default 1)"
    )
    parser.add_argument(
        "--r", metavar="R", help="--stabilise: LQR offset weight, a number or a diagonal (1e-3)"
    )
    parser.add_argument(
        "--orbits",
        type=_count(1, 1000, "each orbit is simulated for every perturbed start"),
        default=20,
        help="--stabilise: orbits simulated from each perturbed state (default 20)",
    )
    parser.add_argument(
        "--library",
        metavar="NAME=FIRST:LAST:COUNT",
        help="continue the optimum in period, step_length, speed or a parameter over COUNT "
        "values, e.g. step_length=0.2:0.5:7",
    )
    parser.add_argument(
        "--cold",
        type=_count(0, 200, "a library has at most 200 points (--library ...:COUNT)"),
        default=2,
        help="--library: points checked against cold starts (default 2)",
    )
    parser.add_argument("--out", metavar="DIR", help="write JSON, CSV and figures to DIR")


def _parse(args: argparse.Namespace, model: Any) -> dict[str, Any]:
    from .common import InputError, _assignments

    fixed = _assignments(
        "--fix", args.fix, {"period": "period=0.8", "step_length": "step_length=0.3"}
    )
    for name, (item, value) in fixed.items():
        if name not in _FIXABLE:
            raise InputError(
                f"--fix {item}: {name!r} cannot be fixed; {did_you_mean(name, _FIXABLE)}"
                f"choose from {', '.join(_FIXABLE)}, e.g. --fix period=0.8"
            )
        if not value > 0:
            raise InputError(f"--fix {item}: must be positive, e.g. --fix {name}=0.8")
    bounds: dict[str, Any] = {  # the model's finite declared bounds (applied anyway)
        n: float(hi) if lo == -hi else (float(lo), float(hi))
        for n, (lo, hi) in model.input_bounds.items()
        if math.isfinite(lo) and math.isfinite(hi)
    }
    inputs, states = _bounds(args.bound, model)
    bounds.update(inputs)
    state_bounds = {**dict(model.state_bounds), **states}
    paths = _constrain(args.constrain, model)
    if paths and args.library is not None:
        raise InputError(
            f"--constrain {paths[0]}: a --library does not take path constraints yet; "
            f"drop --constrain or --library"
        )
    if args.max_roughness is not None and args.max_multiplier is None:
        raise InputError(
            f"--max-roughness {args.max_roughness:g} applies with --max-multiplier; add "
            f"--max-multiplier 1 or drop --max-roughness"
        )
    if args.max_multiplier is not None and args.library is not None:
        raise InputError(
            f"--max-multiplier {args.max_multiplier:g}: a --library does not take the bound "
            f"yet; drop --max-multiplier or --library"
        )
    free = tuple(args.free or ())
    for name in free:
        if name not in model.params:
            raise InputError(
                f"--free {name}: {model.name} has no parameter {name!r}; "
                f"{did_you_mean(name, model.params)}parameters: {', '.join(model.params)}"
            )
    return {
        **{name: value for name, (_, value) in fixed.items()},
        "bounds": bounds,
        "state_bounds": state_bounds,
        **({"path_constraints": paths} if paths else {}),
        "free": free,
        "tol": args.tol,
        **({"max_multiplier": args.max_multiplier} if args.max_multiplier is not None else {}),
        **({"max_roughness": args.max_roughness} if args.max_roughness is not None else {}),
    }


def _constrain(items: list[str] | None, model: Any) -> tuple[str, ...]:
    """``--constrain LIMIT``: limits the model declares (``Phase.limits``), each once."""
    from ..optimize.problem import declared_limits
    from .common import InputError

    declared = declared_limits(model)
    names: list[str] = []
    for item in items or ():
        name = item.strip()
        if name not in declared:
            have = (
                f"its limits: {', '.join(declared)}"
                if declared
                else "it declares none (Phase.limits)"
            )
            raise InputError(
                f"--constrain {item}: {model.name} has no limit {name!r}; "
                f"{did_you_mean(name, declared) if declared else ''}{have}"
            )
        if name not in names:
            names.append(name)
    return tuple(names)


def _bounds(items: list[str] | None, model: Any) -> tuple[dict[str, Any], dict[str, Any]]:
    """``--bound INPUT=MAX`` (``|u| <= MAX``; 0 switches the input off) or ``INPUT=LOW:HIGH``;
    ``--bound STATE=LOW:HIGH`` (an empty side: unbounded there) or ``STATE=MAX``: the input
    bounds and the state bounds."""
    from ..optimize.problem import all_state_names
    from .common import InputError, _number, _split

    states = all_state_names(model)
    examples = {n: f"{n}=10" for n in model.inputs} or {"INPUT": "INPUT=10"}
    examples.update({n: f"{n}=-1:1" for n in states})
    bounds: dict[str, Any] = {}
    state_bounds: dict[str, tuple[float, float]] = {}
    for item in items or ():
        name, text = _split("--bound", item, examples)
        if name not in model.inputs and name in states:
            state_bounds[name] = _state_bound(item, name, text)
            continue
        if name not in model.inputs:
            raise InputError(
                f"--bound {item}: {model.name} has no input or state {name!r}; "
                f"{did_you_mean(name, (*model.inputs, *states))}inputs: "
                f"{', '.join(model.inputs) or 'none'}; states: {', '.join(states)}"
            )
        example = f"--bound {name}=10 (|u| <= 10), {name}=0 (off) or {name}=0:10"
        if ":" in text:
            low_text, _, high_text = text.partition(":")
            low = _number("--bound", item, low_text.strip(), f"{name}=0:10")
            high = _number("--bound", item, high_text.strip(), f"{name}=0:10")
            if not low <= high:
                raise InputError(f"--bound {item}: LOW must not exceed HIGH; e.g. {example}")
            bounds[name] = (low, high)
        else:
            value = _number("--bound", item, text, f"{name}=10")
            if not value >= 0:
                raise InputError(f"--bound {item}: the bound must be >= 0; e.g. {example}")
            bounds[name] = value
    return bounds, state_bounds


def _state_bound(item: str, name: str, text: str) -> tuple[float, float]:
    """``--bound STATE=LOW:HIGH`` (LOW < HIGH; an empty side is unbounded) or ``STATE=MAX``
    (``|x| <= MAX``, MAX > 0)."""
    from .common import InputError, _number

    example = f"--bound {name}=-0.5:0.5 (-0.5 <= {name} <= 0.5), {name}=0: or {name}=0.5"
    if ":" not in text:
        value = _number("--bound", item, text, f"{name}=0.5")
        if not value > 0:
            raise InputError(f"--bound {item}: a state's MAX must be > 0; e.g. {example}")
        return -value, value
    low_text, _, high_text = (part.strip() for part in text.partition(":"))
    if not low_text and not high_text:
        raise InputError(f"--bound {item}: give LOW, HIGH or both; e.g. {example}")
    low = _number("--bound", item, low_text, f"{name}=-0.5:0.5") if low_text else -math.inf
    high = _number("--bound", item, high_text, f"{name}=-0.5:0.5") if high_text else math.inf
    if not low < high:
        raise InputError(
            f"--bound {item}: a state's LOW must be below its HIGH (got {low:g} >= {high:g}); "
            f"e.g. {example}"
        )
    return low, high


def run(args: argparse.Namespace) -> int:
    """``gaitopt optimize``: the optimal gait, verified by simulation, with its multipliers."""
    from ..optimize import optimize_gait
    from .common import EXIT_BAD_INPUT, EXIT_NOT_FOUND, EXIT_OK, InputError, build_model
    from .output import _print_json, _solver_output_to_stderr, write_outputs

    model = build_model(args.model, args.set)
    options = _parse(args, model)
    weights = _weights(args)
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
        _print(report, gait.model)
    if lost is not None:  # --out failed after the run: the files went elsewhere, said on stderr
        print(lost, file=sys.stderr)
        return EXIT_BAD_INPUT
    return EXIT_OK if gait.success and stabilised else EXIT_NOT_FOUND


def _weights(args: argparse.Namespace) -> dict[str, Any]:
    """``--q``/``--r`` as :func:`gaitopt.optimize.stabilise` weights (only with --stabilise)."""
    from .common import InputError, _numbers

    q, r = _numbers("--q", args.q), _numbers("--r", args.r)
    for option, value in (("--q", q), ("--r", r), ("--orbits", args.orbits != 20 or None)):
        if value is not None and not args.stabilise:
            raise InputError(f"{option} applies with --stabilise; add --stabilise")
    if args.stabilise and args.library is not None:
        raise InputError("--stabilise applies to one optimum, not a --library; drop one of them")
    weights: dict[str, Any] = {}
    for name, value in (("Q", q), ("R", r)):
        if value is not None:
            if any(v < 0 for v in value) or (name == "R" and any(v <= 0 for v in value)):
                option = f"--{name.lower()}"
                raise InputError(
                    f"{option} {getattr(args, name.lower())}: weights must be "
                    f"{'positive' if name == 'R' else 'non-negative'}, e.g. {option} 1"
                )
            weights[name] = value if len(value) > 1 else value[0]
    return weights


# -- the text output (``gaitopt optimize`` without --json) ----------------------------------
def _print(report: dict[str, Any], model: Any) -> None:
    """Print the ``--json`` ``report`` of an optimum as text, in the model's declared units.

    The style of ``gaitopt solve`` (:mod:`gaitopt.cli.output`): one aligned label column; the
    fixed point one state a line with its unit; each multiplier as ``re ± im j  |λ| = …``; the
    ``--free`` parameters at their optimised values; the active constraints; with ``--starts``
    > 1 the distinct minima and the starts that reached none.

    Parameters
    ----------
    report : dict
        The ``gaitopt optimize --json`` object (:meth:`gaitopt.optimize.OptimalGait.to_json`,
        messages in the command line's options, ``stabilisation`` with ``--stabilise``).
    model : HybridModel
        The optimum's model (its ``--free`` parameters at their optimised values).
    """
    from .output import print_block

    print_block(_report_items(report, model))


def _report_items(report: dict[str, Any], model: Any) -> list[Any]:
    """The rows (``(label, value)``) and lines of :func:`_print`, in order."""
    from ..plotting.labels import cost_unit, speed_unit
    from .output import _number, fixed_point_lines, header_rows, multiplier_text, with_unit

    def complexes(pairs: list[list[float]]) -> list[complex]:
        return [complex(re, im) for re, im in pairs]

    kind = report["cost_kind"]
    cost = cost_unit(model, kind)
    specs = {spec.name: spec for spec in model.parameter_specs()}
    items: list[Any] = header_rows(model, report["success"], report["message"])
    items += [
        (f"cost ({kind})", with_unit(_number(report["cost"]), cost)),
        ("period", with_unit(_number(report["period"]), model.time_unit)),
        ("step length", with_unit(_number(report["step_length"]), model.length_unit)),
        ("speed", with_unit(_number(report["speed"]), speed_unit(model))),
    ]
    for name in report.get("problem", {}).get("free", ()):
        value = with_unit(_number(report["params"][name]), specs[name].unit)
        items.append((f"free {name}", f"{value} (optimised)"))
    if report["fixed_point"]:
        items.append(f"fixed point (section: {model.section.doc})")
        items += fixed_point_lines(model, report["fixed_point"])
    if report["multipliers"]:
        items.append("multipliers")
        items += [f"    {multiplier_text(z)}" for z in complexes(report["multipliers"])]
    error = report["discretisation_error"]
    items += [
        ("stable", report["stable"]),
        ("verified", report["verified"]),
        ("discretisation error", "None" if error is None else f"{error:.2g} (relative)"),
        ("active constraints", ", ".join(report["active_constraints"]) or "none"),
    ]
    if report.get("max_multiplier") is not None:  # --max-multiplier: the bound and its budget
        rho, rho_fd = report.get("spectral_radius"), report.get("spectral_radius_fd")
        items.append(
            ("spectral radius", f"{_number(rho)} (finite differences {_number(rho_fd)}; bound "
             f"{report['max_multiplier']:g})")
        )  # fmt: skip
        items.append(
            ("roughness", f"{_number(report.get('roughness'))} (bound "
             f"{_number(report.get('max_roughness'))}; ∫Σu̇² dt)")
        )  # fmt: skip
    minima, starts = report.get("minima", []), report.get("starts", [])
    if minima or starts:
        items.append((f"minima ({len(minima)})", f"distinct, from {_count(starts, 'start')}"))
        for i, m in enumerate(minima, start=1):
            period = with_unit(_number(m["period"]), model.time_unit)
            reached = ", ".join(str(k) for k in m["starts"])
            items.append(
                f"    {i}. cost {with_unit(_number(m['cost']), cost)}, period {period}, "
                f"verified {m['verified']}; {'start' if len(m['starts']) == 1 else 'starts'} "
                f"{reached}"
            )
    for s in starts:  # the starts that reached no minimum, and why
        if s["status"] != "converged":
            items.append((f"start {s['start']}", f"{s['status']}: {s['message']}"))
    st = report.get("stabilisation")
    if st is not None:
        items += [("stabilised", st["success"]), ("  message", st["message"])]
        if "gain" in st:
            columns = ", ".join(st["section_coordinates"])
            items.append(f"  gain K (δ = −K (s − s*); columns {columns})")
            for name, row in zip(st["inputs"], st["gain"], strict=True):
                items.append(f"    {name:<20}{'  '.join(f'{k: .8g}' for k in row)}")
            for label, key in (
                ("open loop", "open_loop_multipliers"),
                ("closed loop", "closed_loop_multipliers"),
                ("measured closed loop", "measured_closed_loop_multipliers"),
            ):
                items.append(f"  {label} multipliers")
                items += [f"    {multiplier_text(z)}" for z in complexes(st[key])]
    return items


def _count(things: list[Any], noun: str) -> str:
    """``"1 start"``, ``"2 starts"``."""
    return f"{len(things)} {noun}{'' if len(things) == 1 else 's'}"
