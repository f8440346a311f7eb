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
    """The ``gaitopt list --json`` entry of a model class, without building the model.

    Parameters (with each default's ``source``) and inputs are class metadata; the states and
    the section come from the class's declaration (:meth:`HybridModel.declared_structure`,
    checked against the build whenever the model is built), so that listing builds no CasADi
    graph nor linkage (the Strandbeest's takes seconds).  A class that declares none (a
    package's model) is built to learn them.

    Parameters
    ----------
    cls : type of HybridModel
        A registered model class.

    Returns
    -------
    dict
        ``name``, ``title``, ``reference``, ``params`` (each: ``name``, ``unit``, ``default``,
        ``doc``, ``source``, ``range``), ``state_names``, ``section_coordinates``, ``section``,
        ``inputs``, ``input_units``.
    """
    declared = cls.declared_structure()
    if declared is None:
        instance = cls()
        declared = (instance.state_names, instance.section.coordinates, instance.section.doc)
    states, coordinates, section = declared
    return {
        "name": cls.name,
        "title": cls.title,
        "reference": cls.reference,
        "params": [spec.as_dict() for spec in cls.parameter_specs()],
        "state_names": list(states),
        "section_coordinates": list(coordinates),
        "section": section,
        "inputs": list(cls.inputs),
        "input_units": list(cls.input_units),
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
    params = [p for entry in models for p in entry["params"]]
    name_width = max([12, *(len(p["name"]) for p in params)])
    unit_width = max([6, *(len(p["unit"]) for p in params)])
    for entry in models:
        print(f"{entry['name']}: {entry['title']} ({entry['reference']})")
        for p in entry["params"]:
            value = f"{p['name']:<{name_width}} = {p['default']:<9g} {p['unit']:<{unit_width}}"
            print(f"    {value} {p['range']:<20} {p['doc']}")
            print(f"    {'':<{name_width}}   source: {p['source']}")
        print(f"    states       {', '.join(entry['state_names'])}")
        print(f"    section      {entry['section']}")
        print(f"                 coordinates {', '.join(entry['section_coordinates'])}")
        print(f"    inputs       {_inputs_text(entry) or '(none: passive)'}")
    return EXIT_OK


def _inputs_text(entry: dict[str, Any]) -> str:
    """``"hip_torque (N*m), knee_torque (N*m)"``: the inputs with their declared units."""
    units = entry["input_units"] or [None] * len(entry["inputs"])
    return ", ".join(
        name if unit is None else f"{name} ({unit})"
        for name, unit in zip(entry["inputs"], units, strict=False)
    )
