"""A bounded queue between a Zenoh subscriber's callback and a tool that prints what arrives: behind a
slow reader (a terminal, a pipe) the oldest items are dropped and counted, so memory stays bounded and
the newest is always shown."""

from __future__ import annotations

import collections
import threading
from typing import Generic, TypeVar

T = TypeVar("T")


class Inbox(Generic[T]):
    def __init__(self, capacity: int) -> None:
        if capacity < 1:
            raise ValueError(f"capacity must be at least 1, got {capacity}")
        self._items: collections.deque[T] = collections.deque(maxlen=capacity)
        self._ready = threading.Condition()
        self.dropped = 0
        """Items dropped, oldest first, because the reader fell behind."""

    def put(self, item: T) -> None:
        with self._ready:
            if len(self._items) == self._items.maxlen:
                self.dropped += 1
            self._items.append(item)
            self._ready.notify()

    def get(self, timeout: float) -> T | None:
        """The oldest item, waiting at most ``timeout`` seconds for one; None if none came."""
        with self._ready:
            if not self._items and not self._ready.wait_for(lambda: bool(self._items), timeout):
                return None
            return self._items.popleft()
