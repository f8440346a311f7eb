"""The text report of ``gaitopt optimize`` (:func:`print_report`, :func:`report_items`)."""

from __future__ import annotations

from typing import Any

__all__ = ["print_report", "report_items"]


def print_report(report: dict[str, Any], model: Any) -> None:
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

    print_block(report_items(report, model))


def report_items(report: dict[str, Any], model: Any) -> list[Any]:
    """The rows (``(label, value)``) and lines of :func:`print_report`, in order."""
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
