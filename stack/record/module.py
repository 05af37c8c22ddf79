"""The ``recorder`` module: every topic of the vehicle into an MCAP file, like PX4's logger.

It is passive: it never joins the lockstep and the simulation does not wait for its runs, but it
never loses a message either. On the same-host fast path (:mod:`stack.fastpath`) it reads every
ring directly and is a lossless reader: lockstep time waits for it only when it falls far behind.
Over Zenoh its subscription is declared before the stack starts and the bus blocks rather than drops
(its queue is large in real time; in lockstep it is kept short, so that on stop little is left to write,
and once full, lockstep publishers wait). Messages from outside the run come
through one wildcard subscriber on ``stack/<vehicle>/*/*``. Both feed a writer thread: the module's
main thread can be interrupted by a stop signal at any instruction, so the file is only ever written
by that thread, which on stop drains what is still queued, then writes the summary.

List it first in a profile: the supervisor stops modules in reverse order, so it then records
until every other module has stopped (listed last, it stops while the others still publish).

Samples whose schema fingerprint is this build's are recorded as JSON; the rest (a topic not in
the catalogue, a foreign fingerprint, a payload that does not decode) are recorded verbatim under
the sender's fingerprint (see :mod:`stack.record.format`). Samples without a stack header are
counted and skipped, and so are publishers' start-up probes (header flag bit 1, no message).

Arguments: ``path`` (required) the MCAP file to write, replaced if it exists; ``topics``
(optional) a comma-separated selection such as ``sensor_gyro,vehicle_attitude/0``.
"""

from __future__ import annotations

import collections
import json
import logging
import threading
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

import msgspec
import zenoh

from stack.bus import keys
from stack.bus.node import stable_publisher_id, wall_clock_us
from stack.bus.topics import FLAG_LOCKSTEP_TIME, FLAG_PROBE, HEADER
from stack.fastpath.alltopics import AllTopicsReader, RingRecord
from stack.msg.registry import TOPICS, fingerprint
from stack.record.provenance import git_commit
from stack.record.recorder import RecordingWriter, new_recording_info
from stack.record.selection import TopicSelection
from stack.runtime.module import Arg, Module, Timer
from stack.supervisor import state as run_state

QUEUE_CAPACITY = 1 << 16
# In lockstep the backlog is bounded tighter (Zenoh queue, and fast-path records read but not written
# yet): past it lockstep time waits for the writer, so the backlog left to write on stop stays a
# fraction of a second even on a loaded machine (the writer does about 75,000 messages/s on one core).
LOCKSTEP_QUEUE_CAPACITY = 1 << 13
FAST_BACKLOG = 1 << 12
IDLE_SLEEP_S = 0.002
STOP_QUIET_S = 0.2  # on stop, drain until the queue has been empty this long...
STOP_DRAIN_S = 3.0  # ...or this long at most (the stack may still be publishing)
STOP_TIMEOUT_S = 4.0  # the supervisor kills a module 5 s after asking it to stop
STATUS_PERIOD_S = 10.0


class _Route:
    __slots__ = ("decoder", "fingerprint", "instance", "topic", "type_name")

    def __init__(self, topic: str, instance: int) -> None:
        self.topic = topic
        self.instance = instance
        known = TOPICS.get(topic)
        msg_type = known.type if known is not None else None
        self.decoder = msgspec.msgpack.Decoder(msg_type) if msg_type is not None else None
        self.fingerprint = fingerprint(msg_type) if msg_type is not None else None
        self.type_name = msg_type.__name__ if msg_type is not None else ""


