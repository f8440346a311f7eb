"""Output a person reads (issue 25, item 8): ``gaitopt optimize``'s text in ``gaitopt solve``'s
style and in the model's declared units, its figures on labelled axes, and ``gaitopt list``
without building a model, with each parameter's source.

The optimisations run in-process through :func:`gaitopt.cli.main`, each once per module (the
compass gait at a fixed step length and period solves in about a second).
"""

from __future__ import annotations

import doctest
import re

import pytest
from helpers import run_cli

from gaitopt.cli import main

#: A row of the text output: a label, at least two spaces, the value.
_ROW = re.compile(r"^(\S.*?)\s{2,}(\S.*)$")
_FIXED = ["--set", "slope=0", "--fix", "step_length=0.3", "--fix", "period=0.8"]


@pytest.fixture(scope="module")
def compass_text():
    """``gaitopt optimize compass_gait`` at slope 0, step length 0.3 m, period 0.8 s."""
    capture = _Capture()
    status = capture.run("optimize", "compass_gait", *_FIXED)
    assert status == 0, capture.out
    return capture.out


@pytest.fixture(scope="module")
def compass_free_text():
    """The same with ``--free mass_leg`` (the leg mass optimised too)."""
    capture = _Capture()
    status = capture.run("optimize", "compass_gait", *_FIXED, "--free", "mass_leg")
    assert status == 0, capture.out
    return capture.out


@pytest.fixture(scope="module")
def walker_text():
    """``gaitopt optimize simplest_walker`` on level ground at period 3.5 τ, two starts."""
    capture = _Capture()
    status = capture.run(
        "optimize", "simplest_walker", "--set", "slope=0", "--fix", "period=3.5", "--starts", "2"
    )
    assert status == 0, capture.out
    return capture.out


class _Capture:
    """Run :func:`main` capturing stdout (module-scoped fixtures cannot use ``capsys``)."""

    def run(self, *argv: str) -> int:
        import contextlib
        import io

        buffer = io.StringIO()
        with contextlib.redirect_stdout(buffer):
            status = main(list(argv))
        self.out = buffer.getvalue()
        return status


def rows(text: str) -> list[re.Match]:
    """The label rows of a text output (lines that do not start with a space)."""
    found = []
    for line in text.splitlines():
        if line and not line[0].isspace() and not line.startswith(("fixed point", "multipliers")):
            match = _ROW.match(line)
            assert match, f"a row without two spaces between label and value: {line!r}"
            found.append(match)
    return found


def indented_after(text: str, heading: str) -> list[str]:
    """The indented lines that follow the line starting with ``heading``."""
    lines = text.splitlines()
    start = next(i for i, line in enumerate(lines) if line.startswith(heading))
    block = []
    for line in lines[start + 1 :]:
        if not line.startswith("    "):
            break
        block.append(line)
    return block


def significant_digits(number: str) -> int:
    """The significant digits of a printed number: ``"0.002834387969"`` has 10."""
    mantissa = re.sub(r"e.*$", "", number).lstrip("-+")
    return len(mantissa.replace(".", "").lstrip("0"))


# -- gaitopt optimize: text ----------------------------------------------------------------------
def test_optimize_text_labels_are_one_aligned_column(compass_text):
    found = rows(compass_text)
    labels = [m.group(1) for m in found]
    for label in ("model", "cost (effort)", "period", "step length", "speed", "stable",
                  "verified", "discretisation error", "active constraints"):  # fmt: skip
        assert label in labels
    assert len({m.start(2) for m in found}) == 1  # every value starts in the same column
    # The old output ran labels into values: "cost (effort)6.67", "step length (m)0.3".
    for line in compass_text.splitlines():
        assert not re.match(r"^(cost \(\w+\)|step length( \(m\))?|discretisation error)\S", line)


def test_optimize_text_fixed_point_one_state_a_line_with_units(compass_text):
    lines = indented_after(compass_text, "fixed point (section:")
    units = {"stance": "rad", "swing": "rad", "stance_dot": "rad/s", "swing_dot": "rad/s"}
    assert len(lines) == len(units)
    for line, (name, unit) in zip(lines, units.items(), strict=True):
        assert re.fullmatch(rf"    {name}\s+-?\d\.\d+(e-?\d+)? {re.escape(unit)}", line), line
    assert "{" not in compass_text  # no dict printed raw


def test_optimize_text_multipliers_rounded(compass_text):
    lines = indented_after(compass_text, "multipliers")
    assert len(lines) == 3  # the compass gait's section is 3-D
    for line in lines:
        match = re.fullmatch(r"\s+(-?[\d.e+-]+)\s+([+−]) ([\d.e+-]+)j\s+\|λ\| = ([\d.e+-]+)", line)
        assert match, line
        for number in (match.group(1), match.group(3), match.group(4)):
            assert significant_digits(number) <= 10, number
    for number in re.findall(r"\d+\.\d+", compass_text):  # no 17-digit floats anywhere
        assert significant_digits(number) <= 10, number


