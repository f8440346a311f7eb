"""Figures and the ``make gaits`` runner: phase portraits, staircase plots, walker GIFs.

Smoke-level but honest: each test checks what the figure shows against the numbers it was drawn
from (the orbit, a closed form, the ground line), not only that a file appeared.
"""

from __future__ import annotations

import dataclasses
import json
import math
import re

import matplotlib

matplotlib.use("Agg")

import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import pytest  # noqa: E402
from PIL import Image  # noqa: E402

import gaitopt  # noqa: E402
from gaitopt.animation import animate_walker, gif_name, walker_frames  # noqa: E402
from gaitopt.errors import GaitoptInputError  # noqa: E402
from gaitopt.files import write_json  # noqa: E402
from gaitopt.gaits import main as gaits_main  # noqa: E402
from gaitopt.plotting import plot_phase_portrait, plot_return_map  # noqa: E402


@pytest.fixture(scope="module")
def compass() -> gaitopt.LimitCycle:
    cycle = gaitopt.find_limit_cycle(gaitopt.model("compass_gait"))
    assert cycle.success, cycle.message
    return cycle


@pytest.fixture(autouse=True)
def _close_figures():
    yield
    plt.close("all")


def _hidden(folder) -> list[str]:
    return sorted(p.name for p in folder.rglob(".*"))


# -- phase portrait ---------------------------------------------------------------------------


def test_phase_portrait_compass_gait_lines_match_the_orbit(compass):
    fig, ax = plot_phase_portrait(compass)
    (arc,) = compass.orbit
    # Two coordinates with rates (stance, swing); each: one orbit arc and one heel-strike jump.
    lines = ax.get_lines()
    assert len(lines) == 2 * (1 + 1)
    solid = {ln.get_label(): ln for ln in lines if ln.get_linestyle() == "-"}
    dashed = [ln for ln in lines if ln.get_linestyle() == "--"]
    assert set(solid) == {"stance", "swing"} and len(dashed) == 2
    for q, line in solid.items():
        x = arc.x[arc.states.index(q)]
        v = arc.x[arc.states.index(q + "_dot")]
        assert (line.get_xdata().min(), line.get_xdata().max()) == (x.min(), x.max())
        assert (line.get_ydata().min(), line.get_ydata().max()) == (v.min(), v.max())
    # Each jump runs from the pre-impact state to the post-impact state (the fixed point).
    fp = compass.fixed_point
    ends = {(ln.get_xdata()[1], ln.get_ydata()[1]) for ln in dashed}
    assert ends == {(fp["stance"], fp["stance_dot"]), (fp["swing"], fp["swing_dot"])}
    # The axes show every state of the orbit.
    x0, x1 = ax.get_xlim()
    y0, y1 = ax.get_ylim()
    assert x0 <= arc.x[:2].min() and arc.x[:2].max() <= x1
    assert y0 <= arc.x[2:].min() and arc.x[2:].max() <= y1
    assert "0.734461" in ax.get_title()  # period (Drake's CompassGait: 0.7344606 s)


def test_phase_portrait_overlays_one_transient_line_per_coordinate(compass):
    sim = gaitopt.simulate(compass.model, steps=2)
    _, ax = plot_phase_portrait(compass, simulation=sim)
    grey = [ln for ln in ax.get_lines() if ln.get_label() == "simulated transient"]
    assert len(ax.get_lines()) == 4 + 2 and len(grey) == 1
    assert np.isnan(grey[0].get_xdata()).sum() == len(sim.arcs)  # broken at every reset


def test_phase_portrait_of_a_two_step_orbit_draws_every_arc_and_impact():
    # The rimless wheel's gait written out over two steps (find_limit_cycle(steps=2) refuses a
    # repeated period-1 gait): two arcs, two impacts, one coordinate.
    one = gaitopt.find_limit_cycle(gaitopt.model("rimless_wheel"))
    (arc,) = one.orbit
    second = dataclasses.replace(arc, t=arc.t + one.period, x=arc.x.copy())
    cycle = dataclasses.replace(one, orbit=[arc, second], steps=2, period=2 * one.period)
    _, ax = plot_phase_portrait(cycle)
    assert len(cycle.orbit) == 2 and len(ax.get_lines()) == 2 + 2
    labels = [t.get_text() for t in ax.get_legend().get_texts()]
    assert labels == ["theta", "reset (impact)"]


