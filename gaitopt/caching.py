"""gaitopt's one cache rule: a bounded cache that drops the least recently used entry.

Where a function's arguments are its key (hashable: a model class, a mesh), it is
:func:`functools.lru_cache` (``shooting_problem``, the kernels).  Where the key is computed from
arguments that are not hashable (a gait statement with mappings and callables), it is
:func:`lru_by_key`: the same rule, the key given by a function of the arguments."""

from __future__ import annotations

from collections import OrderedDict
from collections.abc import Callable, Hashable
from functools import wraps
from typing import Any, TypeVar

__all__ = ["LRUCache", "lru_by_key"]

T = TypeVar("T")


class LRUCache(OrderedDict):
    """At most ``maxsize`` entries, the least recently used dropped first (an ``OrderedDict``:
    ``clear()`` empties it)."""

    def __init__(self, maxsize: int):
        super().__init__()
        self.maxsize = maxsize

    def get_or_build(self, key: Hashable, build: Callable[[], T]) -> T:
        """The value under ``key`` (now the most recently used), built by ``build()`` if absent."""
        if key in self:
            self.move_to_end(key)
            return self[key]
        value = build()
        self[key] = value
        while len(self) > self.maxsize:
            self.popitem(last=False)
        return value


def lru_by_key(maxsize: int, key: Callable[..., Hashable]):
    """Decorator: cache a function's results in an :class:`LRUCache` of ``maxsize`` entries,
    under ``key(*args, **kwargs)``; the wrapper has ``cache`` (the :class:`LRUCache`) and
    ``cache_clear()``, as :func:`functools.lru_cache`'s."""

    def decorate(fn: Callable[..., T]) -> Callable[..., T]:
        cache = LRUCache(maxsize)

        @wraps(fn)
        def wrapper(*args: Any, **kwargs: Any) -> T:
            return cache.get_or_build(key(*args, **kwargs), lambda: fn(*args, **kwargs))

        wrapper.cache = cache  # type: ignore[attr-defined]
        wrapper.cache_clear = cache.clear  # type: ignore[attr-defined]
        return wrapper

    return decorate
