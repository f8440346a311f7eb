"""The ``gaitopt`` command: list the models, find a gait, simulate a model.

::

    gaitopt list [--json]
    gaitopt solve MODEL [--set NAME=VALUE ...] [--guess STATE=VALUE ...] [--steps K]
                        [--method newton|ipopt] [--json]
    gaitopt simulate MODEL [--set NAME=VALUE ...] [--x0 STATE=VALUE ...] [--steps N]
                           [--controller lqr|acker|deadbeat|blind] [--terrain SEED:AMPLITUDE]
                           [--json]
    gaitopt control MODEL --kind lqr|acker|deadbeat [--set ...] [--guess ...] [--target ...]
                          [--q Q] [--r R] [--poles P] [--from STATE=VALUE ...] [--json]
    gaitopt continue MODEL --param NAME --to VALUE [--set ...] [--guess ...] [--steps K]
                           [--both] [--no-cascade] [--max-period K] [--out DIR] [--json]

Exit status (docs/design.md, public contract): 0 gait found / simulation completed; 1 no gait found
(the JSON is still printed, with ``success: false``) or the simulation did not complete; 2 bad
input, reported as one line on stderr that starts with ``gaitopt: error:``, names the argument,
shows the value and suggests a fix.

Each subcommand is an entry of :data:`SUBCOMMANDS`: a function that declares its arguments and a
function that runs it.  Adding one (``continue``, ``control``) means writing those two functions
and adding the entry.

The module imports the library's submodules directly (not the package ``gaitopt``), so the
console script works however the package is installed.
"""

from __future__ import annotations

import argparse
import contextlib
import ctypes
import json
import math
import os
import sys
import warnings
from collections.abc import Callable, Iterable, Iterator, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any, NoReturn

import numpy as np

from . import cli_linkage, cli_optimize
from .continuation import Branch, continuation
from .errors import (
    MAX_ORBIT_STEPS,
    MAX_SIMULATION_STEPS,
    GaitoptInputError,
    GuessError,
    ParameterError,
    StateError,
    did_you_mean,
)
from .files import jsonable
from .hybrid import HybridModel
from .models import REGISTRY
from .parameters import ParameterSpec, check_parameter
from .result import LimitCycle
from .shooting import find_limit_cycle
from .simulation import Simulation, simulate

__all__ = ["main", "build_parser", "Subcommand", "SUBCOMMANDS", "EXIT_OK", "EXIT_NOT_FOUND"]

PROG = "gaitopt"
EXIT_OK = 0
EXIT_NOT_FOUND = 1
EXIT_BAD_INPUT = 2


class InputError(Exception):
    """Bad command-line input; :func:`main` prints it on one line and exits with status 2."""


class _Parser(argparse.ArgumentParser):
    """An argument parser whose usage errors are one line, in the style of every other error."""

    def error(self, message: str) -> NoReturn:
        """Print ``gaitopt: error: ...`` (one line) and exit with status 2."""
        where = self.prog.removeprefix(PROG).strip()
        prefix = f"{where}: " if where else ""
        self.exit(EXIT_BAD_INPUT, f"{PROG}: error: {prefix}{message}; see `{self.prog} --help`\n")

    def _get_values(self, action: argparse.Action, arg_strings: list[str]) -> Any:
        """``--opt=--``: the value is the text ``--`` (argparse would drop it and store ``[]``,
        a list where a string is expected)."""
        if action.nargs is None and arg_strings == ["--"]:
            value = self._get_value(action, "--")
            self._check_value(action, value)
            return value
        return super()._get_values(action, arg_strings)


@dataclass(frozen=True)
class Subcommand:
    """One subcommand of ``gaitopt``.

    Attributes
    ----------
    help : str
        One-line description (shown by ``gaitopt --help``).
    add_arguments : callable
        ``add_arguments(parser)`` declares the subcommand's arguments.
    run : callable
        ``run(args) -> exit status``; raises :class:`InputError` for bad input.
    """

    help: str
    add_arguments: Callable[[argparse.ArgumentParser], None]
    run: Callable[[argparse.Namespace], int]


# -- small parsers -------------------------------------------------------------------------------
def _count(minimum: int, maximum: int | None = None, why: str = "") -> Callable[[str], int]:
    """An argparse ``type`` accepting integers ``>= minimum`` (and ``<= maximum``: the limit and
    ``why`` it is there are stated when it is exceeded)."""

    def parse(text: str) -> int:
        try:
            value = int(text)
        except ValueError:
            value = minimum - 1
        if value < minimum:
            raise argparse.ArgumentTypeError(f"expected an integer >= {minimum}, got {text!r}")
        if maximum is not None and value > maximum:
            raise argparse.ArgumentTypeError(
                f"{text!r} is above the limit {maximum}" + (f": {why}" if why else "")
            )
        return value

    return parse


def _scheduler_address(text: str) -> str:
    """An argparse ``type`` for ``--scheduler``: ``local`` or a Dask address with its port
    (``tcp://10.0.0.5:8786``, ``10.0.0.5:8786``)."""
    host, sep, port = text.strip().rpartition(":")
    bare = host.split("://", 1)[-1]
    if text.strip() == "local" or (sep and port.isdigit() and bare and "\x00" not in text):
        return text.strip()
    raise argparse.ArgumentTypeError(
        f"expected 'local' or a Dask scheduler address with its port, e.g. tcp://10.0.0.5:8786, "
        f"got {text!r}"
    )


