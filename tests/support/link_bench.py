"""The two modules that serve a MAVLink link from a thread of their own (``mavlink``, ``pixhawk``) on a bench:
their real class with :class:`~tests.support.bench.ModuleBench`'s stand-in runtime, plus a stand-in for the node
they subscribe through directly (they read topics outside the runtime's inputs, on the link thread), so a test
feeds bus messages by hand and sees what they publish without Zenoh or other processes. The link itself is real:
the test talks to it with pymavlink over 127.0.0.1 UDP on ports the OS chooses."""

from __future__ import annotations

import threading
import time
from collections import deque
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

from stack.msg.topic import Topic
from stack.runtime.module import Module
from tests.support.bench import ModuleBench


@dataclass
class _Item:
    msg: Any


class BusSub:
    """A subscription fed by :meth:`BusStandIn.put`: ``poll()`` as a TopicSubscriber's, ``received`` counted, the
    module's wake-up called for each message if it gave one."""

    def __init__(self, capacity: int, wake: Callable[[], None] | None = None) -> None:
        self.queue: deque[_Item] = deque(maxlen=capacity)
        self.received = 0
        self.wake = wake
        self.closed = False

    def put(self, msg: Any) -> None:
        self.queue.append(_Item(msg))
        self.received += 1
        if self.wake is not None:
            self.wake()

    def poll(self) -> _Item | None:
        try:
            return self.queue.popleft()
        except IndexError:
            return None


class BusStandIn:
    """``rt.node`` for these modules: the subscriptions they declare, by topic name."""

    vehicle = "v1"
    session = None

    def __init__(self, name: str) -> None:
        self.name = name
        self.subs: dict[str, list[BusSub]] = {}
        self._lock = threading.Lock()

    def add(self, topic_name: str, capacity: int, wake: Callable[[], None] | None = None) -> BusSub:
        sub = BusSub(capacity, wake)
        with self._lock:
            self.subs.setdefault(topic_name, []).append(sub)
        return sub

    def subscriber(self, topic_name: str, capacity: int, callback: bool = True) -> BusSub:
        return self.add(topic_name, capacity)

    def open(self, topic: Topic) -> list[BusSub]:
        with self._lock:
            return [s for s in self.subs.get(topic.name, []) if not s.closed]

    def put(self, topic: Topic, msg: Any) -> None:
        """Deliver ``msg`` to every open subscription of ``topic`` (on the test's thread, as Zenoh's would)."""
        for sub in self.open(topic):
            sub.put(msg)


class LinkBench(ModuleBench):
    """``ModuleBench`` with ``node`` (a :class:`BusStandIn`) and the error count the link thread keeps."""

    def __init__(
        self,
        cls: type[Module],
        params: dict[str, object] | None = None,
        args: dict[str, Any] | None = None,
        **spec: Any,
    ) -> None:
        self.errors = 0
        super().__init__(cls, params, args, **spec)

    def stand_in_node(self) -> BusStandIn:
        return BusStandIn(self.name)


def wait_for(ok: Callable[[], Any], timeout: float = 5.0, what: str = "the condition") -> Any:
    """``ok()``'s first true answer, polled every millisecond (a condition, never a fixed time); fails naming
    ``what`` after ``timeout``."""
    deadline = time.monotonic() + timeout
    while not (answer := ok()):
        if time.monotonic() > deadline:
            raise AssertionError(f"{what}: not within {timeout:g} s")
        time.sleep(0.001)
    return answer
