"""What every subcommand shares: exit codes, the one-line error, and the parsers of models,
parameters, states and shared arguments (printing and ``--out``: :mod:`gaitopt.cli.output`)."""

from __future__ import annotations

import argparse
from collections.abc import Callable, Iterable, Mapping, Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, NoReturn

from ..errors import (
    MAX_ORBIT_STEPS,
    GaitoptInputError,
    ParameterError,
    StateError,
    did_you_mean,
)
from ..parameters import ParameterSpec, check_parameter

if TYPE_CHECKING:  # annotations only: `gaitopt list` and `--help` need no CasADi
    import numpy as np

    from ..hybrid import HybridModel

PROG = "gaitopt"
EXIT_OK = 0
EXIT_NOT_FOUND = 1
EXIT_BAD_INPUT = 2
EXIT_INTERRUPTED = 130  # Ctrl-C (SIGINT): 128 + 2, as a shell reports a command it interrupted


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


def _count_option(
    parser: argparse.ArgumentParser,
    flag: str,
    default: int,
    limits: tuple[int, int, str],
    help: str,
    metavar: str = "N",
) -> None:
    """Declare ``flag N``: a whole number within ``limits = (minimum, maximum, why)`` (see
    :func:`_count`), with ``(default D, at most M)`` appended to ``help`` (``(default D; m to
    M)`` when the minimum is not 1)."""
    low, high, why = limits
    span = f"at most {high}" if low == 1 else f"{low} to {high}"
    parser.add_argument(
        flag,
        type=_count(low, high, why),
        default=default,
        metavar=metavar,
        help=f"{help} (default {default}{', ' if low == 1 else '; '}{span})",
    )


def _items_option(
    parser: argparse.ArgumentParser, flag: str, help: str, metavar: str = "STATE=VALUE"
) -> None:
    """Declare a repeatable ``flag NAME=VALUE`` (a list of the items given, or None)."""
    parser.add_argument(flag, action="append", metavar=metavar, help=help)


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


def _number(
    option: str, item: str, text: str, example: str, parse: Callable[[str], Any] = float
) -> Any:
    """A finite number ``parse(text)`` (a float by default: ``0.09``, ``1e-2``), or an
    :class:`InputError` naming ``option item`` with the ``example``."""
    try:
        value = parse(text)
    except ValueError:
        raise InputError(
            f"{option} {item}: {text!r} is not a number; e.g. {option} {example}"
        ) from None
    import numpy as np  # here: importing the CLI loads no NumPy (threads.start_with_blas_threads)

    if not np.isfinite(value):
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
    """The model class called ``name``: registered, or declared by an installed package's
    entry point (group ``gaitopt.models``, loaded now: :func:`gaitopt.models.model_class`)."""
    from ..errors import UnknownModelError
    from ..models import REGISTRY, model_class, model_names

    if name in REGISTRY:  # no scan of the installed packages' entry points (importlib.metadata)
        return model_class(name)
    names = model_names()
    if name not in names:
        raise InputError(
            f"MODEL {name!r} is not a model; {did_you_mean(name, names)}"
            f"available: {', '.join(names)} (see `{PROG} list`)"
        )
    try:
        return model_class(name)
    except UnknownModelError as exc:  # an installed package's entry point that does not load
        raise InputError(f"MODEL {name}: {exc}") from None


def _parameter(
    model_name: str,
    specs: Mapping[str, ParameterSpec],
    item: str,
    listing: str = "parameters: {} (see `" + PROG + " list`)",
) -> tuple[str, float]:
    """One ``--set NAME=VALUE``: a known parameter, a number, in its range; ``listing`` (with
    ``{}`` for the names) ends the message for an unknown name."""
    examples = {name: f"{name}={spec.default:g}" for name, spec in specs.items()}
    name, text = _split("--set", item, examples)
    if name not in specs:
        raise InputError(
            f"--set {item}: {model_name} has no parameter {name!r}; "
            f"{did_you_mean(name, specs)}{listing.format(', '.join(specs))}"
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
    from ..control import check_section_point

    try:
        check_section_point(model, point, option.lstrip("-"), label=_echo(option, items))
    except GaitoptInputError as exc:
        raise InputError(str(exc)) from None


# -- shared arguments ----------------------------------------------------------------------------
def _model_arguments(parser: argparse.ArgumentParser) -> None:
    """``MODEL`` and ``--set``, shared by the subcommands that act on one model."""
    parser.add_argument("model", metavar="MODEL", help=f"model name (see `{PROG} list`)")
    _items_option(
        parser, "--set", "change a parameter from its default (repeatable)", metavar="NAME=VALUE"
    )
    parser.add_argument("--json", action="store_true", help="print one JSON object")


def _gait_arguments(parser: argparse.ArgumentParser) -> None:
    """``--guess`` and ``--steps``: which gait to find (shared by ``solve`` and ``continue``)."""
    _items_option(
        parser,
        "--guess",
        "initial guess of a section coordinate (repeatable; others from the default start)",
    )
    _count_option(
        parser,
        "--steps",
        1,
        (1, MAX_ORBIT_STEPS, _ORBIT_LIMIT),
        "returns to the section per orbit, 2 for a period-2 gait",
        metavar="K",
    )


def _numbers(option: str, text: str | None, kind: type = float) -> list | None:
    """``--q 1,2,3``: a list of finite numbers (``None`` if the option is absent); ``kind``
    ``complex`` reads ``1+2i`` as ``1+2j``."""
    if text is None:
        return None
    return [
        _number(option, text, part.strip(), "1,0.5", lambda t: kind(t.replace("i", "j")))
        for part in text.split(",")
    ]