#: Why ``--steps`` (solve, continue) and ``--max-period`` stop at :data:`MAX_ORBIT_STEPS`.
_ORBIT_LIMIT = "the shooting system of a period-k orbit grows faster than k"
#: Why ``simulate --steps`` stops at :data:`MAX_SIMULATION_STEPS`.
_SIMULATION_LIMIT = "time and memory grow with every step; simulate in pieces"


def _split(option: str, item: str, examples: Mapping[str, str]) -> tuple[str, str]:
    """Split ``NAME=VALUE``; ``examples`` maps names to a valid ``NAME=VALUE`` for the hint."""
    name, sep, text = (part.strip() for part in item.partition("="))
    if not sep or not name or not text:
        example = examples.get(name) or next(iter(examples.values()), "NAME=VALUE")
        raise InputError(f"{option} {item}: expected NAME=VALUE, e.g. {option} {example}")
    return name, text


def _number(option: str, item: str, text: str, example: str) -> float:
    """A finite float from ``text`` (``0.09``, ``1e-2``), or an :class:`InputError`."""
    try:
        value = float(text)
    except ValueError:
        raise InputError(
            f"{option} {item}: {text!r} is not a number; e.g. {option} {example}"
        ) from None
    if not math.isfinite(value):
        raise InputError(f"{option} {item}: {text!r} is not finite; e.g. {option} {example}")
    return value


def _assignments(
    option: str, items: Sequence[str] | None, examples: Mapping[str, str]
) -> dict[str, tuple[str, float]]:
    """Parse repeated ``NAME=VALUE`` items into ``name -> (item, value)`` (the last one wins)."""
    parsed: dict[str, tuple[str, float]] = {}
    for item in items or ():
        name, text = _split(option, item, examples)
        example = examples.get(name) or next(iter(examples.values()), "NAME=VALUE")
        parsed[name] = (item, _number(option, item, text, example))
    return parsed


def _echo(option: str, items: Iterable[str]) -> str:
    """The arguments as typed: ``--set a=1 --set b=2``."""
    return " ".join(f"{option} {item}" for item in items)


# -- models, parameters, states -----------------------------------------------------------------
def _model_class(name: str) -> type[HybridModel]:
    """The registered model class called ``name``."""
    if name in REGISTRY:
        return REGISTRY[name]
    raise InputError(
        f"MODEL {name!r} is not a model; {did_you_mean(name, REGISTRY)}"
        f"available: {', '.join(REGISTRY)} (see `{PROG} list`)"
    )


def _parameter(model_name: str, specs: Mapping[str, ParameterSpec], item: str) -> tuple[str, float]:
    """One ``--set NAME=VALUE``: a known parameter, a number, in its range."""
    examples = {name: f"{name}={spec.default:g}" for name, spec in specs.items()}
    name, text = _split("--set", item, examples)
    if name not in specs:
        raise InputError(
            f"--set {item}: {model_name} has no parameter {name!r}; "
            f"{did_you_mean(name, specs)}parameters: {', '.join(specs)} (see `{PROG} list`)"
        )
    value = _number("--set", item, text, examples[name])
    try:
        return name, check_parameter(model_name, specs[name], value)
    except ParameterError as exc:
        raise InputError(f"--set {item}: {exc}") from None


def build_model(name: str, settings: Sequence[str] | None) -> HybridModel:
    """The model ``name`` with the ``--set NAME=VALUE`` items applied.

    Raises
    ------
    InputError
        For an unknown model or parameter, a value that is not a number or out of range, or a
        combination of values the model rejects.
    """
    cls = _model_class(name)
    specs = {spec.name: spec for spec in cls.parameter_specs()}
    params = dict(_parameter(name, specs, item) for item in settings or ())
    try:
        return cls(**params)
    except ParameterError as exc:  # cross-parameter checks (rimless wheel: slope < π/spokes)
        raise InputError(f"{_echo('--set', settings or ())}: {exc}") from None


def _state_examples(model: HybridModel) -> dict[str, str]:
    """``name -> "name=value"`` from the model's default start (section coordinates)."""
    return {name: f"{name}={value:.6g}" for name, value in model.default_start().items()}


def _guess_hint(model: HybridModel, name: str) -> str:
    """What to do about a ``--guess`` name that is not a section coordinate."""
    if name in model.state_names:  # fixed by the section: say which names are free
        return f"; --guess takes the section coordinates {', '.join(model.section.coordinates)}"
    close = did_you_mean(name, model.section.coordinates).strip()
    return f"; {close}" if close else ""  # the library's message already lists the coordinates


def parse_guess(model: HybridModel, items: Sequence[str] | None) -> dict[str, float] | None:
    """The ``--guess STATE=VALUE`` items as section coordinates (``None`` if there are none)."""
    if not items:
        return None
    parsed = _assignments("--guess", items, _state_examples(model))
    guess = {name: value for name, (_, value) in parsed.items()}
    coordinates = model.section.coordinates
    try:
        model.section_vector(guess)
    except StateError as exc:  # the library names the first state that is not a coordinate
        name, item = next(
            ((n, item) for n, (item, _) in parsed.items() if n not in coordinates),
            ("", " ".join(items)),
        )
        raise InputError(f"--guess {item}: {exc}{_guess_hint(model, name)}") from None
    return guess


