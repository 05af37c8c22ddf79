"""One module on a bench: its real class with a stand-in runtime, fed messages by hand and run step by step,
for unit tests of a module's glue without a bus or other processes."""

from __future__ import annotations

from typing import Any, TypeVar

from stack.msg.base import Message
from stack.msg.topic import Topic
from stack.params.store import ParamStore
from stack.runtime.module import Module
from stack.runtime.spec import ModuleSpec, resolve_args

M = TypeVar("M", bound=Message)


class _Input:
    def __init__(self) -> None:
        self.latest: Any = None
        self._fresh = False

    def put(self, msg: Any) -> None:
        self.latest = msg
        self._fresh = True

    def update(self) -> Any:
        fresh, self._fresh = self._fresh, False
        return self.latest if fresh else None

    def take(self) -> list[Any]:
        fresh = self.update()
        return [] if fresh is None else [fresh]


class _Output:
    def __init__(self) -> None:
        self.sent: list[Any] = []

    def publish(self, msg: Any, now_us: int) -> None:
        if msg.timestamp == 0:
            msg.timestamp = now_us
        self.sent.append(msg)


class ModuleBench:
    """``bench = ModuleBench(MyModule, {"PARAM": 1})``; ``bench.put(ORB_ID.topic, msg)``; ``bench.run(msg, dt)``;
    ``bench.sent(ORB_ID.topic)`` lists what the module published there, oldest first."""

    def __init__(
        self, cls: type[Module], params: dict[str, object] | None = None, args: dict[str, Any] | None = None
    ) -> None:
        self.name = cls.NAME
        self.params = ParamStore(cls.PARAMS, params)
        self.args: dict[str, Any] = resolve_args(cls.ARGS, args or {})
        self.spec = ModuleSpec(name=cls.NAME, module=cls.NAME)
        self.inputs: dict[tuple[str, int], _Input] = {}
        self.outputs: dict[tuple[str, int], _Output] = {}
        self.rejected = 0
        self.behind = False
        self.now = 0
        self.module = cls(self)  # type: ignore[arg-type]

    def add_input(self, topic: str, instance: int, queue: bool, capacity: int) -> None:
        self.inputs[(topic, instance)] = _Input()

    def add_output(self, topic: str, instance: int, reliable: bool | None) -> None:
        self.outputs[(topic, instance)] = _Output()

    def now_us(self) -> int:
        return self.now

    def watch_modules(self, on_change: Any) -> None:
        """No other module processes on a bench."""

    def put(self, topic: Topic[M], msg: M, instance: int = 0) -> None:
        """Deliver ``msg`` on ``topic`` (stamped now when its timestamp is 0)."""
        if msg.timestamp == 0:
            msg.timestamp = self.now
        self.inputs[(topic.name, instance)].put(msg)

    def set_param(self, name: str, value: object) -> None:
        self.params.set(name, value)
        self.module.on_params_changed(self.params.take_changes())

    def run(self, msg: Any, dt: float) -> None:
        """One run triggered by ``msg``, ``dt`` seconds after the previous one (the clock advances by dt)."""
        self.now += round(dt * 1e6)
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
