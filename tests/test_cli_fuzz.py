"""Fuzz the command line: random argument lists built from the real subcommands, options, model
names, parameter and state names and nasty values (NaN, ±inf, ±1e308, empty, unicode, huge
integers, negative counts, a missing ``=``, unusable output folders ...).

Whatever the arguments, :func:`gaitopt.cli.main` must answer: no exception escapes it, the exit
status is 0, 1 or 2, and bad input (2) is exactly one line on stderr.  The subcommands and their
options are read from the parser itself, so a new subcommand is fuzzed as soon as it is added to
:data:`gaitopt.cli.SUBCOMMANDS`.

Examples are kept cheap: an argument list that could start a long computation (a continuation, a
solve after a parameter change) gets one *poison*, a bad value that every subcommand rejects
before it computes anything; only ``list`` and ``solve``/``simulate`` of fast models at their
defaults run to the end.  Profiles (tests/conftest.py): ``ci`` (default, about a minute, the same
examples every run) and ``long`` (``GAITOPT_HYPOTHESIS_PROFILE=long``, many more, random).
"""

from __future__ import annotations

import argparse
import importlib
import os
import signal
import warnings

import pytest

hypothesis = pytest.importorskip("hypothesis")
from hypothesis import given  # noqa: E402
from hypothesis import strategies as st  # noqa: E402

import gaitopt  # noqa: E402
from gaitopt import cli  # noqa: E402

#: An example still running after this long is a hang (a defect), whatever the profile's deadline.
HANG_SECONDS = 120

PARSER = cli.build_parser()
SUBPARSERS: dict[str, argparse.ArgumentParser] = next(
    a for a in PARSER._actions if isinstance(a, argparse._SubParsersAction)
).choices
#: Subcommands fuzzed: all of them, except any named in GAITOPT_FUZZ_SKIP (comma-separated), for
#: a long run while a defect already found in one subcommand awaits its fix.
COMMANDS = sorted(set(SUBPARSERS) - set(os.environ.get("GAITOPT_FUZZ_SKIP", "").split(",")))
MODELS = list(gaitopt.REGISTRY)
LINKAGES = list(getattr(importlib.import_module("gaitopt.linkage"), "LINKAGES", {}))
PARAMETERS = sorted({s.name for c in gaitopt.REGISTRY.values() for s in c.parameter_specs()})
STATES = sorted(
    {n for c in gaitopt.REGISTRY.values() for p in c.structure().phases for n in p.states}
)
JUNK_NAMES = ["", " ", "walkr", "slop", "é", "名前", "x" * 300, "-", "--", "=", "None", "0"]
NASTY = [
    "nan", "-nan", "NaN", "inf", "-inf", "Infinity", "1e308", "-1e308", "1e309", "1e-320",
    "4.9e-324", "", " ", "0", "-0", "-1", "1", "0.5", "2", "1e3", "99999999999999999999999",
    "-99999999999999999999", "abc", "é", "∞", "١٢", "１", "0x10", "1_000", "1e", "=", "==", "-",
    "--", "None", "True", "1,2", "1,nan", "1:2", "1:-1", "-1:0.1", ":", "0:inf", "a=b", "1j",
    "\t", "\\", "'", '"', "%s", "{}", "$HOME", "../../etc",
]  # fmt: skip
COUNTS = ["-5", "-1", "0", "1", "2", "65", "1000", "10001", "10000000", "99999999999999999999",
          "1.5", "1e3", "abc", "", "nan", "٣"]  # fmt: skip
BAD_FOLDERS = ["/dev/null/x", "", "\x00", "/proc/version", "x" * 300 + "/y"]
#: solve/simulate of these models at their defaults take about a second at most.
FAST_MODELS = ("vanderpol", "rimless_wheel", "bouncing_ball", "line_juggler", "vertical_hopper")


def _options(sub: argparse.ArgumentParser) -> list[argparse.Action]:
    return [a for a in sub._actions if a.option_strings and not isinstance(a, argparse._HelpAction)]


def _positionals(sub: argparse.ArgumentParser) -> list[argparse.Action]:
    return [a for a in sub._actions if not a.option_strings]


PLAUSIBLE = ["0.1", "1", "0.05", "0.9", "2", "0.5", "10", "-0.2"]


def _mostly(draw, good: list[str], bad: list[str], share: int = 4) -> str:
    """One of ``good`` ``share`` times in ``share + 1``, else one of ``bad``."""
    return draw(st.sampled_from(good if draw(st.integers(0, share)) else bad))


@st.composite
def assignment(draw) -> str:
    """``NAME=VALUE``: mostly a real name and ``=``, the value plausible or nasty."""
    name = _mostly(draw, PARAMETERS + STATES, JUNK_NAMES, share=6)
    sep = _mostly(draw, ["="], ["", "==", " = ", ":"], share=8)
    value = draw(
        st.sampled_from(PLAUSIBLE)
        | st.sampled_from(NASTY)
        | st.floats().map(repr)
        | st.integers().map(str)
    )
    return f"{name}{sep}{value}"