def parse_x0(model: HybridModel, items: Sequence[str] | None) -> np.ndarray:
    """The ``--x0 STATE=VALUE`` items as a full phase-0 state.

    Only section coordinates: the others follow from the section (missing coordinates from the
    model's default start).  Any other state named: every state must be given.
    """
    parsed = _assignments("--x0", items, _state_examples(model))
    coordinates, states = model.section.coordinates, model.state_names
    takes = (
        f"the section coordinates {', '.join(coordinates)} (the rest follow from the section) "
        f"or all of {', '.join(states)}"
    )
    for name, (item, _) in parsed.items():
        if name not in states:
            raise InputError(
                f"--x0 {item}: {model.name} has no state {name!r}; "
                f"{did_you_mean(name, states)}--x0 takes {takes}"
            )
    x0 = {name: value for name, (_, value) in parsed.items()}
    if set(x0) <= set(coordinates):
        _check_point(model, "--x0", items or (), x0)
    try:
        if set(x0) <= set(coordinates):
            return model.lift(x0)
        return model.state_vector(x0)
    except StateError as exc:
        raise InputError(f"{_echo('--x0', items or ())}: {exc}; --x0 takes {takes}") from None


def _check_point(
    model: HybridModel, option: str, items: Sequence[str], point: Mapping[str, float]
) -> None:
    """A section point typed in (``--x0``, ``--target``, ``--from``) must exist at the model's
    parameters (the SLIP's apex below its energy height; see
    :func:`gaitopt.control.check_section_point`)."""
    from .control import check_section_point

    try:
        check_section_point(model, point, option.lstrip("-"), label=_echo(option, items))
    except GaitoptInputError as exc:
        raise InputError(str(exc)) from None


# -- output --------------------------------------------------------------------------------------
@contextlib.contextmanager
def _solver_output_to_stderr() -> Iterator[None]:
    """Send whatever the solver prints to stderr while the block runs.

    ``solve --json`` promises one JSON object on stdout, but CasADi's solver plugins print
    (IPOPT's banner), through :data:`sys.stdout` or the C-level file descriptor 1 depending on
    where the output goes.  Both are pointed at stderr here.
    """
    sys.stdout.flush()
    try:
        saved = os.dup(1)
    except OSError:  # no file descriptor 1 to protect
        saved = None
    if saved is not None:
        os.dup2(2, 1)
    try:
        with contextlib.redirect_stdout(sys.stderr):
            yield
            sys.stdout.flush()
    finally:
        if saved is not None:
            _flush_c_stdio()
            os.dup2(saved, 1)
            os.close(saved)


def _flush_c_stdio() -> None:
    """``fflush(NULL)``: push out what C code buffered before file descriptor 1 is restored."""
    with contextlib.suppress(OSError, AttributeError, TypeError):
        ctypes.CDLL(None).fflush(None)


def _print_json(value: Any) -> None:
    print(json.dumps(jsonable(value), indent=2, ensure_ascii=False, allow_nan=False))


def _format_params(params: Mapping[str, float]) -> str:
    return ", ".join(f"{name}={value:g}" for name, value in params.items())


def _print_rows(rows: Iterable[tuple[str, Any]]) -> None:
    for label, value in rows:
        print(f"{label:<12}{value}")


# -- gaitopt list --------------------------------------------------------------------------------
def describe_model(cls: type[HybridModel]) -> dict[str, Any]:
    """The ``gaitopt list --json`` entry of a model class."""
    instance = cls()
    return {
        "name": cls.name,
        "title": cls.title,
        "reference": cls.reference,
        "params": [spec.as_dict() for spec in cls.parameter_specs()],
        "state_names": list(instance.state_names),
        "section_coordinates": list(instance.section.coordinates),
        "section": instance.section.doc,
        "inputs": list(cls.inputs),
    }


def _list_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("--json", action="store_true", help="print a JSON list of the models")


def run_list(args: argparse.Namespace) -> int:
    """``gaitopt list``: the models, their parameters, states and sections."""
    models = [describe_model(cls) for cls in REGISTRY.values()]
    if args.json:
        _print_json(models)
        return EXIT_OK
    for entry in models:
        print(f"{entry['name']}: {entry['title']} ({entry['reference']})")
        for p in entry["params"]:
            value = f"{p['name']:<12} = {p['default']:<9g} {p['unit']:<6}"
            print(f"    {value} {p['range']:<20} {p['doc']}")
        print(f"    states       {', '.join(entry['state_names'])}")
        print(f"    section      {entry['section']}")
        print(f"                 coordinates {', '.join(entry['section_coordinates'])}")
        print(f"    inputs       {', '.join(entry['inputs']) or '(none: passive)'}")
    return EXIT_OK


# -- gaitopt solve -------------------------------------------------------------------------------
def _model_arguments(parser: argparse.ArgumentParser) -> None:
    """``MODEL`` and ``--set``, shared by the subcommands that act on one model."""
    parser.add_argument("model", metavar="MODEL", help=f"model name (see `{PROG} list`)")
    parser.add_argument(
        "--set",
        action="append",
        metavar="NAME=VALUE",
        help="change a parameter from its default (repeatable)",
    )
    parser.add_argument("--json", action="store_true", help="print one JSON object")