def test_optimize_text_values_in_units(compass_text):
    values = {m.group(1): m.group(2) for m in rows(compass_text)}
    assert values["period"] == "0.8 s"
    assert values["step length"] == "0.3 m"
    assert values["speed"] == "0.375 m/s"
    assert values["cost (effort)"].endswith(" (N*m)^2*s")
    assert values["active constraints"] == "period (fixed), step length (fixed)"


def test_optimize_text_shows_the_freed_parameter(compass_free_text, compass_text):
    values = {m.group(1): m.group(2) for m in rows(compass_free_text)}
    match = re.fullmatch(r"([\d.e+-]+) kg \(optimised\)", values["free mass_leg"])
    assert match, values
    mass = float(match.group(1))
    assert 0 < mass < 5  # moved from its default, 5 kg: the lighter leg costs less effort
    params = dict(item.split("=") for item in values["params"].split(", "))
    assert float(params["mass_leg"]) == pytest.approx(mass, rel=1e-5)
    assert "free " not in compass_text  # nothing freed, nothing shown


def test_optimize_text_of_a_dimensionless_model_has_no_si_units(walker_text):
    for si in ("(m)", "(s)", "N·m", "N*m", " m/s", " s\n", " m\n", "(N"):
        assert si not in walker_text, si
    values = {m.group(1): m.group(2) for m in rows(walker_text)}
    assert values["period"] == "3.5 τ"
    assert values["step length"].endswith(" l")
    assert values["speed"].endswith(" l/τ")
    assert values["cost (effort)"].endswith(" (M*g*l)^2*τ")
    fixed = indented_after(walker_text, "fixed point (section:")
    assert [line.split()[-1] for line in fixed] == ["rad", "rad", "rad/τ", "rad/τ"]


def test_optimize_text_summarises_the_minima(walker_text):
    values = {m.group(1): m.group(2) for m in rows(walker_text)}
    label = next(label for label in values if label.startswith("minima ("))
    count = int(re.search(r"\d+", label).group())
    assert values[label] == "distinct, from 2 starts"
    listed = indented_after(walker_text, label)
    assert [line.split(".")[0].strip() for line in listed] == [str(k + 1) for k in range(count)]
    assert all(re.search(r" τ, verified (True|False); starts? \d", line) for line in listed)


def test_solve_text_in_the_same_style(capsys):
    status, out, _ = run_cli(capsys, "solve", "simplest_walker")
    assert status == 0
    values = {m.group(1): m.group(2) for m in rows(out)}
    assert values["period"].startswith("3.88") and " τ (1 step(s) per orbit)" in values["period"]
    fixed = indented_after(out, "fixed point (section:")
    assert [line.split()[-1] for line in fixed] == ["rad", "rad", "rad/τ", "rad/τ"]
    assert all("|λ| = " in line for line in indented_after(out, "multipliers"))


def test_output_helpers_doctests():
    import gaitopt.cli.output as output

    result = doctest.testmod(output)
    assert result.attempted >= 3 and result.failed == 0


# -- gaitopt optimize --out: figures ------------------------------------------------------------
@pytest.fixture(scope="module")
def compass_figures(tmp_path_factory):
    """The figures ``gaitopt optimize compass_gait ... --out`` saves, by file name (the animation
    is left out: it takes longer than the optimisation)."""
    import gaitopt.animation
    import gaitopt.plotting

    saved = {}
    with pytest.MonkeyPatch.context() as patch:
        patch.setattr(gaitopt.plotting, "save_figure", lambda fig, path: saved.update({
            path.name: fig}))  # fmt: skip
        patch.setattr(gaitopt.animation, "animate_walker", lambda *a, **k: None)
        capture = _Capture()
        out = tmp_path_factory.mktemp("optimal")
        status = capture.run("optimize", "compass_gait", *_FIXED, "--out", str(out))
    assert status == 0, capture.out
    return saved


def axis_labels(fig) -> list[tuple[str, str]]:
    """``(xlabel, ylabel)`` of every axis of ``fig``."""
    return [(ax.get_xlabel(), ax.get_ylabel()) for ax in fig.axes]


def test_orbit_figure_has_an_axis_per_unit(compass_figures):
    labels = axis_labels(compass_figures["orbit.png"])
    assert len(labels) >= 2  # angles and rates apart (they shared one axis)
    ylabels = [y for _, y in labels]
    assert ylabels == ["angle stance, swing (rad)", "angular rate stance_dot, swing_dot (rad/s)"]
    assert labels[-1][0] == "time t since the section (s)"


def test_inputs_figure_labelled_with_the_input_unit(compass_figures):
    labels = axis_labels(compass_figures["inputs.png"])
    assert [y for _, y in labels] == ["torque hip_torque (N*m)"]
    assert labels[-1][0] == "time t since the section (s)"


