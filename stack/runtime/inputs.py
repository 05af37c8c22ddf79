"""A module's view of one subscribed topic: the latest value, or a queue of every message.

In lockstep the view is made deterministic. A module acting at time ``t`` because of a trigger
message from publisher ``P`` sees:

- every message a lockstep member published before ``t``;
- the messages ``P`` published at ``t`` before the trigger (same publisher, lower sequence);
- messages from outside the lockstep (a user's CLI command) as soon as they arrive.

Messages other members publish at ``t`` wait for the next run. Which of them a module sees thus
never depends on which process the scheduler ran first. In real time, everything received is seen.

Whatever the transport and the clock, two kinds of message are never seen, and the last good message stays
the latest: one from a publisher the module does not hear (:mod:`stack.bus.access`), counted in
``unauthorized``, and one holding a value its type does not allow (NaN in a state, infinity:
:mod:`stack.msg.validity`), counted in ``invalid``.
"""

from __future__ import annotations

import logging
from collections.abc import Callable
from typing import Any

from stack.bus.topics import Received, TopicSubscriber
from stack.msg.validity import refusal

log = logging.getLogger("stack.runtime")


def visible(published_us: int, publisher: int, seq: int, now_us: int, trigger_publisher: int, trigger_seq: int) -> bool:
    """Whether a run at ``now_us`` for the trigger ``(trigger_publisher, trigger_seq)`` sees a message a lockstep
    member published at ``published_us`` (the rule of the module docstring; -1 for a timer tick's trigger)."""
    return published_us < now_us or (publisher == trigger_publisher and seq < trigger_seq)


class InputBuffer:
    __slots__ = (
        "_latest_key",
        "_new",
        "_pending",
        "_queue",
        "invalid",
        "last_index",
        "latest",
        "members",
        "open_while",
        "queue_mode",
        "repeats",
        "sub",
        "unauthorized",
    )

    def __init__(self, sub: TopicSubscriber, queue_mode: bool, repeats: bool = True) -> None:
        self.sub = sub
        self.queue_mode = queue_mode
        self.repeats = repeats
        """Whether a message may arrive twice (a lockstep publisher's topic indices only grow: one that does not is
        the same message again, put by its publisher and relayed, see stack.fastpath.bridge)."""
        self.latest: Any = None
        self._latest_key: tuple[int, int, int] = (-1, 0, 0)
        self._new = False
        self._pending: list[Received] = []
        self._queue: list[tuple[tuple[int, int, int], Any]] = []
        # Highest topic index received per publisher id, for the lockstep barrier. A latest-value input
        # may sit on a ring buffer that drops old messages: the barrier only needs the newest to be in.
        self.last_index: dict[int, int] = {}
        self.invalid = 0
        self.unauthorized = 0
        # Whom the input hears (stack.bus.access): None, anyone; else these publisher ids, and anyone while
        # ``open_while()`` says so.
        self.members: frozenset[int] | None = None
        self.open_while: Callable[[], bool] | None = None

    @property
    def received(self) -> int:
        return self.sub.received

    @property
    def decode_errors(self) -> int:
        return self.sub.decode_errors

    @property
    def schema_errors(self) -> int:
        return self.sub.schema_errors

    @property
    def foreign(self) -> int:
        return self.sub.foreign

    @property
    def ring_decode_errors(self) -> int:
        """Malformed messages read from elsewhere than the subscriber (the fast path's rings)."""
        return 0

    @property
    def lost(self) -> int:
        """Messages overwritten before this input read them (a fast-path ring lapped a slow reader)."""
        return 0

    def admits(self, msg: Any, publisher: int) -> bool:
        """Whether the module may see ``msg`` from ``publisher``; counts and logs the ones refused."""
        members = self.members
        if members is not None and publisher not in members and not (self.open_while and self.open_while()):
            self.unauthorized += 1
            if self.unauthorized == 1 or self.unauthorized % 1000 == 0:
                log.warning(
                    "%s: ignored a message from publisher %08x, no module of this vehicle publishing it (%d so far)",
                    self.sub.suffix,
                    publisher,
                    self.unauthorized,
                )
            return False
        why = refusal(msg)
        if why is None:
            return True
        self.invalid += 1
        if self.invalid == 1 or self.invalid % 1000 == 0:
            log.warning("%s: dropped a message holding %s (%d so far)", self.sub.suffix, why, self.invalid)
        return False

    def pull(self) -> None:
        """Move everything Zenoh has delivered into the pending list."""
        poll = self.sub.poll
        last = self.last_index
        repeats = self.repeats
        item = poll()
        while item is not None:
            if item.index > last.get(item.publisher, 0):
                last[item.publisher] = item.index
                self._pending.append(item)
            elif repeats or item.time_us < 0:
                self._pending.append(item)
            item = poll()

    def promote_all(self) -> None:
        """Real time: every received message becomes visible, in arrival order."""
        if not self._pending:
            return
        admitted = [item.msg for item in self._pending if self.admits(item.msg, item.publisher)]
        self._pending.clear()
        if not admitted:
            return
        if self.queue_mode:
            # One shared key: the stable sort in take() then keeps arrival order.
            self._queue.extend(((0, 0, 0), msg) for msg in admitted)
        self.latest = admitted[-1]
        self._new = True

    def take_in_everything(self) -> None:
        """Real time: make every message received so far visible (and a passive module's last look before it
        stops)."""
        self.pull()
        self.promote_all()

    def refresh(
        self, now: int, members: frozenset[int], trigger_publisher: int = -1, trigger_seq: int = 0
    ) -> None:
        """Lockstep: take in what a run at ``now`` may see, for a tick or for the trigger message ``trigger_seq``
        of ``trigger_publisher``, in a run of ``members`` (the rules of the module docstring)."""
        self.pull()
        self.promote_visible(now, trigger_publisher, trigger_seq, members)

    def promote_visible(self, now: int, trigger_pub: int, trigger_seq: int, members: frozenset[int]) -> None:
        """Lockstep: make visible exactly the messages the rules in the module docstring allow."""
        if not self._pending:
            return
        pending = self._pending
        waiting: list[Received] = []
        for item in pending:
            t, pub, seq = item.time_us, item.publisher, item.seq
            if pub not in members:
                self._accept((now, pub, seq), item.msg)
            elif visible(t, pub, seq, now, trigger_pub, trigger_seq):
                self._accept((t, pub, seq), item.msg)
            else:
                waiting.append(item)
        pending[:] = waiting  # the same list: the memory bus appends to it (stack.runtime.membus.MemoryInput)

    def _accept(self, key: tuple[int, int, int], msg: Any) -> None:
        if not self.admits(msg, key[1]):
            return
        if self.queue_mode:
            self._queue.append((key, msg))
        if key >= self._latest_key:
            self._latest_key = key
            self.latest = msg
            self._new = True

    def update(self) -> Any:
        """The latest message if it is new since the previous call, else None (PX4's ``update()``)."""
        if self._new:
            self._new = False
            return self.latest
        return None

    def take(self) -> list[Any]:
        """All messages that became visible since the previous call, oldest first."""
        if not self._queue:
            return []
        if len(self._queue) > 1:
            self._queue.sort(key=lambda entry: entry[0])
        msgs = [msg for _, msg in self._queue]
        self._queue.clear()
        self._new = False
        return msgs


def sample_time(msg: Any) -> int:
    """The time a message's data refers to: ``timestamp_sample`` when it has one (PX4's dt source)."""
    return getattr(msg, "timestamp_sample", 0) or msg.timestamp