def _gait_arguments(parser: argparse.ArgumentParser) -> None:
    """``--guess`` and ``--steps``: which gait to find (shared by ``solve`` and ``continue``)."""
    parser.add_argument(
        "--guess",
        action="append",
        metavar="STATE=VALUE",
        help="initial guess of a section coordinate (repeatable; others from the default start)",
    )
    parser.add_argument(
        "--steps",
        type=_count(1, MAX_ORBIT_STEPS, _ORBIT_LIMIT),
        default=1,
        metavar="K",
        help=f"returns to the section per orbit (2: a period-2 gait; default 1, at most "
        f"{MAX_ORBIT_STEPS})",
    )


def _solve_arguments(parser: argparse.ArgumentParser) -> None:
    _model_arguments(parser)
    _gait_arguments(parser)
    parser.add_argument(
        "--method",
        choices=("newton", "ipopt"),
        default="newton",
        help="Newton rootfinder on the shooting equations (default) or IPOPT",
    )
    parser.add_argument(
        "--starts",
        type=_count(1),
        default=1,
        metavar="N",
        help="also run a seeded multi-start search from N starts around the default start and "
        "list every distinct gait found, with its stability (default 1: none)",
    )
    parser.add_argument(
        "--seed", type=_count(0), default=0, help="seed of the multi-start sample (default 0)"
    )
    parser.add_argument(
        "--scheduler",
        type=_scheduler_address,
        default=None,
        metavar="ADDRESS",
        help="run the multi-start on Dask: 'local' or a scheduler address (default: serial)",
    )


def _print_cycle(cycle: LimitCycle) -> None:
    model = cycle.model
    _print_rows(
        [
            ("model", f"{model.name} ({model.title})"),
            ("params", _format_params(model.params)),
            ("success", cycle.success),
            ("message", cycle.message),
        ]
    )
    if not cycle.success:
        return
    _print_rows([("period", f"{cycle.period:.10g} ({cycle.steps} step(s) per orbit)")])
    print(f"fixed point (section: {model.section.doc})")
    for name, value in cycle.fixed_point.items():
        print(f"    {name:<12}{value: .10g}")
    print("multipliers")
    for z in cycle.multipliers:
        print(f"    {z.real: .8f} {z.imag:+.8f}j    |λ| = {abs(z):.8f}")
    _print_rows([("stable", cycle.stable), ("verified", cycle.verified)])
    if cycle.route:
        _print_rows([("route", cycle.route)])
    if cycle.gaits:
        print(f"distinct gaits of the multi-start ({len(cycle.gaits)})")
        for k, gait in enumerate(cycle.gaits, start=1):
            mods = ", ".join(f"{abs(complex(*z)):.6f}" for z in gait["multipliers"])
            where = ", ".join(f"{n}={v:.8g}" for n, v in gait["fixed_point"].items())
            kind = "stable" if gait["stable"] else "unstable"
            print(
                f"    {k}. period {gait['period']:.10g}  |λ| = [{mods}]  {kind}  "
                f"({gait['starts']} start(s))  {where}"
            )


def run_solve(args: argparse.Namespace) -> int:
    """``gaitopt solve``: find a gait by multiple shooting, with its multipliers."""
    model = build_model(args.model, args.set)
    guess = parse_guess(model, args.guess)
    try:
        with _solver_output_to_stderr():
            cycle = find_limit_cycle(
                model,
                guess,
                steps=args.steps,
                method=args.method,
                starts=args.starts,
                seed=args.seed,
                scheduler=args.scheduler,
            )
    except GuessError as exc:
        raise InputError(f"{_echo('--guess', args.guess or ()) or '--guess'}: {exc}") from None
    except OSError as exc:  # a Dask scheduler that cannot be reached
        if args.scheduler in (None, "local"):
            raise
        raise InputError(f"--scheduler {args.scheduler}: cannot reach it ({exc})") from None
    if args.json:
        _print_json(cycle.as_dict())
    else:
        _print_cycle(cycle)
    return EXIT_OK if cycle.success else EXIT_NOT_FOUND


# -- gaitopt simulate ----------------------------------------------------------------------------
def _simulate_arguments(parser: argparse.ArgumentParser) -> None:
    _model_arguments(parser)
    parser.add_argument(
        "--x0",
        action="append",
        metavar="STATE=VALUE",
        help="start state (repeatable): section coordinates (others from the default start), "
        "or every state",
    )
    parser.add_argument(
        "--steps",
        type=_count(1, MAX_SIMULATION_STEPS, _SIMULATION_LIMIT),
        default=10,
        metavar="N",
        help=f"returns to the section to simulate (default 10, at most {MAX_SIMULATION_STEPS})",
    )
    parser.add_argument(
        "--controller",
        choices=("lqr", "acker", "deadbeat", "blind"),
        help="step-to-step controller around the model's gait (default: open loop at the "
        "nominal input); blind: the SLIP's swing-leg law, deadbeat on unknown ground",
    )
    parser.add_argument(
        "--target",
        action="append",
        metavar="STATE=VALUE",
        help="with --controller: drive to this section point instead of the gait's fixed point "
        "(e.g. slip: --target z=1.0)",
    )
    parser.add_argument(
        "--terrain",
        metavar="SEED:AMPLITUDE",
        help="seeded random ground: each step the ground parameter (slip: ground_height, m; "
        "walkers: slope, rad) drawn within ±AMPLITUDE of its value",
    )


