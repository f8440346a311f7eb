"""``--optimal FILE``: an optimal gait read back from ``gaitopt optimize``'s JSON, for the
subcommands that analyse a gait (``continue``, ``continue --follow``, ``control``).

The file is ``gaitopt optimize --json``'s object (saved with ``> FILE``) or ``optimize --out
DIR``'s ``optimal.json`` (the folder itself may be given).  It carries the model, its parameters,
the fixed point, the period and the exact input profile (``profiles``: each piece's breaks and
polynomial coefficients), from which the optimum's open loop is rebuilt bit for bit
(:func:`gaitopt.orbit.feedforward.feedforward_model`).  Only a certified optimum is accepted.
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path
from typing import Any

import numpy as np

from ..errors import GaitoptInputError
from .common import InputError, _model_class

__all__ = ["add_optimal_argument", "optimal_from_args", "load_optimal"]

_REQUIRED = ("model", "params", "success", "fixed_point", "period", "profiles", "cost_kind")


def add_optimal_argument(parser: argparse.ArgumentParser) -> None:
    """``--optimal FILE``."""
    parser.add_argument(
        "--optimal",
        metavar="FILE",
        help="start from the optimal gait in FILE (`gaitopt optimize --json` saved, or "
        "`optimize --out DIR`'s optimal.json or DIR), its input profile held fixed and read on "
        "the clock since the section; MODEL must be the file's model, and --set/--guess/--steps "
        "do not apply (the file fixes them)",
    )


def optimal_from_args(args: argparse.Namespace, extra: tuple[str, ...] = ()) -> Any | None:
    """The optimal gait of ``--optimal`` (None without it), checked against MODEL and the
    options it excludes (``--set``, ``--guess``, ``--steps`` other than 1, and ``extra``:
    attribute names of further options)."""
    path = getattr(args, "optimal", None)
    if path is None:
        return None
    for option, value in (
        ("--set", getattr(args, "set", None)),
        ("--guess", getattr(args, "guess", None)),
        *((f"--{name}", getattr(args, name, None)) for name in extra),
    ):
        if value:
            raise InputError(
                f"--optimal {path}: {option} does not apply (the file fixes the gait and its "
                f"parameters); drop {option}"
            )
    if getattr(args, "steps", 1) != 1:
        raise InputError(
            f"--optimal {path}: --steps {args.steps} does not apply (the open loop of a one-step "
            f"optimum); drop --steps"
        )
    gait = load_optimal(path)
    if gait.model.name != args.model:
        raise InputError(
            f"--optimal {path}: the file holds an optimal gait of {gait.model.name}, not "
            f"{args.model}; write MODEL as {gait.model.name}"
        )
    return gait


def load_optimal(path: str) -> Any:
    """The :class:`~gaitopt.optimize.OptimalGait` written to ``path`` (a JSON file, or a folder
    with ``optimal.json``): the model at the file's parameters, fixed point, period, durations,
    multipliers and the exact profiles.

    Raises
    ------
    InputError
        Naming ``--optimal PATH`` and what is wrong: no such file, not JSON, not an optimal
        gait's object (or one written before profiles were stored), a failed optimisation.
    """
    from ..optimize import InputProfile, OptimalGait

    where = f"--optimal {path}"
    file = Path(path)
    if file.is_dir():
        file = file / "optimal.json"
    try:
        data = json.loads(file.read_text(encoding="utf-8"))
    except OSError as exc:
        raise InputError(
            f"{where}: cannot read {file} ({exc.strerror or exc}); give the JSON written by "
            f"`gaitopt optimize MODEL ... --json > FILE` or the folder of `--out DIR`"
        ) from None
    except ValueError as exc:
        raise InputError(f"{where}: {file} is not JSON ({exc})") from None
    missing = [k for k in _REQUIRED if not isinstance(data, dict) or k not in data]
    if missing:
        hint = (
            "written before optimal gaits stored their profiles: run `gaitopt optimize` again"
            if missing == ["profiles"]
            else "not the JSON of `gaitopt optimize --json`"
        )
        raise InputError(f"{where}: no {missing[0]!r} in {file} ({hint})")
    if not data["success"]:
        raise InputError(
            f"{where}: the optimal gait in {file} failed ({data.get('message', '')}); only a "
            f"certified optimum can be analysed: optimise it again with the advice given"
        )
    try:
        cls = _model_class(str(data["model"]))
        model = cls(**{k: float(v) for k, v in data["params"].items()})
        profiles = [InputProfile.from_dict(p) for p in data["profiles"]]
        fixed_point = {k: float(v) for k, v in data["fixed_point"].items()}
        model.state_vector(fixed_point)  # every state, finite
        multipliers = np.array([complex(re, im) for re, im in data.get("multipliers") or []])
        return OptimalGait(
            success=True,
            message=str(data.get("message", "")),
            model=model,
            cost_kind=str(data["cost_kind"]),
            cost=data.get("cost"),
            period=float(data["period"]),
            step_length=data.get("step_length"),
            speed=data.get("speed"),
            fixed_point=fixed_point,
            profiles=profiles,
            durations=np.asarray(data.get("durations") or [data["period"]], dtype=float),
            multipliers=multipliers,
            stable=data.get("stable"),
            verified=bool(data.get("verified", False)),
            params=dict(model.params),
            status="success",
        )
    except InputError as exc:
        raise InputError(f"{where}: {exc}") from None
    except (GaitoptInputError, KeyError, TypeError, ValueError) as exc:
        raise InputError(f"{where}: {file} does not describe an optimal gait ({exc})") from None
