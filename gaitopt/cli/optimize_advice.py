"""The advice in :func:`gaitopt.optimize_gait`'s messages, in the options of ``gaitopt
optimize``: shared by :mod:`gaitopt.cli.optimize` and :mod:`gaitopt.cli.optimize_library`
(below both, so neither imports the other)."""

from __future__ import annotations

__all__ = ["for_the_cli"]

#: The Python API's names in advice, as the options of ``gaitopt optimize`` (a message shown
#: on the command line names the options that exist there): ``(pattern, replacement)``.
_CLI_ADVICE = (
    (r"bounds=\{'(\w+)': \((-?[\d.e+-]+), (-?[\d.e+-]+)\)\}", r"--bound \1=\2:\3"),
    (r"bounds=\{'(\w+)': (-?[\d.e+-]+)\}", r"--bound \1=\2"),
    (r"cost='(\w+)'", r"--cost \1"),
    (r"gaitopt\.model\('\w+', (\w+)=([\d.e+-]+)\)", r"--set \1=\2"),
    (r"\b(period|step_length|speed)=([\d.e+-]+)", r"--fix \1=\2"),
    (r"\b(starts|seed|steps|tol)=([\d.e+-]+)", r"--\1 \2"),
    (r"`(period|step_length|speed)`", r"--fix \1"),
    (r"`bounds(\[[^]]*\])?`", "--bound"),
    (r"state_bounds=\{'(\w+)': \((-?[\w.e+-]+), (-?[\w.e+-]+)\)\}", r"--bound \1=\2:\3"),
    (r"`state_bounds(\[[^]]*\])?`", "--bound"),
    (r"path_constraints=\('(\w+)',\)", r"--constrain \1"),
    (r"`path_constraints`", "--constrain"),
    (r"`(cost|starts|seed|steps|tol|free|scheduler)`", r"--\1"),
    (r"`?\bmax_(multiplier|roughness)`?=([\d.e+-]+)", r"--max-\1 \2"),
    (r"`max_(multiplier|roughness)`", r"--max-\1"),
    (r"\bmax_(multiplier|roughness)\b", r"--max-\1"),
)


def for_the_cli(message: str) -> str:
    """``message`` (from :func:`gaitopt.optimize_gait`, in the Python API's names) with its
    advice in the options of ``gaitopt optimize``: ```tol``` → ``--tol``, ``bounds={'hip': 20}``
    → ``--bound hip=20``, ``period=0.8`` → ``--fix period=0.8``, ``cost='effort'`` →
    ``--cost effort``."""
    import re

    for pattern, replacement in _CLI_ADVICE:
        message = re.sub(pattern, replacement, message)
    return message