def describe_simulation(model: HybridModel, sim: Simulation, requested: int) -> dict[str, Any]:
    """The ``gaitopt simulate --json`` object."""
    names = model.state_names
    return {
        "model": model.name,
        "params": model.params,
        "success": sim.success,
        "status": sim.status,
        "message": sim.message,
        "steps": sim.steps,
        "requested_steps": requested,
        "state_names": list(names),
        "section_coordinates": list(model.section.coordinates),
        "section": model.section.doc,
        "returns": [
            {"t": t, "state": dict(zip(names, row, strict=True))}
            for t, row in zip(sim.section_times, sim.section_states, strict=True)
        ],
        "events": [{"t": event.t, "transition": event.transition} for event in sim.events],
    }


def _print_simulation(report: Mapping[str, Any]) -> None:
    _print_rows(
        [
            ("model", report["model"]),
            ("params", _format_params(report["params"])),
            ("status", f"{report['status']}: {report['message']}"),
        ]
    )
    names = report["state_names"]
    print(f"returns to the section ({report['section']})")
    print(f"    {'t':>12}" + "".join(f"{name:>14}" for name in names))
    for entry in report["returns"]:
        values = "".join(f"{entry['state'][name]:14.8f}" for name in names)
        print(f"    {entry['t']:12.6f}{values}")


def parse_terrain(model: HybridModel, text: str | None):
    """``--terrain SEED:AMPLITUDE`` as a :class:`gaitopt.terrain.RandomTerrain` (or ``None``)."""
    if text is None:
        return None
    from .terrain import random_terrain

    seed, sep, amplitude = (part.strip() for part in text.partition(":"))
    example = "--terrain 1:0.05"
    try:
        seed_value, amplitude_value = int(seed), float(amplitude)
    except ValueError:
        seed_value, amplitude_value = -1, math.nan
    if not sep or seed_value < 0 or not (math.isfinite(amplitude_value) and amplitude_value >= 0):
        raise InputError(
            f"--terrain {text}: expected SEED:AMPLITUDE (a non-negative integer seed and a "
            f"non-negative amplitude), e.g. {example}"
        )
    try:
        return random_terrain(model, seed_value, amplitude_value)
    except GaitoptInputError as exc:
        raise InputError(f"--terrain {text}: {exc}") from None


def _simulation_controller(model: HybridModel, kind: str | None, target):
    """The model to simulate and its policy for ``--controller`` (open loop: ``None``)."""
    if kind is None:
        if target is not None:
            raise InputError("--target needs --controller (open loop runs at the nominal input)")
        return model, None, None
    from .control import ControlDesignError, NoGaitError, deadbeat, design_controller
    from .terrain import BlindPolicy

    try:
        with _solver_output_to_stderr():
            if kind == "blind":
                if model.name != "slip":
                    raise ControlDesignError(
                        f"the blind swing-leg policy is for slip only, not {model.name}; "
                        f"use --controller lqr or deadbeat"
                    )
                controller = deadbeat(model, target=target)
                policy = BlindPolicy(controller, heights=(-0.1, 0.1))
                return policy.model(), policy, controller
            controller = design_controller(model, kind, target=target)
    except ControlDesignError as exc:
        raise InputError(f"--controller {kind}: {exc}") from None
    except NoGaitError as exc:
        raise _NoGait(str(exc)) from None
    return model, controller, controller


class _NoGait(Exception):
    """No gait to control: exit 1."""


def run_simulate(args: argparse.Namespace) -> int:
    """``gaitopt simulate``: simulate the hybrid model and report each return to the section."""
    model = build_model(args.model, args.set)
    x0 = parse_x0(model, args.x0)
    terrain = parse_terrain(model, args.terrain)
    target = parse_guess(model, args.target) if args.target else None
    if target is not None:
        _check_point(model, "--target", args.target, target)
    try:
        simulated, policy, controller = _simulation_controller(model, args.controller, target)
    except _NoGait as exc:
        print(f"{PROG}: {exc}", file=sys.stderr)
        return EXIT_NOT_FOUND
    sim = simulate(simulated, x0, steps=args.steps, inputs=policy, terrain=terrain)
    report = describe_simulation(model, sim, args.steps)
    if args.controller is not None or terrain is not None:
        report["controller"] = (
            None
            if controller is None
            else {
                "kind": args.controller,
                "target": dict(
                    zip(model.section.coordinates, map(float, controller.target), strict=True)
                ),
                "gain": controller.gain.tolist(),
            }
        )
        report["inputs"] = [
            dict(zip(simulated.inputs, map(float, arc.u), strict=True))
            for arc in sim.arcs
            if arc.phase == 0
        ]
        report["terrain"] = sim.step_parameters
    if args.json:
        _print_json(report)
    else:
        _print_simulation(report)
    return EXIT_OK if sim.success else EXIT_NOT_FOUND