def test_phase_portrait_refuses_a_failed_search():
    failed = gaitopt.LimitCycle(False, "did not converge", gaitopt.model("compass_gait"))
    with pytest.raises(GaitoptInputError, match="success=False"):
        plot_phase_portrait(failed)


# -- return map -------------------------------------------------------------------------------


def test_rimless_wheel_staircase_marks_the_closed_form_rolling_fixed_point():
    model = gaitopt.model("rimless_wheel")
    _, ax = plot_return_map(
        model, (0.5, 2.0), start=1.9, iterations=5, closed_form=model.closed_form_map, samples=30
    )
    by_gid = {ln.get_gid(): ln for ln in ax.get_lines() if ln.get_gid()}
    stable = by_gid["stable fixed points"].get_xdata()
    assert len(by_gid["unstable fixed points"].get_xdata()) == 0
    # Source: Tedrake, Underactuated Robotics, "Simple models of walking", rimless wheel:
    # ω* = cot 2α · sqrt(4 g/l sin α sin γ) = 1.095462839648 rad/s at the defaults.
    assert len(stable) == 1
    assert abs(stable[0] - model.rolling_speed()) < 1e-8
    assert math.isclose(model.rolling_speed(), 1.095462839648, abs_tol=1e-12)

    # The sampled map breaks at the vaulting speed ω₁ (rocking below, rolling above) ...
    curve = next(ln for ln in ax.get_lines() if ln.get_label().startswith("return map"))
    x, y = np.asarray(curve.get_xdata()), np.asarray(curve.get_ydata())
    (gap,) = np.flatnonzero(np.isnan(x))
    assert abs(x[gap - 1] - model.vaulting_speed()) < 1e-6
    assert abs(x[gap + 1] - model.vaulting_speed()) < 1e-6
    # ... and on the rolling branch agrees with the closed-form map (energy + momentum).
    rolling = np.isfinite(x) & (x > model.vaulting_speed() + 1e-3)
    closed = np.array([model.closed_form_map(s) for s in x[rolling]])
    np.testing.assert_allclose(y[rolling], closed, atol=1e-8)
    # The staircase starts on the diagonal and each step lands on the map.
    stair = next(ln for ln in ax.get_lines() if ln.get_label().startswith("staircase"))
    sx, sy = stair.get_xdata(), stair.get_ydata()
    assert (sx[0], sy[0]) == (1.9, 1.9)
    np.testing.assert_allclose(sy[1::2], [model.closed_form_map(s) for s in sx[1::2]], atol=1e-8)


def test_return_map_needs_a_one_dimensional_section():
    with pytest.raises(GaitoptInputError, match="1-D section"):
        plot_return_map(gaitopt.model("compass_gait"), (0.0, 1.0))


# -- animation --------------------------------------------------------------------------------


