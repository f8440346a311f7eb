"""The examples in the docstrings run and print what they say (``doctest``).

Source of each expected value: the example itself (the compass gait's period 0.734461 s is the one
``make gaits`` reports, Drake's passive gait; a cycle is at distance 0 from its own start state).
"""

from __future__ import annotations

import doctest
import importlib

import pytest

# Modules whose docstrings hold examples that run (``# doctest: +SKIP`` ones write files or need
# a figure, and are only read).
MODULES = ("gaitopt", "gaitopt.plotting", "gaitopt.orbits")


@pytest.mark.parametrize("name", MODULES)
def test_docstring_examples_run(name):
    module = importlib.import_module(name)
    result = doctest.testmod(module, optionflags=doctest.ELLIPSIS, verbose=False)
    assert result.attempted > 0, f"{name} has no docstring example left to run"
    assert result.failed == 0