# -- gaitopt control -----------------------------------------------------------------------------
def _control_arguments(parser: argparse.ArgumentParser) -> None:
    _model_arguments(parser)
    parser.add_argument(
        "--kind",
        required=True,
        choices=("lqr", "acker", "deadbeat"),
        help="discrete LQR (python-control dlqr), pole placement (acker) or deadbeat",
    )
    parser.add_argument(
        "--guess",
        action="append",
        metavar="STATE=VALUE",
        help="guess of the gait to control (section coordinates, repeatable)",
    )
    parser.add_argument(
        "--target",
        action="append",
        metavar="STATE=VALUE",
        help="make this section point the fixed point (solving for the nominal input; as many "
        "inputs as section coordinates, e.g. slip: --target z=1.0)",
    )
    parser.add_argument(
        "--q", metavar="Q", help="LQR state weight: a number or comma-separated diagonal"
    )
    parser.add_argument(
        "--r", metavar="R", help="LQR input weight: a number or comma-separated diagonal"
    )
    parser.add_argument(
        "--poles",
        metavar="P",
        help="acker: comma-separated closed-loop multipliers (default all 0)",
    )
    parser.add_argument(
        "--from",
        dest="start",
        action="append",
        metavar="STATE=VALUE",
        help="decide the input from this section state (repeatable) and take one step",
    )


def _numbers(option: str, text: str | None, kind: type = float) -> list | None:
    """``--q 1,2,3``: a list of finite numbers (``None`` if the option is absent)."""
    if text is None:
        return None
    values = []
    for part in text.split(","):
        try:
            value = kind(part.strip().replace("i", "j"))
        except ValueError:
            raise InputError(
                f"{option} {text}: {part.strip()!r} is not a number; e.g. {option} 1,0.5"
            ) from None
        if not np.isfinite(value):
            raise InputError(f"{option} {text}: {part.strip()!r} is not finite")
        values.append(value)
    return values


def _describe_decision(controller, decision, sim: Simulation | None) -> dict[str, Any]:
    model = controller.model
    out: dict[str, Any] = {
        "from": dict(zip(model.section.coordinates, map(float, decision.state), strict=True)),
        "input": dict(zip(model.inputs, map(float, decision.input), strict=True)),
        "decision_success": bool(decision.success),
        "decision": decision.message,
        "predicted": dict(
            zip(model.section.coordinates, map(float, decision.predicted), strict=True)
        ),
        "next": None,
    }
    if sim is not None and sim.success:
        x = sim.section_states[-1]
        out["next"] = dict(zip(model.state_names, map(float, x), strict=True))
        out["next_error"] = float(
            np.max(np.abs(model.section_coordinates_of(x) - controller.target))
        )
    elif sim is not None:
        out["step"] = sim.message
    return out


def run_control(args: argparse.Namespace) -> int:
    """``gaitopt control``: design a step-to-step controller around the model's gait."""
    from .control import ControlDesignError, NoGaitError, design_controller

    model = build_model(args.model, args.set)
    guess = parse_guess(model, args.guess)
    target = parse_guess(model, args.target) if args.target else None
    if target is not None:
        _check_point(model, "--target", args.target, target)
    if target is not None:
        target = {**{k: v for k, v in model.default_start().items()}, **target}
    options: dict[str, Any] = {}
    q, r = _numbers("--q", args.q), _numbers("--r", args.r)
    poles = _numbers("--poles", args.poles, complex)
    for option, value, kind in (("--q", q, "lqr"), ("--r", r, "lqr"), ("--poles", poles, "acker")):
        if value is not None and args.kind != kind:
            raise InputError(f"{option} applies to --kind {kind}, not --kind {args.kind}")
    if args.kind == "lqr":
        options.update(Q=q if q is None or len(q) > 1 else q[0])
        options.update(R=r if r is None or len(r) > 1 else r[0])
    if args.kind == "acker" and poles is not None:
        options["poles"] = poles
    start = None
    if args.start:
        start = _assignments("--from", args.start, _state_examples(model))
        for name, (item, _) in start.items():
            if name not in model.section.coordinates:
                coordinates = model.section.coordinates
                raise InputError(
                    f"--from {item}: {did_you_mean(name, coordinates)}--from takes the section "
                    f"coordinates {', '.join(repr(c) for c in coordinates)} (the other states "
                    f"follow from the section)"
                )
        _check_point(model, "--from", args.start, {n: v for n, (_, v) in start.items()})
    try:
        with _solver_output_to_stderr():
            controller = design_controller(model, args.kind, guess=guess, target=target, **options)
    except NoGaitError as exc:
        report = {"model": model.name, "params": model.params, "kind": args.kind,
                  "success": False, "message": str(exc)}  # fmt: skip
        if args.json:
            _print_json(report)
        else:
            _print_rows([("model", model.name), ("success", False), ("message", str(exc))])
        return EXIT_NOT_FOUND
    except (ControlDesignError, GaitoptInputError) as exc:
        raise InputError(f"--kind {args.kind}: {exc}") from None
    report = controller.as_dict()
    status = EXIT_OK
    if start is not None:
        s = model.section_vector({name: value for name, (_, value) in start.items()})
        decision = controller.decide(s)
        sim = simulate(model, model.lift(s), steps=1, inputs=decision.input)
        report.update(_describe_decision(controller, decision, sim))
        if not (decision.success and sim.success):
            status = EXIT_NOT_FOUND
            report["success"] = False
            report["message"] = (
                decision.message if not decision.success else f"the step falls: {sim.message}"
            )
    if args.json:
        _print_json(report)
    else:
        _print_control(report)
    return status