def test_walker_gif_has_frames_and_steps_land_on_the_ground(compass, tmp_path):
    model = compass.model
    sim = gaitopt.simulate(model, compass.x, steps=2)
    assert sim.success, sim.message
    path = animate_walker(model, sim, tmp_path / "walk.gif", fps=10, max_frames=6, dpi=30)
    with Image.open(path) as im:
        assert im.format == "GIF"
        assert im.n_frames == 6  # 1.47 s at 10 fps needs 15 frames: capped at max_frames
        assert im.info["duration"] == 100  # ms between frames (1/fps)
    assert _hidden(tmp_path) == []  # the temporary file was moved into place

    # Each new contact point (the swing foot at heel strike) is on the ground line.
    strike = sim.events[0].state_before
    next_contact = np.asarray(model.phases[0].points(strike, model.p))[:, 2]  # swing foot
    assert next_contact[0] > 0.3  # a step of about 2 l sin(0.27) forward (downhill)
    np.testing.assert_allclose(next_contact[1], -next_contact[0] * math.tan(model.slope), atol=1e-9)
    # The second step's frames stand on it (the event instant itself still shows the first step).
    second = sim.arcs[1]
    during = walker_frames(model, sim, [0.5 * (second.t0 + second.t1)])[0]
    np.testing.assert_allclose(during["contact"], next_contact, atol=1e-12)
    first = walker_frames(model, sim, [sim.arcs[0].t1])[0]  # heel strike: still on the origin
    assert first["contact"].tolist() == [0.0, 0.0]
    np.testing.assert_allclose(first["outline"][:, 2], next_contact, atol=1e-9)


def test_models_without_geometry_are_not_animated(tmp_path):
    model = gaitopt.model("vanderpol")
    sim = gaitopt.simulate(model, steps=1)
    with pytest.raises(GaitoptInputError, match="no drawing points"):
        animate_walker(model, sim, tmp_path / "vdp.gif")
    assert list(tmp_path.iterdir()) == []


# -- the `make gaits` runner ------------------------------------------------------------------


def test_gaits_runner_writes_cycle_json_atomically(tmp_path, capsys):
    status = gaits_main(["--out", str(tmp_path), "--models", "rimless_wheel"])
    out = capsys.readouterr().out
    assert status == 0, out
    folder = tmp_path / "rimless_wheel"
    data = json.loads((folder / "cycle.json").read_text())
    assert data["model"] == "rimless_wheel" and data["success"] is True
    assert abs(data["fixed_point"]["theta_dot"] - 1.095462839648) < 1e-8  # Tedrake's ω*
    names = sorted(p.name for p in folder.iterdir())
    assert names == [
        "animation.key", "cycle.json", "phase_portrait.png", "return_map.png", "walking.gif"
    ]  # fmt: skip
    assert _hidden(tmp_path) == []  # no temporary file left behind
    assert "rimless_wheel" in out.splitlines()[-1] and "True" in out.splitlines()[-1]


def test_gaits_runner_keeps_an_animation_drawn_from_the_same_gait(tmp_path, monkeypatch):
    """A second run of the same gait by the same code keeps the GIF (its animation.key
    matches); a changed gait draws it again.  (The GIFs are most of `make gaits`' time.)"""
    import gaitopt.animation

    drawn = []
    original = gaitopt.animation.animate_walker

    def counting(*args, **kwargs):
        drawn.append(1)
        return original(*args, **kwargs)

    monkeypatch.setattr(gaitopt.animation, "animate_walker", counting)
    args = ["--out", str(tmp_path), "--models", "rimless_wheel"]
    assert gaits_main(args) == 0 and len(drawn) == 1
    gif = (tmp_path / "rimless_wheel" / "walking.gif").read_bytes()
    assert gaits_main(args) == 0 and len(drawn) == 1  # kept, not drawn again
    assert (tmp_path / "rimless_wheel" / "walking.gif").read_bytes() == gif
    key = tmp_path / "rimless_wheel" / "animation.key"
    key.write_text("another gait\n")
    assert gaits_main(args) == 0 and len(drawn) == 2  # drawn again
    assert key.read_text().strip() != "another gait"


