"""The models, one file each, and the registry behind :func:`gaitopt.model`."""

from __future__ import annotations

from ..errors import ParameterError, UnknownModelError, did_you_mean
from ..hybrid import HybridModel
from .ballistic_walker import BallisticWalker
from .bouncing_ball import BouncingBall
from .compass_gait import CompassGait
from .five_link_biped import FiveLinkBiped
from .kneed_walker import KneedWalker
from .line_juggler import LineJuggler
from .planar_juggler import PlanarJuggler
from .raibert_hopper import RaibertHopper
from .rimless_wheel import RimlessWheel
from .simplest_walker import SimplestWalker
from .slip import Slip
from .strandbeest import Strandbeest
from .vanderpol import VanDerPol
from .vertical_hopper import VerticalHopper

__all__ = [
    "REGISTRY",
    "model",
    "as_model",
    "register",
    "unregister",
    "BouncingBall",
    "CompassGait",
    "KneedWalker",
    "LineJuggler",
    "FiveLinkBiped",
    "PlanarJuggler",
    "BallisticWalker",
    "RaibertHopper",
    "RimlessWheel",
    "SimplestWalker",
    "Slip",
    "Strandbeest",
    "VanDerPol",
    "VerticalHopper",
]

REGISTRY: dict[str, type[HybridModel]] = {
    cls.name: cls
    for cls in (
        VanDerPol,
        RimlessWheel,
        CompassGait,
        SimplestWalker,
        KneedWalker,
        FiveLinkBiped,
        Slip,
        VerticalHopper,
        RaibertHopper,
        BouncingBall,
        LineJuggler,
        PlanarJuggler,
        BallisticWalker,
        Strandbeest,
    )
}


def register(cls: type[HybridModel]) -> type[HybridModel]:
    """Register a model class under its ``name``, for :func:`model` and the CLI.

    Usable as a decorator.  A package can also register its models without being imported
    first, through the entry-point group ``gaitopt.models`` (``name = "package.module:Class"``),
    which :func:`model` consults for a name it does not know.

    Raises
    ------
    GaitoptInputError
        If ``cls`` is not a :class:`~gaitopt.hybrid.HybridModel` subclass with a ``name``, or the
        name is taken (unregister the old one first: one meaning per name).
    """
    from ..errors import GaitoptInputError

    if not (isinstance(cls, type) and issubclass(cls, HybridModel) and cls.name):
        raise GaitoptInputError(
            f"register: expected a HybridModel subclass with a `name`, got {cls!r}; see "
            f"docs/writing-a-model.md"
        )
    if cls.name in REGISTRY:
        raise GaitoptInputError(
            f"register: a model named {cls.name!r} is already registered "
            f"({REGISTRY[cls.name].__module__}); call gaitopt.unregister({cls.name!r}) first"
        )
    REGISTRY[cls.name] = cls
    return cls


def unregister(name: str) -> None:
    """Remove a registered model (a no-op for an unknown name)."""
    REGISTRY.pop(name, None)


def _from_entry_points(name: str) -> None:
    """Register the model ``name`` if an installed package declares it as an entry point."""
    from importlib.metadata import entry_points

    for entry in entry_points(group="gaitopt.models"):
        if entry.name == name:
            register(entry.load())
            return


def model(name: str, **params: float) -> HybridModel:
    """Build a model by name with some parameters changed from their defaults.

    Raises
    ------
    UnknownModelError
        If ``name`` is not a registered model.
    ParameterError
        If a parameter is unknown, not a number, or out of range.
    """
    if not isinstance(name, str):
        raise UnknownModelError(
            f"`name` must be a model name (a str), got {name!r} of type {type(name).__name__}; "
            f"available: {', '.join(REGISTRY)}"
        )
    if name not in REGISTRY:
        _from_entry_points(name)
    if name not in REGISTRY:
        raise UnknownModelError(
            f"unknown model {name!r}; {did_you_mean(name, REGISTRY)}available: "
            f"{', '.join(REGISTRY)}"
        )
    cls = REGISTRY[name]
    known = [s.name for s in cls.parameter_specs()]
    for key in params:
        if key not in known:
            raise ParameterError(
                f"{name}: unknown parameter {key!r}; {did_you_mean(key, known)}"
                f"parameters: {', '.join(known)}"
            )
    return cls(**params)


def as_model(value: HybridModel | str, argument: str = "model") -> HybridModel:
    """A model instance: ``value`` itself, or the registered model of that name at its defaults.

    Parameters
    ----------
    value : HybridModel or str
        A model, or a model name (``"compass_gait"``: :func:`model` with default parameters).
    argument : str
        The argument's name, for the error message.

    Raises
    ------
    UnknownModelError
        If ``value`` is neither a model nor a registered model name.
    """
    if isinstance(value, HybridModel):
        return value
    if isinstance(value, str):
        return model(value)
    raise UnknownModelError(
        f"`{argument}` must be a model (e.g. gaitopt.model('compass_gait')) or a model name, "
        f"got {value!r} of type {type(value).__name__}"
    )