def _print_control(report: Mapping[str, Any]) -> None:
    _print_rows(
        [
            ("model", report["model"]),
            ("params", _format_params(report["params"])),
            ("kind", report["kind"]),
            ("success", report["success"]),
            ("message", report["message"]),
        ]
    )
    print("fixed point")
    for name, value in report["fixed_point"].items():
        print(f"    {name:<12}{value: .10g}")
    print("nominal input")
    for name, value in report["nominal_input"].items():
        print(f"    {name:<12}{value: .10g}")
    print(
        f"gain K       {report['gain']}  (u = u* − K (s − s*), s = {report['section_coordinates']})"
    )
    for label in ("open_loop_multipliers", "closed_loop_multipliers"):
        print(label.replace("_", " "))
        for re_, im in report[label]:
            print(f"    {re_: .8f} {im:+.8f}j    |λ| = {math.hypot(re_, im):.8f}")
    if "feasible_range" in report and report["feasible_range"]:
        for name, (lo, hi) in report["feasible_range"].items():
            print(f"feasible     {lo:.6g} ≤ {name} ≤ {hi:.6g} (deadbeat reaches the target)")
    if "input" in report:
        print(f"from         {report['from']}")
        print(f"input        {report['input']}  ({report['decision']})")
        print(f"next         {report['next']}")


# -- gaitopt continue ----------------------------------------------------------------------------
def _continue_arguments(parser: argparse.ArgumentParser) -> None:
    _model_arguments(parser)
    parser.add_argument("--param", required=True, metavar="NAME", help="parameter to vary")
    parser.add_argument(
        "--to", required=True, metavar="VALUE", help="parameter value to continue to"
    )
    _gait_arguments(parser)
    parser.add_argument(
        "--both", action="store_true", help="also continue away from --to, to the range's end"
    )
    parser.add_argument(
        "--no-cascade",
        action="store_true",
        help="do not switch to the period-2k branches at period doublings",
    )
    parser.add_argument(
        "--max-period",
        type=_count(1, MAX_ORBIT_STEPS, _ORBIT_LIMIT),
        default=8,
        metavar="K",
        help=f"deepest period of the period-doubling cascade (default 8, at most "
        f"{MAX_ORBIT_STEPS})",
    )
    parser.add_argument(
        "--out",
        metavar="DIR",
        help="write branch.json, branch.csv and branch.png to DIR (with --follow: curve.*)",
    )
    from .cli_curves import add_curve_arguments  # two-parameter curves (--follow)

    add_curve_arguments(parser)


def run_continue(args: argparse.Namespace) -> int:
    """``gaitopt continue``: follow a gait through a parameter; special points; cascades."""
    from .cli_curves import run_curve, wants_curve

    if wants_curve(args):  # --follow: a special point in two parameters
        return run_curve(args)
    model = build_model(args.model, args.set)
    specs = {s.name: s for s in model.parameter_specs()}
    if args.param not in specs:
        raise InputError(
            f"--param {args.param}: {model.name} has no parameter {args.param!r}; "
            f"{did_you_mean(args.param, specs)}parameters: {', '.join(specs)}"
        )
    to = _number("--to", args.to, args.to, f"{specs[args.param].default:g}")
    try:
        check_parameter(model.name, specs[args.param], to)
    except ParameterError as exc:
        raise InputError(f"--to {args.to}: {exc}") from None
    guess = parse_guess(model, args.guess)
    try:
        with _solver_output_to_stderr():
            branch = continuation(
                model,
                args.param,
                to=to,
                start=guess,
                steps=args.steps,
                both_directions=args.both,
                cascade=not args.no_cascade,
                max_period=args.max_period,
            )
    except GuessError as exc:
        raise InputError(f"{_echo('--guess', args.guess or ()) or '--guess'}: {exc}") from None
    except ParameterError as exc:
        raise InputError(f"--param {args.param} --to {args.to}: {exc}") from None
    written = write_outputs(args.out, lambda folder: _write_branch(branch, folder))
    if args.json:
        _print_json(branch.as_dict())
    else:
        _print_branch(branch)
    if written is not None:
        print(written, file=sys.stderr)
        return EXIT_BAD_INPUT
    return EXIT_OK if branch.success else EXIT_NOT_FOUND


def write_outputs(out: str | None, write: Callable[[Path], None]) -> str | None:
    """Write a subcommand's files into ``--out`` after its computation, never losing them.

    ``--out`` was checked before the computation (:func:`main`); if writing still fails (the
    directory was removed or filled meanwhile) the files go to a fresh fallback directory
    (:func:`gaitopt.files.write_or_fall_back`).

    Returns
    -------
    str or None
        None if the files are in ``--out`` (or there is no ``--out``); otherwise the one-line
        error to print on stderr, saying where the files are: the caller prints it after its
        results and exits with status 2.
    """
    from .files import write_or_fall_back

    if not out:
        return None
    try:
        folder, error = write_or_fall_back(out, write, prefix=f"{PROG}-out-")
    except OSError as exc:
        return f"{PROG}: error: --out {out}: cannot write there, nor to a fallback folder ({exc})"
    if error is None:
        return None
    reason = " ".join(str(error).split())
    return (
        f"{PROG}: error: --out {out}: cannot write there ({reason}); the results were written "
        f"to {folder} instead"
    )


