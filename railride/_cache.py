"""A store of shared, read-only values bounded by their bytes: the random-track realisations and
the rail input and forcing tables that the runs of a study meet again.

A bound on the number of entries does not bound memory: a table at 65 m/s is four times one at
30 m/s, and a store per kind of value, each holding its own keys, kept every realisation a
table's key referred to. Here each store counts the bytes of what it holds and drops the least
recently used first once they pass its budget; keys are plain values (settings), never the
objects built from them.
"""

from __future__ import annotations

import threading
from collections import OrderedDict
from collections.abc import Callable, Hashable
from typing import Generic, TypeVar

V = TypeVar("V")

MiB = 1 << 20


class BytesLRU(Generic[V]):
    """Values built on demand by ``get(key, build)`` and kept by key while their bytes
    (``size(value)``) stay within ``budget``; past it, the least recently used go first. A value
    larger than the budget is built and returned but not kept, and so is one whose key is None
    or cannot be hashed (a setting that is no plain value). Safe to share between threads (a
    Dask worker's): two threads that miss the same key at once both build it, one is kept."""

    def __init__(self, name: str, budget: int, size: Callable[[V], int]):
        self.name = name
        self.budget = int(budget)
        self._size = size
        self._items: OrderedDict[Hashable, tuple[V, int]] = OrderedDict()
        self._bytes = 0
        self._lock = threading.Lock()
        self.hits = 0
        self.misses = 0

    def get(self, key, build: Callable[[], V]) -> V:
        key = hashable(key)
        if key is None:
            return build()
        value = self.lookup(key)
        if value is not None:
            return value
        value = build()  # outside the lock: a build takes milliseconds, other threads go on
        self.put(key, value)
        return value

    def lookup(self, key) -> V | None:
        """The value kept under ``key`` (a hit), or None (a miss; a key that is None or cannot be
        hashed is never kept and counts as neither)."""
        key = hashable(key)
        if key is None:
            return None
        with self._lock:
            item = self._items.get(key)
            if item is not None:
                self._items.move_to_end(key)
                self.hits += 1
                return item[0]
            self.misses += 1
        return None

    def put(self, key, value: V) -> None:
        """Keep ``value`` under ``key`` within the budget (the least recently used go first); one
        larger than the budget, or a key that is None or cannot be hashed, is not kept."""
        key = hashable(key)
        nbytes = int(self._size(value))
        if key is None or nbytes > self.budget:
            return
        with self._lock:
            if key not in self._items:
                self._items[key] = (value, nbytes)
                self._bytes += nbytes
            while self._bytes > self.budget:
                _, (_, dropped) = self._items.popitem(last=False)
                self._bytes -= dropped

    @property
    def nbytes(self) -> int:
        """The bytes held now (at most `budget`)."""
        return self._bytes

    def __len__(self) -> int:
        return len(self._items)

    def clear(self) -> None:
        with self._lock:
            self._items.clear()
            self._bytes = 0


def hashable(key):
    """``key``, or None where it cannot be hashed (a store builds such a value, never keeps it;
    `railride.studies.case` makes such a setting's suspension each time)."""
    try:
        hash(key)
    except TypeError:
        return None
    return key
