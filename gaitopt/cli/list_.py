"""``gaitopt list``: the registered models (with those installed packages declare through the
``gaitopt.models`` entry point group), their parameters, states, sections and inputs."""

from __future__ import annotations

import argparse
import sys
from typing import Any

from ..hybrid import HybridModel
from ..models import REGISTRY, load_entry_points
from .common import EXIT_OK, PROG
from .output import _print_json


# -- gaitopt list --------------------------------------------------------------------------------
def describe_model(cls: type[HybridModel]) -> dict[str, Any]:
    """The ``gaitopt list --json`` entry of a model class."""
    instance = cls()
    return {
        "name": cls.name,
        "title": cls.title,
        "reference": cls.reference,
        "params": [spec.as_dict() for spec in cls.parameter_specs()],
        "state_names": list(instance.state_names),
        "section_coordinates": list(instance.section.coordinates),
        "section": instance.section.doc,
        "inputs": list(cls.inputs),
    }


def _list_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("--json", action="store_true", help="print a JSON list of the models")


def run_list(args: argparse.Namespace) -> int:
    """``gaitopt list``: the models, their parameters, states and sections.

    The models of installed packages' entry points are loaded and listed after the built-in
    ones; one that cannot be loaded is named in a one-line warning on stderr (the others are
    still listed, and the exit status stays 0: the command line's input was fine).
    """
    for problem in load_entry_points():
        print(f"{PROG}: warning: {' '.join(str(problem).split())}", file=sys.stderr)
    models = [describe_model(cls) for cls in REGISTRY.values()]
    if args.json:
        _print_json(models)
        return EXIT_OK
    for entry in models:
        print(f"{entry['name']}: {entry['title']} ({entry['reference']})")
        for p in entry["params"]:
            value = f"{p['name']:<12} = {p['default']:<9g} {p['unit']:<6}"
            print(f"    {value} {p['range']:<20} {p['doc']}")
        print(f"    states       {', '.join(entry['state_names'])}")
        print(f"    section      {entry['section']}")
        print(f"                 coordinates {', '.join(entry['section_coordinates'])}")
        print(f"    inputs       {', '.join(entry['inputs']) or '(none: passive)'}")
    return EXIT_OK
