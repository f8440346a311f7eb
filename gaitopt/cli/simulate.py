"""``gaitopt simulate``: a model simulated, open loop or with a controller, on rough terrain."""

from __future__ import annotations

import argparse
import math
import sys
from collections.abc import Mapping
from typing import Any

from ..errors import (
    MAX_SIMULATION_STEPS,
    GaitoptInputError,
)
from ..hybrid import HybridModel
from ..simulation import Simulation, simulate
from .common import (
    _SIMULATION_LIMIT,
    EXIT_NOT_FOUND,
    EXIT_OK,
    PROG,
    InputError,
    _check_point,
    _count_option,
    _items_option,
    _model_arguments,
    build_model,
    parse_guess,
    parse_x0,
)
from .output import _format_params, _print_json, _print_rows, _solver_output_to_stderr


# -- gaitopt simulate ----------------------------------------------------------------------------
def _simulate_arguments(parser: argparse.ArgumentParser) -> None:
    _model_arguments(parser)
    _items_option(
        parser,
        "--x0",
        "start state (repeatable): section coordinates (others from the default start), "
        "or every state",
    )
    _count_option(
        parser,
        "--steps",
        10,
        (1, MAX_SIMULATION_STEPS, _SIMULATION_LIMIT),
        "returns to the section to simulate",
    )
    parser.add_argument(
        "--controller",
        choices=("lqr", "acker", "deadbeat", "blind"),
        help="step-to-step controller around the model's gait (default: open loop at the "
        "nominal input); blind: the SLIP's swing-leg law, deadbeat on unknown ground",
    )
    _items_option(
        parser,
        "--target",
        "with --controller: drive to this section point instead of the gait's fixed point "
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
    from ..terrain import random_terrain

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
    from ..control import ControlDesignError, NoGaitError, deadbeat, design_controller
    from ..terrain import BlindPolicy

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
