"""gaitopt.files: files written whole or not at all, values made strict JSON."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

from gaitopt.files import jsonable, replaced_atomically, write_json


def _hidden(folder) -> list[str]:
    return sorted(p.name for p in folder.iterdir() if p.name.startswith("."))


# -- replaced_atomically -----------------------------------------------------------------------
def test_replaced_atomically_replaces_the_content(tmp_path):
    path = tmp_path / "out.txt"
    path.write_text("old")
    with replaced_atomically(path, ".txt") as tmp:
        assert tmp.parent == tmp_path and tmp.name.startswith(".out.txt.")
        assert tmp.suffix == ".txt" and not tmp.exists()
        tmp.write_text("new")
        assert path.read_text() == "old"  # not replaced before the block ends
    assert path.read_text() == "new"
    assert _hidden(tmp_path) == []


def test_replaced_atomically_creates_a_missing_file(tmp_path):
    with replaced_atomically(str(tmp_path / "new.txt")) as tmp:
        tmp.write_text("content")
    assert (tmp_path / "new.txt").read_text() == "content"
    assert _hidden(tmp_path) == []


def test_a_failing_write_leaves_the_old_file_and_no_temporary_file(tmp_path):
    path = tmp_path / "out.txt"
    path.write_text("old")
    with pytest.raises(RuntimeError, match="half-way"):
        with replaced_atomically(path) as tmp:
            tmp.write_text("half a fi")
            raise RuntimeError("failed half-way")
    assert path.read_text() == "old"
    assert _hidden(tmp_path) == []


def test_temporary_names_are_fresh(tmp_path):
    with replaced_atomically(tmp_path / "a") as one, replaced_atomically(tmp_path / "a") as two:
        assert one != two
        one.write_text("1")
        two.write_text("2")
    assert (tmp_path / "a").read_text() == "1"  # the outer block ends last
    assert _hidden(tmp_path) == []


# -- write_json --------------------------------------------------------------------------------
def test_write_json_writes_strict_json(tmp_path):
    path = tmp_path / "cycle.json"
    data = {"period": float("nan"), "x": np.array([1.0, np.inf]), "name": "θ", "n": np.int64(3)}
    assert write_json(data, str(path)) == path
    text = path.read_text(encoding="utf-8")
    assert text.endswith("}\n") and "θ" in text and "NaN" not in text
    assert json.loads(text) == {"period": None, "x": [1.0, None], "name": "θ", "n": 3}
    assert _hidden(tmp_path) == []


def test_write_json_failure_leaves_the_old_file_whole(tmp_path):
    path = tmp_path / "cycle.json"
    write_json({"period": 1.0}, path)
    with pytest.raises(TypeError):
        write_json({"period": object()}, path)
    assert json.loads(path.read_text()) == {"period": 1.0}
    assert _hidden(tmp_path) == []


# -- jsonable ----------------------------------------------------------------------------------
def test_jsonable_numpy_arrays_and_scalars():
    out = jsonable({"a": np.arange(3), "m": np.eye(2), "f": np.float32(0.5), "b": np.bool_(True)})
    assert out == {"a": [0, 1, 2], "m": [[1.0, 0.0], [0.0, 1.0]], "f": 0.5, "b": True}
    assert type(out["a"][0]) is int and type(out["m"][0][0]) is float
    assert type(out["f"]) is float and type(out["b"]) is bool
    assert jsonable((1, True, "s", None)) == [1, True, "s", None]
    assert type(jsonable(True)) is bool and type(jsonable(np.int32(7))) is int


def test_jsonable_non_finite_and_complex():
    assert jsonable([math.nan, -math.inf, np.float64(np.inf), 2.5]) == [None, None, None, 2.5]
    assert jsonable(1 + 2j) == [1.0, 2.0]
    assert jsonable(np.array([0.5 - 1j, complex(math.nan, 1)])) == [[0.5, -1.0], [None, 1.0]]


def test_jsonable_keys_become_strings_and_others_pass_through():
    marker = object()
    assert jsonable({1: "a", ("k",): marker}) == {"1": "a", "('k',)": marker}
    json.dumps(jsonable({"x": np.array([np.nan])}), allow_nan=False)  # strict JSON