def test_stored_gaits_keep_only_their_certified_digits():
    """cycle.json (make gaits) stores the numbers to the certificate's accuracy, so that the
    last-digit noise of another build (here: a relative perturbation of 1e-14, the size of the
    differences between two builds seen in practice) does not change the stored file, while
    the numbers stay within that accuracy of the computed ones."""
    import copy

    from gaitopt.gaits import certified_record

    record = gaitopt.find_limit_cycle(gaitopt.model("compass_gait")).as_dict(timing=False)
    noisy = copy.deepcopy(record)
    for name in noisy["fixed_point"]:
        noisy["fixed_point"][name] *= 1 + 1e-14
    noisy["period"] *= 1 - 1e-14
    noisy["residual"] *= 1.7
    stored = certified_record(record)
    assert certified_record(noisy) == stored
    accuracy = max(record["discretisation_error"], record["residual"])
    for name, value in record["fixed_point"].items():
        assert abs(stored["fixed_point"][name] - value) <= accuracy
    assert "residual < 1e-" in stored["message"] and stored["residual"] >= record["residual"]
    # Drake's CompassGait simulated to convergence (docs/design.md's reference numbers).
    assert stored["period"] == pytest.approx(0.7344606, abs=5e-8)


def test_gaits_runner_reports_a_failed_search(tmp_path, capsys, monkeypatch):
    import gaitopt.gaits

    def fail(model):
        message = "newton did not converge (test)"
        return gaitopt.LimitCycle(False, message, model, inputs=model.nominal_input())

    stale = tmp_path / "compass_gait" / "phase_portrait.png"
    stale.parent.mkdir()
    stale.write_bytes(b"from an earlier run")
    monkeypatch.setattr(gaitopt.gaits, "find_limit_cycle", fail)
    assert gaits_main(["--out", str(tmp_path), "--models", "compass_gait"]) == 1
    data = json.loads((tmp_path / "compass_gait" / "cycle.json").read_text())
    assert data["success"] is False and data["message"] == "newton did not converge (test)"
    assert sorted(p.name for p in stale.parent.iterdir()) == ["cycle.json"]
    assert "NOT SOLVED" in capsys.readouterr().out


def test_gaits_runner_rejects_unknown_models(tmp_path, capsys):
    assert gaits_main(["--out", str(tmp_path), "--models", "rimless_wheal"]) == 2
    assert "did you mean 'rimless_wheel'" in capsys.readouterr().err
    assert list(tmp_path.iterdir()) == []


def test_write_json_is_all_or_nothing(tmp_path):
    path = tmp_path / "cycle.json"
    write_json({"period": 1.0}, path)
    with pytest.raises(TypeError):
        write_json({"period": object()}, path)  # not JSON: the old file stays whole
    assert json.loads(path.read_text()) == {"period": 1.0}
    assert _hidden(tmp_path) == []


# -- every axis carries quantity, symbol and unit -------------------------------------------------
# A unit suffix: "(rad)", "(m/s)", "(dimensionless)", "[m]" at the end of the label.
_UNIT = re.compile(r"(\([^()]+\)|\[[^\[\]]+\])\s*$")
_NO_UNIT = ("unit not declared",)


def axes_without_units(fig) -> list[str]:
    """Every visible axis of ``fig`` whose label is missing or has no unit suffix (images with
    their axes switched off are exempt)."""
    bad = []
    for k, ax in enumerate(fig.axes):
        if not ax.get_visible() or not ax.axison:
            continue
        for which, label in (("x", ax.get_xlabel()), ("y", ax.get_ylabel())):
            if (
                which == "x"
                and not ax.xaxis.get_visible()
                or which == "y"
                and not (ax.yaxis.get_visible())
            ):
                continue
            if (
                which == "x"
                and not label
                and any(
                    a is not ax and a.get_shared_x_axes().joined(a, ax) and a.get_xlabel()
                    for a in fig.axes
                )
            ):
                continue  # a shared x axis labelled once, under the bottom panel
            if not _UNIT.search(label) or any(t in label for t in _NO_UNIT):
                bad.append(
                    f"axes {k} ({ax.get_title() or ax.get_title(loc='left')!r}) {which}: {label!r}"
                )
    return bad


def test_unit_audit_can_fail():
    fig, ax = plt.subplots()
    ax.plot([0, 1], [0, 1])
    ax.set_xlabel("coordinate q (rad or m")  # no closing parenthesis: no unit suffix
    ax.set_ylabel("rate")
    assert len(axes_without_units(fig)) == 2
    ax.set_xlabel("stance angle θ (rad)")
    ax.set_ylabel("stance rate θ̇ (rad/s)")
    assert axes_without_units(fig) == []