def test_figures_of_a_dimensionless_gait_in_its_units():
    import matplotlib.pyplot as plt

    import gaitopt
    from gaitopt.plotting import plot_optimal_inputs, plot_optimal_orbit

    walker = gaitopt.model("simplest_walker", slope=0.0)
    gait = gaitopt.optimize_gait(walker, "effort", period=3.5)  # not certified: drawn anyway
    assert gait.orbit and gait.inputs, gait.message
    (orbit, _), (inputs, _) = plot_optimal_orbit(gait), plot_optimal_inputs(gait)
    try:
        orbit_labels, input_labels = axis_labels(orbit), axis_labels(inputs)
    finally:
        plt.close(orbit)
        plt.close(inputs)
    assert [y for _, y in orbit_labels] == [
        "angle theta, phi (rad)",
        "angular rate theta_dot, phi_dot (rad/τ)",
    ]
    assert [y for _, y in input_labels] == [
        "torque hip_torque (M*g*l)",
        "impulse push_off (M*sqrt(g*l))",
    ]
    for labels in (orbit_labels, input_labels):  # one shared time axis, at the bottom
        assert [x for x, _ in labels] == ["", "time t since the section (τ, dimensionless)"]
    for x, y in orbit_labels + input_labels:
        for si in ("(m)", "(s)", "N·m", "N*m", "(m/s)"):
            assert si not in y and si not in x
    assert "(M*g*l)^2*τ" in inputs.axes[0].get_title()


def test_labels_doctests():
    import gaitopt.plotting.labels
    import gaitopt.plotting.optimal

    for module in (gaitopt.plotting.labels, gaitopt.plotting.optimal):
        result = doctest.testmod(module)
        assert result.attempted >= 1 and result.failed == 0


# -- gaitopt list -------------------------------------------------------------------------------
def test_list_builds_no_model(capsys, monkeypatch):
    from gaitopt.hybrid import HybridModel
    from gaitopt.models import REGISTRY

    built = []

    def no_build(cls, *args):
        built.append(cls.__name__)
        raise AssertionError(f"gaitopt list built {cls.__name__}")

    # structure() is where every build (cached or not) is reached: phases, section, state_names.
    monkeypatch.setattr(HybridModel, "structure", classmethod(no_build))
    for cls in REGISTRY.values():
        monkeypatch.setattr(cls, "build", classmethod(no_build))
    for argv in (["list"], ["list", "--json"]):
        status, out, err = run_cli(capsys, *argv)
        assert status == 0 and err == "" and out
    assert built == []


def test_list_json_and_text_give_each_parameters_source(capsys):
    from gaitopt.models import REGISTRY

    status, out, _ = run_cli(capsys, "list", "--json")
    assert status == 0
    entries = {entry["name"]: entry for entry in json_loads(out)}
    assert set(entries) == set(REGISTRY)
    for name, cls in REGISTRY.items():
        sources = {p["name"]: p["source"] for p in entries[name]["params"]}
        assert sources == {spec.name: spec.source for spec in cls.parameter_specs()}
        assert all(sources.values()), name  # every default says where it comes from
    compass = entries["compass_gait"]
    assert compass["input_units"] == ["N*m"]
    status, text, _ = run_cli(capsys, "list")
    for entry in entries.values():
        for p in entry["params"]:
            assert f"source: {p['source']}\n" in text
    assert "hip_torque (N*m)" in text


def test_list_declarations_are_the_built_structure(capsys):
    from gaitopt.cli.list_ import describe_model
    from gaitopt.models import REGISTRY

    for cls in REGISTRY.values():
        entry, model = describe_model(cls), cls()
        assert cls.declared_structure() is not None, cls.name
        assert entry["state_names"] == list(model.state_names)  # builds (and checks) the model
        assert entry["section_coordinates"] == list(model.section.coordinates)
        assert entry["section"] == model.section.doc


def test_a_declaration_that_differs_from_the_build_is_refused():
    from dataclasses import dataclass

    from gaitopt.errors import ModelDefinitionError
    from gaitopt.models.vanderpol import VanDerPol

    @dataclass(frozen=True)
    class Misdeclared(VanDerPol):
        declared_states = ("x", "x_dot")
        declared_coordinates = ("x_dot",)
        declared_section_doc = "q = 0, q_dot > 0"

    with pytest.raises(ModelDefinitionError, match=r"declared_states = \('x', 'x_dot'\)"):
        _ = Misdeclared().state_names

    @dataclass(frozen=True)
    class Undeclared(VanDerPol):  # a subclass does not inherit its parent's declaration
        pass

    assert Undeclared.declared_structure() is None
    assert Undeclared().state_names == ("q", "q_dot")


def json_loads(text: str):
    import json

    return json.loads(text)
