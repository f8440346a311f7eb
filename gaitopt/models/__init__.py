"""The models, one file each, and the registry behind :func:`gaitopt.model`."""

from __future__ import annotations

from collections.abc import MutableMapping
from types import ModuleType
from typing import TYPE_CHECKING

from ..errors import ParameterError, UnknownModelError, did_you_mean
from ..hybrid import HybridModel

if TYPE_CHECKING:
    from importlib.metadata import EntryPoint

__all__ = [
    "REGISTRY",
    "ENTRY_POINT_GROUP",
    "model",
    "model_class",
    "model_names",
    "load_entry_points",
    "as_model",
    "register",
    "unregister",
    "BipedRunner",
    "BouncingBall",
    "CompassGait",
    "KneedWalker",
    "LineJuggler",
    "MinimalBipedRun",
    "MinimalBipedWalk",
    "OneDHopper",
    "FiveLinkBiped",
    "PlanarJuggler",
    "PlanarQuadruped",
    "PlanarQuadrupedPronk",
    "PlanarQuadrupedRaibert",
    "PlanarQuadrupedRaibertPronk",
    "BallisticWalker",
    "RaibertHopper",
    "RimlessWheel",
    "SimplestWalker",
    "Slip",
    "SlipActuated",
    "Strandbeest",
    "ThreeLinkWalker",
    "VanDerPol",
    "VerticalHopper",
]

#: The built-in models: name -> (module of this package, class), in the order ``gaitopt list``
#: shows them.  A class's module is imported when the class is first asked for
#: (``REGISTRY[name]``, ``gaitopt.model(name)``, ``gaitopt.models.CompassGait``), so ``import
#: gaitopt`` and ``gaitopt solve compass_gait`` import one model file, not all of them
#: (tests/test_import_cost.py checks this table against each class's ``name``).
BUILTIN: dict[str, tuple[str, str]] = {
    "vanderpol": ("vanderpol", "VanDerPol"),
    "rimless_wheel": ("rimless_wheel", "RimlessWheel"),
    "compass_gait": ("compass_gait", "CompassGait"),
    "simplest_walker": ("simplest_walker", "SimplestWalker"),
    "kneed_walker": ("kneed_walker", "KneedWalker"),
    "five_link_biped": ("five_link_biped", "FiveLinkBiped"),
    "slip": ("slip", "Slip"),
    "slip_actuated": ("slip_actuated", "SlipActuated"),
    "vertical_hopper": ("vertical_hopper", "VerticalHopper"),
    "one_d_hopper": ("one_d_hopper", "OneDHopper"),
    "raibert_hopper": ("raibert_hopper", "RaibertHopper"),
    "bouncing_ball": ("bouncing_ball", "BouncingBall"),
    "line_juggler": ("line_juggler", "LineJuggler"),
    "planar_juggler": ("planar_juggler", "PlanarJuggler"),
    "ballistic_walker": ("ballistic_walker", "BallisticWalker"),
    "strandbeest": ("strandbeest", "Strandbeest"),
    "three_link_walker": ("three_link_walker", "ThreeLinkWalker"),
    "planar_quadruped": ("planar_quadruped", "PlanarQuadruped"),
    "planar_quadruped_pronk": ("planar_quadruped", "PlanarQuadrupedPronk"),
    "planar_quadruped_raibert": ("planar_quadruped_raibert", "PlanarQuadrupedRaibert"),
    "planar_quadruped_raibert_pronk": (
        "planar_quadruped_raibert_pronk",
        "PlanarQuadrupedRaibertPronk",
    ),
    "biped_runner": ("biped_runner", "BipedRunner"),
    "minimal_biped_walk": ("minimal_biped", "MinimalBipedWalk"),
    "minimal_biped_run": ("minimal_biped", "MinimalBipedRun"),
}
_CLASSES = {cls: module for module, cls in BUILTIN.values()}
_MODULES = frozenset(_CLASSES.values())


def _load_builtin(name: str) -> type[HybridModel]:
    """Import the built-in model ``name``'s module and return its class."""
    from importlib import import_module

    module, cls_name = BUILTIN[name]
    cls = getattr(import_module(f".{module}", __name__), cls_name)
    if cls.name != name:  # the table above and the class disagree: a bug here, said plainly
        raise RuntimeError(f"gaitopt.models.BUILTIN[{name!r}] names {cls_name}, named {cls.name!r}")
    return cls


