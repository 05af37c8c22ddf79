"""One simulated clock for the vehicles of a swarm, each running its own lockstep (stack.cli.swarm_launch).

As the vehicles of one Gazebo world follow its one ``/clock`` (PX4's ``GZBridge::clockCallback``), a vehicle's
lockstep coordinator begins step ``t`` only once every other vehicle of the world is at most SLACK_US behind it;
when it must wait, it waits until every other one has finished the step before ``t``, then may run SLACK_US ahead
again. So the vehicles are never more than SLACK_US apart, and a vehicle sleeps once per SLACK_US of simulated time
rather than once per step (each sleep a wake-up across processes, the dearest thing on a virtual machine). What
one vehicle reads of another does not depend on how far apart they are: a peer input gives each message a fixed
delay longer than SLACK_US and waits for it when it is due (stack.runtime.peers).

The world is a small file shared by the vehicles' coordinators, one slot per vehicle: the last step it finished
(µs; LEFT once it has left the world), a 32-bit sequence bumped at each step, on which the others sleep (a
futex on the shared mapping, woken at each bump), and its coordinator's pid. The file's creator (the swarm's
launcher) sets a slot LEFT when its vehicle's stack ends, and a vehicle's coordinator does on its way out; a
waiting coordinator that finds the laggard's pid gone counts it left too. Without futexes (another machine
than x86-64 or arm64) the wait polls every 0.2 ms.
"""

from __future__ import annotations

import ctypes
import logging
import mmap
import os
import platform
import struct
import time
from pathlib import Path
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    import zenoh

    from stack.runtime.bus_world_clock import BusWorldClock
    from stack.runtime.spec import ModuleSpec

log = logging.getLogger("stack.lockstep")

SLOT_BYTES = 32
_DONE, _SEQ, _PID = 0, 8, 16
LEFT = (1 << 63) - 1
"""A slot's finished step once its vehicle has left the world: every step waits no more for it."""
BUS_WORLD = "bus"
"""A swarm's ``world`` when its clock is kept over the bus (stack.runtime.bus_world_clock) rather than in a file."""
SLACK_US = 50_000
"""How far ahead of the slowest vehicle of its world another may run (simulated µs)."""
WAIT_S = 0.1
"""How long a wait sleeps before it checks again that the vehicle it waits for is still there."""
SLOW_WAIT_S = 5.0
POLL_S = 0.0002
_FUTEX_SYSCALL = {"x86_64": 202, "aarch64": 98}.get(platform.machine())
_FUTEX_WAIT, _FUTEX_WAKE = 0, 1
_libc = ctypes.CDLL(None, use_errno=True)


class _Timespec(ctypes.Structure):
    _fields_ = [("tv_sec", ctypes.c_long), ("tv_nsec", ctypes.c_long)]


def create_world(path: Path, vehicles: int) -> None:
    """A world for ``vehicles`` vehicles, none of which has finished a step."""
    path.write_bytes(bytes(SLOT_BYTES * vehicles))


