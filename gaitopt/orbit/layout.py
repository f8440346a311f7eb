"""Named blocks of a transcription's vectors: which entries of the unknowns ``w`` (columns) and of
the residual (rows) are which, by name, never by position in a tuple.

A :class:`Layout` maps each block's name to its :class:`slice` and shape; the blocks are listed
in order, do not overlap and cover the vector exactly once (checked on construction)."""

from __future__ import annotations

from collections.abc import Iterable, Iterator
from dataclasses import dataclass, field

import numpy as np

__all__ = ["Block", "Layout"]


@dataclass(frozen=True)
class Block:
    """One named block of a vector.

    Attributes
    ----------
    name : str
        The block's name (``"s"``, ``"nodes 0"``, ``"T0"``, ``"dynamics (stance)"``, …).
    slice : slice
        Where it sits in the vector.
    shape : tuple of int
        Its shape when read as an array (column-major, CasADi's order); ``(size,)`` for a
        plain run of entries.
    """

    name: str
    slice: slice
    shape: tuple[int, ...]

    @property
    def size(self) -> int:
        """Number of entries."""
        return self.slice.stop - self.slice.start


@dataclass(frozen=True)
class Layout:
    """The named blocks of a vector of ``size`` entries, in order.

    Build it with :meth:`from_sizes` (names and shapes in order); read a block with
    ``layout["name"]`` (its slice), :meth:`take` (its values, in its shape) or :meth:`index`
    (its entries' positions).
    """

    blocks: tuple[Block, ...]
    size: int
    _by_name: dict[str, Block] = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        by_name: dict[str, Block] = {}
        at = 0
        for block in self.blocks:
            if block.name in by_name:
                raise ValueError(f"Layout: the block name {block.name!r} is used twice")
            if block.slice.start != at:
                raise ValueError(
                    f"Layout: block {block.name!r} starts at {block.slice.start}, not at {at} "
                    "(blocks must follow each other without gaps or overlaps)"
                )
            at = block.slice.stop
            by_name[block.name] = block
        if at != self.size:
            raise ValueError(f"Layout: the blocks cover {at} entries of {self.size}")
        object.__setattr__(self, "_by_name", by_name)

    @classmethod
    def from_sizes(cls, entries: Iterable[tuple[str, tuple[int, ...] | int]]) -> Layout:
        """A layout from ``(name, shape)`` pairs in order (a shape may be an int: a run)."""
        blocks, at = [], 0
        for name, shape in entries:
            shape = (shape,) if isinstance(shape, (int, np.integer)) else tuple(shape)
            size = int(np.prod(shape)) if shape else 1
            blocks.append(Block(name, slice(at, at + size), shape))
            at += size
        return cls(tuple(blocks), at)

    @property
    def names(self) -> list[str]:
        """The block names, in order."""
        return [b.name for b in self.blocks]

    def __getitem__(self, name: str) -> slice:
        return self.block(name).slice

    def __contains__(self, name: object) -> bool:
        return name in self._by_name

    def __iter__(self) -> Iterator[Block]:
        return iter(self.blocks)

    def __len__(self) -> int:
        return len(self.blocks)

    def block(self, name: str) -> Block:
        """The block called ``name`` (``KeyError`` naming the known blocks if there is none)."""
        try:
            return self._by_name[name]
        except KeyError:
            raise KeyError(f"no block {name!r}; the blocks are {self.names}") from None

    def index(self, name: str) -> np.ndarray:
        """The positions of block ``name``'s entries."""
        s = self[name]
        return np.arange(s.start, s.stop)

    def take(self, v, name: str) -> np.ndarray:
        """Block ``name`` of the vector ``v``, in its shape (column-major)."""
        b = self.block(name)
        values = np.asarray(v, dtype=float).ravel()[b.slice]
        return values.reshape(b.shape, order="F") if len(b.shape) > 1 else values.copy()

    def owner(self) -> np.ndarray:
        """For each entry of the vector, the index of its block in :attr:`blocks`."""
        out = np.empty(self.size, dtype=int)
        for j, b in enumerate(self.blocks):
            out[b.slice] = j
        return out