def _write_branch(branch: Branch, folder: Path) -> None:
    from .files import write_csv, write_json
    from .plotting import plot_branch, save_figure

    write_json(branch.as_dict(), folder / "branch.json")
    if branch.cycles:
        write_csv(*branch.csv_rows(), folder / "branch.csv")
        fig, _ = plot_branch(branch)
        save_figure(fig, folder / "branch.png")


def _print_branch(branch: Branch) -> None:
    model = branch.model
    _print_rows(
        [
            ("model", f"{model.name} ({model.title})"),
            ("params", _format_params(model.params)),
            ("success", branch.success),
            ("message", branch.message),
        ]
    )
    for sub in branch.descendants():
        if not sub.cycles:
            continue
        lam = sub.params
        print(
            f"period-{sub.steps} branch: {len(sub.cycles)} gaits, {branch.param} from "
            f"{lam.min():.8g} to {lam.max():.8g}; {sub.message}"
        )
        for sp in sub.special_points:
            mults = ", ".join(f"{abs(z):.6f}" for z in sp.cycle.multipliers) if sp.cycle else ""
            print(
                f"    {sp.kind:<9}{branch.param} = {sp.param:.10f}   |λ| = [{mults}]   {sp.message}"
            )


# -- the command ---------------------------------------------------------------------------------
SUBCOMMANDS: dict[str, Subcommand] = {
    "list": Subcommand("list the models and their parameters", _list_arguments, run_list),
    "solve": Subcommand(
        "find a gait (periodic orbit) by multiple shooting", _solve_arguments, run_solve
    ),
    "simulate": Subcommand(
        "simulate a model and print its returns to the section", _simulate_arguments, run_simulate
    ),
    "control": Subcommand(
        "design a step-to-step controller (LQR, pole placement, deadbeat) around a gait",
        _control_arguments,
        run_control,
    ),
    "continue": Subcommand(
        "follow a gait through a parameter: special points, period-doubling cascades",
        _continue_arguments,
        run_continue,
    ),
    "linkage": Subcommand(cli_linkage.HELP, cli_linkage.add_arguments, cli_linkage.run),
    "optimize": Subcommand(cli_optimize.HELP, cli_optimize.add_arguments, cli_optimize.run),
}


def build_parser() -> argparse.ArgumentParser:
    """The ``gaitopt`` argument parser, one subparser per entry of :data:`SUBCOMMANDS`."""
    from . import __version__

    parser = _Parser(
        prog=PROG,
        description="Gaits of simple legged-locomotion models as periodic orbits of hybrid "
        "systems. Exit status: 0 found, 1 not found, 2 bad input.",
    )
    parser.add_argument("--version", action="version", version=f"{PROG} {__version__}")
    commands = parser.add_subparsers(dest="command", metavar="COMMAND", required=True)
    for name, command in SUBCOMMANDS.items():
        sub = commands.add_parser(name, help=command.help, description=command.help)
        command.add_arguments(sub)
        sub.set_defaults(run=command.run)
    return parser


def _check_out(args: argparse.Namespace) -> None:
    """``--out DIR`` of any subcommand: checked before the computation, so that an unusable path
    fails in a second instead of after a long run (:func:`gaitopt.files.check_output_folder`)."""
    out = getattr(args, "out", None)
    if out is None:
        return
    from .files import check_output_folder

    try:
        check_output_folder(out)
    except GaitoptInputError as exc:
        raise InputError(f"--out {out}: {exc}") from None


def main(argv: Sequence[str] | None = None) -> int:
    """Run ``gaitopt`` with ``argv`` (default ``sys.argv[1:]``); return the exit status.

    Parameters
    ----------
    argv : sequence of str, optional
        The arguments after the program name.

    Returns
    -------
    int
        0 found / completed, 1 not found / not completed, 2 bad input.
    """
    parser = build_parser()
    try:
        args = parser.parse_args(argv)
    except SystemExit as exc:  # usage errors (2) and --help (0) exit from inside argparse
        return exc.code if isinstance(exc.code, int) else EXIT_BAD_INPUT
    try:
        _check_out(args)
        with warnings.catch_warnings():
            # The results say in words what went wrong; NumPy's and SciPy's numerical warnings
            # (an overflow while a diverging guess is simulated) would only add lines to stderr.
            warnings.simplefilter("ignore", RuntimeWarning)
            return args.run(args)
    except InputError as exc:
        message = " ".join(str(exc).split())  # one line, whatever the message holds
        print(f"{PROG}: error: {message}", file=sys.stderr)
        return EXIT_BAD_INPUT
    except GaitoptInputError as exc:  # raised by the library, wherever the input reached it
        message = " ".join(str(exc).split())
        print(f"{PROG}: error: {args.command}: {message}", file=sys.stderr)
        return EXIT_BAD_INPUT
    except BrokenPipeError:  # `gaitopt ... | head`: the reader left; say nothing more
        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
        return EXIT_NOT_FOUND


if __name__ == "__main__":
    sys.exit(main())