class SampleRecorder:
    """Turns bus samples (stack header + msgpack payload) into recording writes.

    The log time is the recording clock: in lockstep, the latest lockstep publication time seen
    (the simulated time at which the message arrived); in real time, the wall clock.
    """

    def __init__(
        self,
        writer: RecordingWriter,
        selection: TopicSelection,
        lockstep: bool,
        clock: Callable[[], int] = wall_clock_us,
    ) -> None:
        self.writer = writer
        self.selection = selection
        self.lockstep = lockstep
        self.clock = clock
        self.sim_now_us = 0
        self.without_header = 0
        # Publishers whose messages come from the fast path: their Zenoh copies are skipped. On the fast path every
        # sample with lockstep time is such a copy, also before the run's publishers are known.
        self.fast_publishers: frozenset[int] = frozenset()
        self.fast_path = False
        self._routes: dict[str, _Route | None] = {}
        self._suffix_routes: dict[str, _Route | None] = {}

    def _route(self, key: str) -> _Route | None:
        parsed = keys.parse_topic_key(key)
        route = None
        if parsed is not None and (parsed[1], parsed[2]) in self.selection:
            route = _Route(parsed[1], parsed[2])
        self._routes[key] = route
        return route

    def handle_fast(self, record: RingRecord) -> None:
        """A record read from the fast path: lockstep time, logged at its publication time."""
        suffix, pub_time = record.topic, record.time_us
        try:
            route = self._suffix_routes[suffix]
        except KeyError:
            topic, _, instance = suffix.rpartition("/")
            route = _Route(topic, int(instance)) if (topic, int(instance)) in self.selection else None
            self._suffix_routes[suffix] = route
        if route is None:
            return
        if pub_time > self.sim_now_us:
            self.sim_now_us = pub_time
        fp, publisher, index = record.fingerprint, record.publisher_id, record.index
        self._record(route, fp, publisher, index, pub_time, FLAG_LOCKSTEP_TIME, pub_time, record.payload)

    def handle(self, sample: zenoh.Sample) -> None:
        key = str(sample.key_expr)
        try:
            route = self._routes[key]
        except KeyError:
            route = self._route(key)
        if route is None:
            return
        attachment = sample.attachment
        header = attachment.to_bytes() if attachment is not None else b""
        if len(header) != HEADER.size:
            self.without_header += 1
            return
        fp, publisher, _seq, index, pub_time, flags, _run = HEADER.unpack(header)
        if flags & FLAG_PROBE or publisher in self.fast_publishers or (self.fast_path and flags & FLAG_LOCKSTEP_TIME):
            return  # a publisher announcing itself at start-up, or a copy of a fast-path record
        if self.lockstep:
            if flags & FLAG_LOCKSTEP_TIME and pub_time > self.sim_now_us:
                self.sim_now_us = pub_time
            log_time = self.sim_now_us
        else:
            log_time = self.clock()
        self._record(route, fp, publisher, index, pub_time, flags, log_time, sample.payload.to_bytes())

    def _record(
        self,
        route: _Route,
        fp: int,
        publisher: int,
        index: int,
        pub_time: int,
        flags: int,
        log_time: int,
        payload: bytes,
    ) -> None:
        if fp == route.fingerprint:
            try:
                msg = route.decoder.decode(payload)
            except msgspec.DecodeError as e:
                reason = f"payload does not decode as {route.type_name}: {e}"
            else:
                self.writer.write(route.topic, route.instance, msg, publisher, index, pub_time, flags, log_time)
                return
        elif route.decoder is None:
            reason = "topic not in this build's catalogue"
        else:
            reason = f"schema fingerprint differs from this build's {route.type_name} ({route.fingerprint:016x})"
        self.writer.write_raw(
            route.topic, route.instance, payload, fp, publisher, index, pub_time, flags, log_time, reason
        )


class RecordingPump:
    """The writer thread: drains the subscriber's queue into a SampleRecorder, then closes the file.

    If writing fails (disk full, or a bug), it logs the error once and keeps draining without
    writing, so that a full queue never holds up the stack.
    """

    def __init__(self, sub: Any, sink: SampleRecorder, log: logging.Logger) -> None:
        self._sub = sub
        self._sink = sink
        # Records the module's thread read from the fast path, waiting for this thread.
        self.fast: collections.deque[RingRecord] = collections.deque()
        self._log = log
        self._stop = threading.Event()
        self._stop_deadline = 0.0
        self.failed: str | None = None
        self.errors = 0
        self.discarded = 0
        self._thread = threading.Thread(target=self._run, name="recorder-writer", daemon=True)

    def start(self) -> None:
        self._thread.start()

    def stop(self, timeout_s: float = STOP_TIMEOUT_S) -> bool:
        """Drain what is still queued, finish the file; False if that took longer than the timeout."""
        self._stop_deadline = time.monotonic() + STOP_DRAIN_S
        self._stop.set()
        self._thread.join(timeout_s)
        return not self._thread.is_alive()

    def _run(self) -> None:
        writer = self._sink.writer
        try:
            self._drain()
        except Exception as e:
            disk = isinstance(e, OSError)
            self.failed = f"cannot write {writer.path}: {e.strerror or e}" if disk else f"{type(e).__name__}: {e}"
            self._log.error("recording stopped: %s; discarding the rest", self.failed, exc_info=not disk)
            self._discard()
        finally:
            try:
                writer.close(self._end_info())
            except Exception as e:
                self._log.error("could not finish %s: %s", writer.path, e)

    def _drain(self) -> None:
        try_recv = self._sub.try_recv
        handle = self._sink.handle
        writer = self._sink.writer
        busy = False
        handled = 0
        last_sample = time.monotonic()
        while True:
            if self.fast:
                self._drain_fast()
                busy = True
                continue
            sample = try_recv()
            if sample is not None:
                busy = True
                handled += 1
                if handled & 1023 == 0 and self._stop.is_set() and time.monotonic() >= self._stop_deadline:
                    self._cut_short()  # the stack keeps publishing faster than we write: stop anyway
                    return
                try:
                    handle(sample)
                except OSError:
                    raise
                except Exception:
                    self.errors += 1
                    if self.errors <= 10 or self.errors % 1000 == 0:
                        self._log.exception("failed to record a sample on %s (%d so far)", sample.key_expr, self.errors)
                continue
            now = time.monotonic()
            if busy:
                busy = False
                last_sample = now
            if self._stop.is_set() and (now - last_sample >= STOP_QUIET_S or now >= self._stop_deadline):
                return
            writer.flush_if_due()
            time.sleep(IDLE_SLEEP_S)

    def _drain_fast(self) -> None:
        handle = self._sink.handle_fast
        pending = self.fast
        while pending:
            record = pending.popleft()
            try:
                handle(record)
            except OSError:
                raise
            except Exception:
                self.errors += 1
                if self.errors <= 10 or self.errors % 1000 == 0:
                    self._log.exception("failed to record a message on %s (%d so far)", record.topic, self.errors)

    def _cut_short(self) -> None:
        for _ in range(QUEUE_CAPACITY):
            if self._sub.try_recv() is None:
                break
            self.discarded += 1
        self._log.error("recording cut short on stop: %d queued messages not written", self.discarded)

    def _discard(self) -> None:
        while not self._stop.is_set():
            while self._sub.try_recv() is not None:
                self.discarded += 1
            self.discarded += len(self.fast)
            self.fast.clear()
            time.sleep(IDLE_SLEEP_S)

    def _end_info(self) -> dict[str, str]:
        return {
            "without_header": str(self._sink.without_header),
            "record_errors": str(self.errors),
            "write_error": self.failed or "",
            "discarded": str(self.discarded),
        }


