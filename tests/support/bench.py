"""One module on a bench: its real class with a stand-in runtime, fed messages by hand and run step by step,
for unit tests of a module's glue without a bus or other processes."""

from __future__ import annotations

import collections
from collections.abc import Callable
from typing import Any, TypeVar

from stack.bus.topics import Received
from stack.msg.base import Message
from stack.msg.topic import Topic
from stack.params.store import ParamStore
from stack.runtime.module import Module
from stack.runtime.spec import ModuleSpec, resolve_args

M = TypeVar("M", bound=Message)


class _Input:
    def __init__(self, queue: bool = False) -> None:
        self.latest: Any = None
        self._fresh = False
        self._queue: list[Any] | None = [] if queue else None

    def put(self, msg: Any) -> None:
        self.latest = msg
        self._fresh = True
        if self._queue is not None:
            self._queue.append(msg)

    def update(self) -> Any:
        fresh, self._fresh = self._fresh, False
        return self.latest if fresh else None

    def take(self) -> list[Any]:
        """Every message put since the previous call (a queue input), else the latest if fresh."""
        fresh = self.update()
        if self._queue is not None:
            taken, self._queue = self._queue, []
            return taken
        return [] if fresh is None else [fresh]


class _Subscription:
    """Stands in for a subscriber the module opens on the node itself (``node.subscriber``, wrapped in its own
    InputBuffer): with ``keep_last`` a ring of ``capacity`` that drops its oldest, as Zenoh's ring channel."""

    def __init__(self, topic: str, instance: int, capacity: int, keep_last: bool) -> None:
        self.suffix = f"{topic}/{instance}"
        self.capacity = capacity
        self.keep_last = keep_last
        self._ring: collections.deque[Received] = collections.deque(maxlen=capacity if keep_last else None)
        self._seq = 0

    def put(self, msg: Any) -> None:
        self._seq += 1
        self._ring.append(Received(time_us=-1, publisher=1, seq=self._seq, msg=msg, index=self._seq))

    def poll(self) -> Received | None:
        return self._ring.popleft() if self._ring else None


class _Channel:
    """Stands in for a raw Zenoh subscriber with a FIFO channel (``session.declare_subscriber``)."""

    def __init__(self, key: str, handler: Any) -> None:
        self.key = key
        self.handler = handler
        self.samples: collections.deque[Any] = collections.deque()
        self.undeclared = False

    def try_recv(self) -> Any:
        return self.samples.popleft() if self.samples else None

    def undeclare(self) -> None:
        self.undeclared = True


class _Session:
    """What a module asks of the Zenoh session itself: raw subscribers (``channels``, by key), and queries
    (``queries``, by key), each answered by ``replies``."""

    def __init__(self) -> None:
        self.channels: dict[str, _Channel] = {}
        self.replies: list[Any] = []
        self.queries: list[str] = []

    def declare_subscriber(self, key: str, handler: Any = None) -> _Channel:
        self.channels[key] = _Channel(key, handler)
        return self.channels[key]

    def get(self, key: str, payload: Any = None, **options: Any) -> list[Any]:
        self.queries.append(key)
        return list(self.replies)


class _Node:
    def __init__(self, vehicle: str) -> None:
        self.vehicle = vehicle
        self.session = _Session()
        self.subscriptions: dict[tuple[str, int], _Subscription] = {}

    def subscriber(
        self, topic: str, instance: int = 0, *, capacity: int = 256, keep_last: bool = False, **options: Any
    ) -> _Subscription:
        self.subscriptions[(topic, instance)] = _Subscription(topic, instance, capacity, keep_last)
        return self.subscriptions[(topic, instance)]


class _Output:
    def __init__(self) -> None:
        self.sent: list[Any] = []

    def publish(self, msg: Any, now_us: int) -> None:
        if msg.timestamp == 0:
            msg.timestamp = now_us
        self.sent.append(msg)


