"""A stop request that a signal handler may make: an event whose ``set`` takes no lock.

Python runs a signal handler in the main thread between two of its bytecodes, wherever that thread is, also inside
``threading.Event.wait()`` while it holds the event's lock (taking it back after a timed wait). A handler that calls
``Event.set()`` there waits for that lock for ever, and the process never stops. :class:`StopEvent` keeps its state
in a plain attribute and wakes its waiters through an eventfd, which only the kernel guards.
"""

from __future__ import annotations

import os
import select
import weakref


class StopEvent:
    """``set``, ``is_set`` and ``wait`` as ``threading.Event``'s, with ``set`` safe in a signal handler. Once set it
    stays set (a stop is not taken back)."""

    def __init__(self) -> None:
        self._set = False
        self._fd = os.eventfd(0, os.EFD_NONBLOCK | os.EFD_CLOEXEC)
        # Closed once nothing can set or wait on it any more (a callback of another thread may, until then).
        weakref.finalize(self, os.close, self._fd)

    def set(self) -> None:
        if not self._set:
            self._set = True
            os.eventfd_write(self._fd, 1)  # never read: the eventfd stays readable and wakes every waiter

    def is_set(self) -> bool:
        return self._set

    def wait(self, timeout: float | None = None) -> bool:
        """Until set or ``timeout`` seconds have passed; whether it is set."""
        if not self._set:
            select.select([self._fd], [], [], timeout)
        return self._set