@st.composite
def value_for(draw, action: argparse.Action) -> str:
    """A value for one option, from what the parser says about it."""
    metavar = str(action.metavar or "")
    if action.dest == "out":
        return draw(st.sampled_from(BAD_FOLDERS))  # never write files: only refused folders
    if action.dest == "scheduler":
        return draw(st.sampled_from(["", "nowhere", "tcp://", "\x00"]))  # never start Dask
    if action.choices:
        return _mostly(draw, [str(c) for c in action.choices], NASTY)
    if "=" in metavar:
        return draw(assignment())
    if metavar in ("K", "N") or action.dest in ("steps", "max_period", "starts", "samples", "seed"):
        return _mostly(draw, ["1", "2", "3"], COUNTS, share=2)
    if metavar in ("NAME", "PARAM") or action.dest in ("param", "param2"):
        return _mostly(draw, PARAMETERS, JUNK_NAMES)
    return _mostly(draw, PLAUSIBLE, NASTY, share=1)


@st.composite
def poison(draw, sub: argparse.ArgumentParser) -> list[str]:
    """Arguments every subcommand rejects before computing anything (exit 2 at once)."""
    names = {s for a in _options(sub) for s in a.option_strings}
    kinds = [["--no-such-option"]]  # rejected by the parser (rarely: it hides everything else)
    if "--set" in names:  # rejected when the model is built, the first thing every run does
        kinds += [["--set", "no_such_parameter=1"], ["--set", "=1"], ["--set", "x"]] * 6
    if "--out" in names:  # rejected before the run
        kinds += [["--out", "/dev/null/x"]] * 3
    return draw(st.sampled_from(kinds))


#: Values no option accepts (``float`` accepts "1_000", "١٢" and "１", so those are not here).
CLEARLY_BAD = {"nan", "-nan", "NaN", "inf", "-inf", "Infinity", "1e309", "", " ", "abc", "é",
               "∞", "1e", "=", "==", "None", "True", "\t", "\\", "'", '"', "%s", "{}", "$HOME",
               "1j", "1,nan", "0:inf", "a=b"}  # fmt: skip
CLEARLY_BAD |= (set(JUNK_NAMES) - {"0"}) | set(BAD_FOLDERS)


def _clearly_bad(argv: list[str]) -> bool:
    """Whether some option value is one no subcommand may accept: then it must be rejected
    before any computation, and the example needs no poison (a slow rejection is a defect)."""
    for token in argv[1:]:
        value = token.split("=", 1)[1] if token.startswith("--") and "=" in token else token
        name, sep, rest = value.partition("=")
        if value in CLEARLY_BAD or (sep and (name in CLEARLY_BAD or rest in CLEARLY_BAD)):
            return True
    return False


def _cheap(argv: list[str]) -> bool:
    """Whether the arguments can only lead to a fast computation (or none): ``list``; ``solve``
    or ``simulate`` of a fast model without a parameter change, a controller or many steps."""
    command = argv[0]
    if command == "list":
        return True
    if command not in ("solve", "simulate") or len(argv) < 2 or argv[1] not in FAST_MODELS:
        return False
    risky = {"--set", "--scheduler", "--controller", "--target", "--terrain", "--method"}

    def few(option: str, most: int) -> bool:
        values = [argv[i + 1] for i, a in enumerate(argv[:-1]) if a == option]
        return all(v.strip().isdigit() and int(v) <= most for v in values)

    small = few("--steps", 2 if command == "solve" else 50) and few("--starts", 2)
    return small and not risky.intersection(argv)


@st.composite
def command_lines(draw) -> list[str]:
    command = draw(st.sampled_from(COMMANDS))
    sub = SUBPARSERS[command]
    argv = [command]
    for action in _positionals(sub):
        if draw(st.integers(0, 19)) > 0:  # sometimes leave the positional out
            names = LINKAGES if action.metavar == "LINKAGE" else MODELS
            argv.append(_mostly(draw, names, JUNK_NAMES, share=9))
    head = len(argv)
    options = _options(sub)
    chosen = draw(st.lists(st.sampled_from(options), max_size=5)) if options else []
    required = [a for a in options if a.required and draw(st.integers(0, 19)) > 0]
    for action in required + chosen:
        flag = draw(st.sampled_from(action.option_strings))
        if action.nargs == 0:
            argv.append(flag)
        elif draw(st.integers(0, 19)) == 0:
            argv.append(flag)  # a value missing
        else:
            value = draw(value_for(action))
            # A value that starts with '-' only reaches the option as --opt=value.
            argv += [f"{flag}={value}"] if value.startswith("-") else [flag, value]
    if not (_cheap(argv) or _clearly_bad(argv)):  # after the positionals, or at the end
        at = draw(st.sampled_from([head, len(argv)]))
        argv[at:at] = draw(poison(sub))
    return argv


class _Hang(Exception):
    pass


def _alarm(signum, frame):
    raise _Hang(f"no answer within {HANG_SECONDS} s")


@given(command_lines())
def test_cli_answers_every_argument_list(capfd, argv):
    capfd.readouterr()
    previous = signal.signal(signal.SIGALRM, _alarm)
    signal.alarm(HANG_SECONDS)
    try:
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            status = cli.main(argv)  # any exception escaping main fails the test: a traceback
    finally:
        signal.alarm(0)
        signal.signal(signal.SIGALRM, previous)
    out, err = capfd.readouterr()
    hypothesis.event(f"exit {status}" + (" (usage)" if "see `gaitopt" in err else ""))
    assert status in (0, 1, 2), (argv, status, err)
    assert "Traceback" not in err, (argv, err)
    if status == 2:
        lines = err.splitlines() + [str(w.message) for w in caught]  # a warning is a line too
        assert len(lines) == 1, (argv, lines)
        assert lines[0].startswith("gaitopt: error: "), (argv, lines)