def profile_name(vehicle: str, supervisor_pid: int) -> str:
    """The launch profile of the running stack, from the state file its supervisor wrote."""
    try:
        state = json.loads(run_state.state_path(vehicle, supervisor_pid).read_text())
    except (OSError, json.JSONDecodeError):
        return ""
    return Path(str(state.get("profile", ""))).stem


class RecorderModule(Module):
    NAME = "recorder"
    DESCRIPTION = "Records every topic of the vehicle into an MCAP file (Foxglove, PlotJuggler, stack replay)"
    PASSIVE = True
    LOSSLESS = True
    TRIGGER = Timer(20.0)
    ARGS = (
        Arg("path", "", doc="MCAP file to write (replaced if it exists)"),
        Arg("topics", "", doc="Only these topics, comma-separated: name or name/instance (default: all)"),
    )

    def __init__(self, rt: Any) -> None:
        super().__init__(rt)
        path_arg = str(self.args["path"]).strip()
        if not path_arg:
            raise ValueError("recorder: the argument 'path' is required (the MCAP file to write)")
        selection = TopicSelection([str(self.args["topics"])])
        spec = rt.spec
        path = Path(path_arg).expanduser().resolve()
        info = new_recording_info(
            spec.vehicle,
            profile_name(spec.vehicle, spec.supervisor_pid),
            spec.seed,
            spec.lockstep,
            git_commit(),
            publishers={stable_publisher_id(spec.vehicle, name): name for name in spec.peers},
        )
        try:
            path.parent.mkdir(parents=True, exist_ok=True)
            self.writer = RecordingWriter(path, info)
        except OSError as e:
            raise ValueError(f"recorder: cannot write {path}: {e.strerror or e}") from None
        self.sink = SampleRecorder(self.writer, selection, spec.lockstep)
        self._sub = rt.node.session.declare_subscriber(
            keys.all_topics(spec.vehicle),
            zenoh.handlers.FifoChannel(LOCKSTEP_QUEUE_CAPACITY if spec.lockstep else QUEUE_CAPACITY),
        )
        self.pump = RecordingPump(self._sub, self.sink, self.log)
        self.fast: AllTopicsReader | None = None
        if rt.fast is not None:
            rt.read_all_topics()
            self.fast = AllTopicsReader(rt.fast)
            self.sink.fast_path = True
        self.pump.start()
        self._next_status = time.monotonic() + STATUS_PERIOD_S
        what = "all topics" if selection.everything else f"topics {self.args['topics']}"
        self.log.info("recording %s of vehicle '%s' to %s", what, spec.vehicle, path)

    def run(self, msg: None, dt: float) -> None:
        if self.fast is not None and len(self.pump.fast) < FAST_BACKLOG:
            self._read_fast(final=False)
        now = time.monotonic()
        if now >= self._next_status:
            self._next_status = now + STATUS_PERIOD_S
            w = self.writer
            self.log.info("recorded %d messages (%d undecoded) to %s", w.messages, w.raw_messages, w.path.name)

    def status(self) -> dict[str, float | int | str | bool]:
        """The recording's figures for the heartbeat (``stack status``): what is in the file and what was not."""
        w = self.writer
        return {
            "recorded": w.messages,
            "undecoded": w.raw_messages,
            "record_errors": self.pump.errors,
            "fast_lost": self.fast.lost if self.fast is not None else 0,
        }

    def _read_fast(self, final: bool) -> None:
        assert self.fast is not None
        self.fast.read(self.pump.fast.append, final)
        self.sink.fast_publishers = self.fast.publisher_ids

    def close(self) -> None:
        if self.fast is not None:
            self._read_fast(final=True)
            if self.fast.lost:
                self.log.error("%d messages were overwritten on the fast path before being recorded", self.fast.lost)
        finished = self.pump.stop()
        w = self.writer
        if finished:
            self._sub.undeclare()
            self.log.info("recording finished: %d messages in %s", w.messages, w.path)
        else:
            self.log.error("recording of %s not finished in time: the file lacks its summary (still readable)", w.path)