class _Registry(MutableMapping):
    """The registry: model name -> model class, a built-in class imported on first access.

    A mapping like a dict (``REGISTRY[name]``, ``in``, ``list``, ``items``, ``values``); the
    order is that of registration (the built-in models first, in :data:`BUILTIN`'s order).
    Iterating over the names imports nothing; reading a value imports that model's module.
    """

    def __init__(self) -> None:
        self._items: dict[str, type[HybridModel] | None] = dict.fromkeys(BUILTIN)

    def __getitem__(self, name: str) -> type[HybridModel]:
        cls = self._items[name]
        if cls is None:
            cls = self._items[name] = _load_builtin(name)
        return cls

    def __setitem__(self, name: str, cls: type[HybridModel]) -> None:
        self._items[name] = cls

    def __delitem__(self, name: str) -> None:
        del self._items[name]

    def __iter__(self):
        return iter(self._items)

    def __len__(self) -> int:
        return len(self._items)

    def __contains__(self, name: object) -> bool:
        return name in self._items

    def loaded(self, name: str) -> bool:
        """Whether ``name``'s class is imported already (a registered class always is)."""
        return self._items.get(name) is not None

    def __repr__(self) -> str:
        return f"REGISTRY({', '.join(self._items)})"


REGISTRY: MutableMapping[str, type[HybridModel]] = _Registry()


def __getattr__(name: str) -> type[HybridModel]:
    """``gaitopt.models.CompassGait``: a built-in model class (or ``.compass_gait``, its module),
    the module imported on first use (PEP 562)."""
    from importlib import import_module

    if name in _MODULES:  # a model's module (``gaitopt.models.compass_gait``), as if imported
        return import_module(f".{name}", __name__)
    module = _CLASSES.get(name)
    if module is None:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    value = getattr(import_module(f".{module}", __name__), name)
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(_CLASSES))


#: The entry-point group through which installed packages declare their models.
ENTRY_POINT_GROUP = "gaitopt.models"


def register(cls: type[HybridModel]) -> type[HybridModel]:
    """Register a model class under its ``name``, for :func:`model` and the CLI.

    Usable as a decorator.  A package can also declare its models without being imported first,
    through the entry-point group ``gaitopt.models`` (``name = "package.module:Class"``), which
    :func:`model`, :func:`model_class`, ``gaitopt solve NAME`` and ``gaitopt list`` consult.
    Loading such an entry point imports the module, whose ``@register`` (if it has one) registers
    the class; the loader then registers it again, which is why registering the class that is
    already registered under its name is a no-op.

    Parameters
    ----------
    cls : type
        A :class:`~gaitopt.hybrid.HybridModel` subclass with a ``name``.

    Returns
    -------
    type
        ``cls`` itself (so the function works as a decorator).

    Raises
    ------
    GaitoptInputError
        If ``cls`` is not a :class:`~gaitopt.hybrid.HybridModel` subclass with a ``name`` that
        implements :meth:`~gaitopt.hybrid.HybridModel.build` and
        :meth:`~gaitopt.hybrid.HybridModel.default_start`, or a
        *different* class is registered under that name (unregister the old one first: one
        meaning per name).
    """
    from ..errors import GaitoptInputError

    if not (isinstance(cls, type) and issubclass(cls, HybridModel) and cls.name):
        raise GaitoptInputError(
            f"register: expected a HybridModel subclass with a `name`, got {cls!r}; see "
            f"docs/writing-a-model.md"
        )
    missing = [
        name
        for name in ("build", "default_start")
        # a classmethod is a new bound method on each access: compare the functions under it
        if getattr(getattr(cls, name), "__func__", getattr(cls, name))
        is getattr(getattr(HybridModel, name), "__func__", getattr(HybridModel, name))
    ]
    if missing:
        raise GaitoptInputError(
            f"register: {cls.__qualname__} does not implement {' and '.join(missing)}, which "
            f"every model must (the phases and section from symbols; a start on the section); "
            f"see docs/writing-a-model.md"
        )
    taken = REGISTRY.get(cls.name)
    if taken is cls:
        return cls
    if taken is not None:
        raise GaitoptInputError(
            f"register: a model named {cls.name!r} is already registered "
            f"({taken.__module__}.{taken.__qualname__}), so {cls.__module__}.{cls.__qualname__} "
            f"cannot take that name; call gaitopt.unregister({cls.name!r}) first, or give the "
            f"new class another `name`"
        )
    REGISTRY[cls.name] = cls
    return cls


def unregister(name: str) -> None:
    """Remove a registered model (a no-op for an unknown name).

    A model of an installed package's entry point is registered again the next time its name
    is asked for.
    """
    REGISTRY.pop(name, None)


