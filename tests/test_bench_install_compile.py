"""bench.install_compile in its fast mode (one small model): the kernel compile of ``make
install`` measured from an empty cache, written, read back and shown in the goals table."""

from __future__ import annotations

import pytest

from bench import goals, install_compile
from gaitopt.kernels.cache import compiler


@pytest.mark.skipif(
    compiler() is None, reason="no C compiler ($GAITOPT_CC, default gcc): nothing is compiled"
)
def test_install_compile_fast_mode_round_trip(tmp_path, capsys):
    out = tmp_path / "install.json"
    assert install_compile.main(["--jobs", "1", "--out", str(out), "vanderpol"]) == 0
    entry = install_compile.latest(out)
    assert entry is not None and entry["exit_code"] == 0
    # the model's own line, as gaitopt.kernels --warm printed it: compiled, within the whole run
    model = entry["per_model"]["vanderpol"]
    assert model["how"] == "compiled"
    assert 0 < model["wall_s"] <= entry["wall_s"]
    assert 0 < model["cpu_s"] <= entry["cpu_s"] + 0.05  # the printed value is rounded to 0.01 s
    assert entry["met"] == (entry["wall_s"] <= install_compile.GOAL_S)
    assert "Kernel compile from an empty cache" in capsys.readouterr().out
    row = [r for r in goals.rows({"install_compile": entry}) if "make install" in r["goal"]]
    assert len(row) == 1 and row[0]["met"] == entry["met"]


def test_missing_results_give_an_unmeasured_row(tmp_path):
    assert install_compile.latest(tmp_path / "none.json") is None
    row = [r for r in goals.rows({"install_compile": None}) if "make install" in r["goal"]]
    assert len(row) == 1 and row[0]["met"] is None