class ModuleBench:
    """``bench = ModuleBench(MyModule, {"PARAM": 1}, {"arg": "x"}, vehicle="v2")`` (the last: ModuleSpec fields);
    ``bench.put(ORB_ID.topic, msg)``; ``bench.run(msg, dt)``;
    ``bench.sent(ORB_ID.topic)`` lists what the module published there, oldest first.

    A module that opens subscribers on the node itself, or talks to the Zenoh session, gets stand-ins
    (``bench.node``); the bench is a real-time runtime over Zenoh (``fast`` is None: no same-host fast path)."""

    fast: Any = None

    def __init__(
        self,
        cls: type[Module],
        params: dict[str, object] | None = None,
        args: dict[str, Any] | None = None,
        **spec: Any,
    ) -> None:
        self.name = cls.NAME
        self.params = ParamStore(cls.PARAMS, params)
        self.args: dict[str, Any] = resolve_args(cls.ARGS, args or {})
        self.spec = ModuleSpec(name=cls.NAME, module=cls.NAME, **spec)
        self.inputs: dict[tuple[str, int], _Input] = {}
        self.outputs: dict[tuple[str, int], _Output] = {}
        self.rejected = 0
        self.behind = False
        self.now = 0
        self.node = self.stand_in_node()
        self.host_watchers: list[Callable[[str, bytes], None]] = []
        self.module_watchers: list[Callable[[str, int, bool], None]] = []
        self.module = cls(self)  # type: ignore[arg-type]

    def stand_in_node(self) -> Any:
        """What the module gets as ``rt.node`` (a bench for other modules may give its own)."""
        return _Node(self.spec.vehicle)

    def add_input(self, topic: str, instance: int, queue: bool, capacity: int) -> None:
        self.inputs[(topic, instance)] = _Input(queue)

    def add_output(self, topic: str, instance: int, reliable: bool | None) -> None:
        self.outputs[(topic, instance)] = _Output()

    def now_us(self) -> int:
        return self.now

    def watch_modules(self, on_change: Callable[[str, int, bool], None]) -> None:
        """No other module processes on a bench: a test tells of them with :meth:`module_changed`."""
        self.module_watchers.append(on_change)

    def module_changed(self, module: str, pid: int, alive: bool) -> None:
        for on_change in self.module_watchers:
            on_change(module, pid, alive)

    def watch_hosts(self, on_beat: Callable[[str, bytes], None]) -> None:
        """No other hosts on a bench: a test beats for them with :meth:`host_beat`."""
        self.host_watchers.append(on_beat)

    def host_beat(self, host: str, payload: bytes = b"") -> None:
        for on_beat in self.host_watchers:
            on_beat(host, payload)

    def put(self, topic: Topic[M], msg: M, instance: int = 0) -> None:
        """Deliver ``msg`` on ``topic`` (stamped now when its timestamp is 0)."""
        if msg.timestamp == 0:
            msg.timestamp = self.now
        inp = self.inputs[(topic.name, instance)]
        if isinstance(inp, _Input):
            inp.put(msg)
        else:  # an InputBuffer the module made on a node.subscriber
            self.node.subscriptions[(topic.name, instance)].put(msg)

    def set_param(self, name: str, value: object) -> None:
        self.params.set(name, value)
        self.module.on_params_changed(self.params.take_changes())

    def run(self, msg: Any, dt: float) -> None:
        """One run triggered by ``msg``, ``dt`` seconds after the previous one (the clock advances by dt)."""
        self.now += round(dt * 1e6)
        for inp in self.inputs.values():
            if not isinstance(inp, _Input):
                inp.take_in_everything()  # as a real-time runtime does before each run
        self.module.run(msg, dt)

    def sent(self, topic: Topic[M], instance: int = 0) -> list[M]:
        return self.outputs[(topic.name, instance)].sent


class Calls(list):
    """The arguments of each call to a method stood in for by :func:`stand_in` (a tuple each, ``self`` left out);
    each call answers ``returns``."""

    returns: Any = None


def stand_in(monkeypatch: Any, cls: type, method: str, returns: Any = None, *, through: bool = False) -> Calls:
    """Replace ``cls.method`` for the test by one recording its calls and answering ``returns`` (with ``through``,
    what the method itself answers): to see what a module's glue hands its algorithm, and what it makes of an
    answer."""
    calls = Calls()
    calls.returns = returns
    original = getattr(cls, method)

    def record(self: Any, *args: Any) -> Any:
        calls.append(args)
        return original(self, *args) if through else calls.returns

    monkeypatch.setattr(cls, method, record)
    return calls