def _entry_points() -> list[EntryPoint]:
    """The installed packages' entry points of :data:`ENTRY_POINT_GROUP`, first of a name
    first (the order of ``sys.path``)."""
    from importlib.metadata import entry_points

    return list(entry_points(group=ENTRY_POINT_GROUP))


def _describe(entry: EntryPoint) -> str:
    """``kicked_ball = my_package.kicked_ball:KickedBall (package my-package 0.1)``."""
    dist = getattr(entry, "dist", None)
    where = f" (package {dist.name} {dist.version})" if dist is not None else ""
    return f"entry point {entry.name} = {entry.value}{where} of group {ENTRY_POINT_GROUP!r}"


def _load_entry_point(entry: EntryPoint) -> type[HybridModel]:
    """Import one entry point and register the model it names (a class, or a module whose
    ``@register`` registers a model of the entry point's name).

    Raises
    ------
    UnknownModelError
        If the entry point cannot be imported, names neither a model class nor a module that
        registers one, or gives a model whose ``name`` is not the entry point's name.
    """
    from ..errors import GaitoptInputError

    try:
        target = entry.load()
    except Exception as exc:  # the package's code: any error, said in one line
        reason = " ".join(f"{type(exc).__name__}: {exc}".split())
        raise UnknownModelError(
            f"model {entry.name!r}: the {_describe(entry)} cannot be loaded ({reason}); fix or "
            f"reinstall that package"
        ) from exc
    if isinstance(target, ModuleType):  # the module registers its models itself
        if entry.name in REGISTRY:
            return REGISTRY[entry.name]
        raise UnknownModelError(
            f"model {entry.name!r}: the {_describe(entry)} names a module that registers no "
            f"model {entry.name!r}; name the class (module:Class) or decorate it with "
            f"@gaitopt.register"
        )
    if isinstance(target, type) and issubclass(target, HybridModel) and target.name != entry.name:
        raise UnknownModelError(
            f"model {entry.name!r}: the {_describe(entry)} gives a model named "
            f"{target.name!r}; name the entry point after the class's `name`"
        )
    try:
        return register(target)
    except GaitoptInputError as exc:
        raise UnknownModelError(f"model {entry.name!r}: the {_describe(entry)}: {exc}") from None


def load_entry_points() -> list[UnknownModelError]:
    """Register every model the installed packages declare (group ``gaitopt.models``).

    Returns
    -------
    list of UnknownModelError
        One error per entry point that could not be loaded (see :func:`model_class`); the others
        are registered.  ``gaitopt list`` prints them as warnings and lists the rest.
    """
    problems = []
    for entry in _entry_points():
        if entry.name in REGISTRY:
            continue
        try:
            _load_entry_point(entry)
        except UnknownModelError as exc:
            problems.append(exc)
    return problems


def model_names() -> list[str]:
    """The names :func:`model` knows: the registered models, then the installed packages'
    entry points not loaded yet (nothing is imported)."""
    names = list(REGISTRY)
    for entry in _entry_points():
        if entry.name not in names:
            names.append(entry.name)
    return names


def model_class(name: str) -> type[HybridModel]:
    """The model class registered as ``name``, loaded from an installed package's entry point
    (group ``gaitopt.models``) if it is not registered yet.

    Parameters
    ----------
    name : str
        A model name (``gaitopt list`` shows them).

    Returns
    -------
    type
        The :class:`~gaitopt.hybrid.HybridModel` subclass.

    Raises
    ------
    UnknownModelError
        If ``name`` is not a str, is neither registered nor declared by an entry point, or its
        entry point cannot be loaded (the message says which and why).
    """
    if not isinstance(name, str):
        raise UnknownModelError(
            f"`name` must be a model name (a str), got {name!r} of type {type(name).__name__}; "
            f"available: {', '.join(model_names())}"
        )
    if name in REGISTRY:
        return REGISTRY[name]
    for entry in _entry_points():
        if entry.name == name:
            return _load_entry_point(entry)
    raise UnknownModelError(
        f"unknown model {name!r}; {did_you_mean(name, model_names())}available: "
        f"{', '.join(model_names())}"
    )


def model(name: str, **params: float) -> HybridModel:
    """Build a model by name with some parameters changed from their defaults.

    Parameters
    ----------
    name : str
        A registered model, or one an installed package declares in the entry-point group
        ``gaitopt.models`` (loaded and registered on first use: :func:`model_class`).
    **params : float
        Parameter values; the others keep their defaults.

    Returns
    -------
    HybridModel
        The model instance.

    Raises
    ------
    UnknownModelError
        If ``name`` is not a model (or its entry point cannot be loaded).
    ParameterError
        If a parameter is unknown, not a number, or out of range.
    """
    cls = model_class(name)
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