@pytest.mark.parametrize("name", sorted(gaitopt.REGISTRY))
def test_every_model_figure_labels_each_axis_with_a_unit(name, cycles):
    if not gaitopt.REGISTRY[name].passive_gait:
        pytest.skip(f"{name} has no passive gait to draw (its figures come from its study)")
    cycle = cycles[name] if name in cycles else gaitopt.find_limit_cycle(gaitopt.model(name))
    if not cycle.success:
        pytest.skip(f"{name}: no gait at the defaults to draw ({cycle.message[:60]})")
    model = cycle.model
    sim = gaitopt.simulate(model, steps=3, inputs=cycle.inputs)
    fig, _ = plot_phase_portrait(cycle, simulation=sim)
    assert axes_without_units(fig) == []
    # The period is shown with its unit.
    title = fig.axes[0].get_title()
    assert re.search(r"period [0-9.e+-]+ (s|\(dimensionless time\)|τ)", title), title
    # One unit per axis: every coordinate on an axis has the label's unit.
    for ax in fig.axes:
        unit = _UNIT.search(ax.get_xlabel()).group(0).strip("()[] ")
        for line in ax.get_lines():
            q = line.get_label()
            if q in model.state_units:
                assert model.state_units[q] in (unit, "1"), (q, unit)
    if len(model.section.coordinates) == 1:
        s = float(cycle.section_point[0])
        lo, hi = sorted((0.5 * s, 1.5 * s)) if s else (-1.0, 1.0)
        fig, ax = plot_return_map(model, (lo, hi), iterations=2, samples=6)
        assert axes_without_units(fig) == []
        # A staircase started by default is moved off a fixed point (else it shows nothing).
        stair = next(ln for ln in ax.get_lines() if ln.get_label().startswith("staircase"))
        for fp in (g for ln in ax.get_lines() if ln.get_gid() for g in ln.get_xdata()):
            assert abs(stair.get_xdata()[0] - fp) > 0.04 * (hi - lo)


def test_line_juggler_portrait_plots_the_ball_height_against_its_velocity(cycles):
    # Defect: b was plotted against the held pre-impact velocity b_dot (a flat line).  The
    # declared rate of b is v: the orbit's velocity spans ±ḃ_d (the mirror law's fixed point).
    cycle = cycles["line_juggler"]
    _, ax = plot_phase_portrait(cycle)
    (line,) = [ln for ln in ax.get_lines() if ln.get_label() == "b"]
    v = np.asarray(line.get_ydata())
    assert np.ptp(v) > 1.0  # not flat
    assert ax.get_ylabel().endswith("(m/s)")


def test_legend_lists_only_markers_that_are_drawn(cycles):
    # Defect: the vertical hopper's legend named resets whose markers were never drawn.  Its
    # bottom, liftoff and apex resets only relabel the state (y, ẏ unchanged: no jump drawn);
    # touchdown is the one drawn (the leg's mass is lost in the impact).
    cycle = cycles["vertical_hopper"]
    kinds = {arc.transition for arc in cycle.orbit}
    assert len(kinds) > 1  # several kinds of reset in the cycle ...
    _, ax = plot_phase_portrait(cycle)
    labels = [t.get_text() for t in ax.get_legend().get_texts()]
    assert labels == ["y", "touchdown (impact)"]  # ... but only one is drawn and listed


def test_branch_plot_has_parameter_units_and_log_multipliers():
    branch = gaitopt.continuation(gaitopt.model("rimless_wheel"), "slope", to=0.1)
    from gaitopt.plotting import plot_branch

    fig, (top, bottom) = plot_branch(branch)
    assert axes_without_units(fig) == []
    assert bottom.get_xlabel() == "parameter slope (rad)"
    assert bottom.get_yscale() == "log"
    assert any(ln.get_label().startswith("|λ| = 1") for ln in bottom.get_lines())


