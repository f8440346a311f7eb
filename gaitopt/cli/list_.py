"""``gaitopt list``: the registered models, their parameters, states, sections and inputs."""

from __future__ import annotations

import argparse
from typing import Any

from ..hybrid import HybridModel
from ..models import REGISTRY
from .common import EXIT_OK
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
    """``gaitopt list``: the models, their parameters, states and sections."""
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