class World:
    """The world file, mapped: each slot's finished step, sequence and pid."""

    def __init__(self, path: Path) -> None:
        self._file = path.open("r+b")
        self._map = mmap.mmap(self._file.fileno(), 0)
        self.slots = len(self._map) // SLOT_BYTES
        self._seqs = [ctypes.c_uint32.from_buffer(self._map, s * SLOT_BYTES + _SEQ) for s in range(self.slots)]
        # Aligned 8-byte words, read and written whole (struct would copy them byte by byte, and a reader could see
        # half of a step another coordinator is writing).
        self._dones = [ctypes.c_int64.from_buffer(self._map, s * SLOT_BYTES + _DONE) for s in range(self.slots)]

    def done_us(self, slot: int) -> int:
        return self._dones[slot].value

    def pid(self, slot: int) -> int:
        return struct.unpack_from("=Q", self._map, slot * SLOT_BYTES + _PID)[0]

    def set_pid(self, slot: int, pid: int) -> None:
        struct.pack_into("=Q", self._map, slot * SLOT_BYTES + _PID, pid)

    def finish(self, slot: int, t_us: int) -> None:
        """Slot ``slot`` has finished step ``t_us`` (LEFT: left the world): wake whoever waits for it. Only its
        vehicle's coordinator calls it, or anyone once that coordinator is gone."""
        self._dones[slot].value = t_us
        word = self._seqs[slot]
        word.value = (word.value + 1) & 0xFFFFFFFF
        if _FUTEX_SYSCALL is not None:
            _libc.syscall(_FUTEX_SYSCALL, ctypes.byref(word), _FUTEX_WAKE, 0x7FFFFFFF, None, None, 0)

    def sleep_on(self, slot: int, seq: int) -> bool:
        """Sleep until slot ``slot``'s sequence moves on from ``seq`` or WAIT_S passes; False on time-out."""
        word = self._seqs[slot]
        if _FUTEX_SYSCALL is None:
            end = time.monotonic() + WAIT_S
            while word.value == seq:
                if time.monotonic() > end:
                    return False
                time.sleep(POLL_S)
            return True
        timeout = _Timespec(0, int(WAIT_S * 1e9))
        _libc.syscall(_FUTEX_SYSCALL, ctypes.byref(word), _FUTEX_WAIT, seq, ctypes.byref(timeout), None, 0)
        return word.value != seq

    def seq(self, slot: int) -> int:
        return self._seqs[slot].value

    def close(self) -> None:
        del self._seqs, self._dones
        self._map.close()
        self._file.close()


def leave_world(path: Path, slot: int) -> None:
    """Mark vehicle ``slot``'s place left (its stack has ended): the others go on without it."""
    world = World(path)
    try:
        world.finish(slot, LEFT)
    finally:
        world.close()


class WorldClock:
    """Vehicle ``slot``'s coordinator's side of the world in file ``path``: :meth:`wait` before each step,
    :meth:`done` after it, :meth:`close` on the way out."""

    def __init__(self, path: Path, slot: int, names: list[str]) -> None:
        """``names``: the vehicles by slot, to name the one time waits for."""
        self.world = World(path)
        if not 0 <= slot < self.world.slots:
            self.world.close()
            raise ValueError(f"{path}: no slot {slot} in a world of {len(names)} vehicles")
        self.slot = slot
        self.names = names
        self.world.set_pid(slot, os.getpid())

    def wait(self, t_us: int, period_us: int) -> None:
        """Block until every other vehicle is at most SLACK_US behind ``t_us``; once it must wait, until every other
        one has finished the steps before ``t_us``."""
        world = self.world
        slack = t_us - max(period_us, SLACK_US)
        if all(world.done_us(s) >= slack for s in range(world.slots) if s != self.slot):
            return
        needed = t_us - period_us
        since = 0.0
        while True:
            laggard = next((s for s in range(world.slots) if s != self.slot and world.done_us(s) < needed), None)
            if laggard is None:
                return
            seq = world.seq(laggard)
            if world.done_us(laggard) >= needed or world.sleep_on(laggard, seq):
                continue
            pid = world.pid(laggard)
            if pid and not _alive(pid):
                log.warning("world clock: vehicle %s is gone: time goes on without it", self.names[laggard])
                world.finish(laggard, LEFT)
                continue
            since = since or time.monotonic()
            if since > 0 and time.monotonic() - since > SLOW_WAIT_S:
                log.warning("world clock: time waits at t=%.3f s for vehicle %s", t_us / 1e6, self.names[laggard])
                since = -1.0

    def done(self, t_us: int) -> None:
        """This vehicle has finished step ``t_us``: wake whoever waits for it."""
        self.world.finish(self.slot, t_us)

    def close(self) -> None:
        """Leave the world (the others go on without this vehicle) and let go of the file."""
        self.world.finish(self.slot, LEFT)
        self.world.close()


def world_clock(spec: ModuleSpec, session: zenoh.Session) -> WorldClock | BusWorldClock | None:
    """The coordinator's side of its swarm's world clock (in a file, or over the bus ``session`` reaches when the
    swarm spans machines), or None for a vehicle on its own clock."""
    if not spec.world:
        return None
    if spec.world == BUS_WORLD:
        from stack.runtime.bus_world_clock import BusWorldClock

        return BusWorldClock(session, spec.world_slot, spec.world_vehicles)
    return WorldClock(Path(spec.world), spec.world_slot, spec.world_vehicles)


def _alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:
        return True
    return True