def test_gifs_are_readable_and_draw_only_declared_lines(tmp_path):
    # Defect: the Raibert hopper's GIF joined the body's ends to the foot (a polyline through
    # every point).  Its declared drawing is the leg (hip–foot) and the body (tail–nose).
    model = gaitopt.model("raibert_hopper")
    cycle = gaitopt.find_limit_cycle(model)
    sim = gaitopt.simulate(model, cycle.x, steps=1, inputs=cycle.inputs)
    frame = walker_frames(model, sim, [0.5 * (sim.arcs[0].t0 + sim.arcs[0].t1)])[0]
    pieces = np.split(frame["outline"], np.flatnonzero(np.isnan(frame["outline"][0])), axis=1)
    drawn = [p[:, ~np.isnan(p[0])].shape[1] for p in pieces]
    assert [n for n in drawn if n] == [2, 2]
    path = animate_walker(model, sim, tmp_path / "hop.gif", fps=10, max_frames=3)
    with Image.open(path) as im:
        assert im.size[0] > 420 and im.size[1] > 224  # larger than the old 420×224


# -- the ball-and-paddle scenes: the bouncing ball and the jugglers --------------------------------
def _gap_drawn(frame: dict) -> float:
    """Signed distance (m) of the drawn ball from the line through the first two drawn points
    (the table's or paddle's bar), positive on its left: above a bar drawn left to right."""
    p0, p1 = frame["outline"][:, 0], frame["outline"][:, 1]
    d = (p1 - p0) / np.hypot(*(p1 - p0))
    ball = frame["mass"][:, 0] - p0
    return float(d[0] * ball[1] - d[1] * ball[0])


@pytest.mark.parametrize("name", ["bouncing_ball", "line_juggler", "planar_juggler"])
def test_ball_scenes_render_and_draw_the_ball_above_its_paddle(name, cycles, tmp_path):
    # The drawing against the model's own declared constraint "ball above the table/paddle"
    # (y − A sin(phase); b (1 + κ) with r = −κ b; n·(x, y) for the tilted paddle): on every frame
    # of two simulated bounces from the gait, the drawn ball's distance from the drawn bar equals
    # the constraint to 1e-9 m (both are the same closed form, to rounding) and is ≥ 0.
    cycle = cycles[name]
    assert cycle.success, cycle.message
    model = cycle.model
    sim = gaitopt.simulate(model, cycle.x, steps=2, inputs=cycle.inputs)
    assert sim.success and len(sim.arcs) == 2, sim.message
    (phase,) = model.phases
    (above,) = phase.constraints
    assert above.name.startswith("ball above")
    ends = np.array([arc.t1 for arc in sim.arcs])
    times = np.linspace(sim.arcs[0].t0, sim.arcs[-1].t1, 301)  # impacts included (gap 0)
    for t, frame in zip(times, walker_frames(model, sim, times), strict=True):
        arc = sim.arcs[min(int(np.searchsorted(ends, t, side="left")), len(sim.arcs) - 1)]
        x = np.asarray(arc.solution(min(max(t, arc.t0), arc.t1)), dtype=float).ravel()
        c = float(above.function(x, cycle.inputs, model.p))
        gap = _gap_drawn(frame)
        assert gap == pytest.approx(c, abs=1e-9)
        assert gap >= -1e-9, (t, gap)
    assert max(_gap_drawn(f) for f in walker_frames(model, sim, times)) > 0.04  # it flies
    # The animation renders (no ground under these scenes: `make gaits` names it animation.gif).
    path = animate_walker(model, sim, tmp_path / "scene.gif", fps=10, max_frames=3, dpi=30)
    with Image.open(path) as im:
        assert im.format == "GIF" and im.n_frames == 3
    assert gif_name(model) == "animation.gif"
    assert gif_name(gaitopt.model("compass_gait")) == "walking.gif"
