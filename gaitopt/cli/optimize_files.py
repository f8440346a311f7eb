"""The files of an optimal gait (``gaitopt optimize --out DIR`` and the optimal-gait studies)."""

from __future__ import annotations

from pathlib import Path
from typing import Any

__all__ = ["write_optimal"]


def write_optimal(gait: Any, report: dict[str, Any], folder: Path) -> None:
    """Write an optimal gait's files into ``folder``: ``optimal.json`` (``report``, the
    ``optimize --json`` object), ``inputs.csv`` (s, input units), ``inputs.png``, ``orbit.png``
    and, for a verified gait of a model with drawn points, ``gait.gif`` (three steps simulated
    with the optimal inputs as a feedforward).  Each file is written atomically.

    Parameters
    ----------
    gait : OptimalGait
        The result of :func:`gaitopt.optimize_gait`.
    report : dict
        Its JSON object.
    folder : pathlib.Path
        Created if missing.
    """
    import matplotlib

    matplotlib.use("Agg")

    from ..animation import animate_walker
    from ..files import write_csv, write_json
    from ..optimize.verify import feedforward_of
    from ..plotting import save_figure
    from ..plotting.optimal import plot_optimal_inputs, plot_optimal_orbit
    from ..simulation import simulate

    folder.mkdir(parents=True, exist_ok=True)
    write_json(report, folder / "optimal.json")
    if not gait.inputs:
        return
    names = list(gait.model.inputs)
    time = gait.inputs["time"]
    rows = zip(time, *[gait.inputs[n] for n in names], strict=True)
    unit = gait.model.time_unit  # "time_s"; "time_τ" in dimensionless time
    write_csv([f"time_{unit}" if unit != "1" else "time", *names], rows, folder / "inputs.csv")
    save_figure(plot_optimal_inputs(gait)[0], folder / "inputs.png")
    if gait.orbit:
        save_figure(plot_optimal_orbit(gait)[0], folder / "orbit.png")

    if gait.success:
        x0 = gait.model.state_vector(gait.fixed_point)
        sim = simulate(
            gait.model, x0, steps=3, feedforward=feedforward_of(gait.profiles), rtol=1e-10
        )
        if sim.success and all(ph.points is not None for ph in gait.model.phases):
            animate_walker(gait.model, sim, folder / "gait.gif")
