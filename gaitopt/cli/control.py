"""``gaitopt control``: a step-to-step controller designed around a gait and checked."""

from __future__ import annotations

import argparse
import math
from collections.abc import Mapping
from typing import Any

import numpy as np

from ..errors import (
    GaitoptInputError,
    did_you_mean,
)
from ..simulation import Simulation, simulate
from .common import (
    EXIT_NOT_FOUND,
    EXIT_OK,
    InputError,
    _assignments,
    _check_point,
    _model_arguments,
    _numbers,
    _state_examples,
    build_model,
    parse_guess,
)
from .output import _format_params, _print_json, _print_rows, _solver_output_to_stderr


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
    from .optimal_file import add_optimal_argument

    add_optimal_argument(parser)  # the per-step input is then an offset on the optimal profile
    parser.add_argument(
        "--from",
        dest="start",
        action="append",
        metavar="STATE=VALUE",
        help="decide the input from this section state (repeatable) and take one step",
    )


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
    from ..control import ControlDesignError, NoGaitError, design_controller
    from .optimal_file import optimal_from_args

    optimal = optimal_from_args(args, ("target",))  # --optimal FILE: control its open loop
    cycle = None
    if optimal is not None:
        from ..open_loop import open_loop_cycle

        with _solver_output_to_stderr():
            cycle = open_loop_cycle(optimal)
        model = cycle.model  # the per-step input: an offset on the profile
    else:
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
            controller = design_controller(
                model if cycle is None else cycle, args.kind, guess=guess, target=target,
                **options,
            )  # fmt: skip
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
