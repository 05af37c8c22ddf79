"""``stack pixhawk-sim``: the simulated Pixhawk as a process, paced to the wall clock, talking MAVLink only.

One loop, one thread: wait (``select``) for input or the next 4 ms step; move bytes through the wire; hand the
received messages to the protocol; run the steps due (all of them back to back when up to
:data:`MAX_CATCH_UP_STEPS` late; beyond that the missed time is skipped and counted); send the streams due.

Step timing: step k is due at start + k·period. Its lateness (wall time at the start of the step minus its due
time) and its duration are recorded; the report gives their percentiles, the steps skipped and the CPU used. The
autopilot's boot time is the wall clock since one period before the first step, so a step's samples carry the
wall time they were computed at. It never opens a Zenoh session: MAVLink is its only interface.
"""

from __future__ import annotations

import gc
import json
import resource
import select
import signal
import sys
import time
from dataclasses import dataclass, field
from pathlib import Path

from stack.airframe.model import VehicleModel
from stack.mavlink.endpoint import DEFAULT_BAUD
from stack.mavlink.link import MavlinkLink
from stack.pixhawk_sim.control import ControlChannel
from stack.pixhawk_sim.faults import FaultInjector, FaultSettings
from stack.pixhawk_sim.protocol import Px4Protocol
from stack.pixhawk_sim.telemetry import Message
from stack.pixhawk_sim.vehicle import SimulatedPixhawk
from stack.pixhawk_sim.wire import PhysicalLink, PtyUart, UdpLink, Wire
from stack.sim.simulator import MAX_CATCH_UP_STEPS


@dataclass
class RunOptions:
    vehicle: VehicleModel
    params: dict[str, object]
    udp: str | None = None
    pty_link: Path | None = None
    baud: int = DEFAULT_BAUD
    system_id: int = 1
    component_id: int = 1
    seed: int = 0
    faults: FaultSettings = field(default_factory=FaultSettings)
    cut_at_s: float | None = None
    cut_for_s: float = 0.0
    control_port: int | None = None
    duration_s: float | None = None
    stats_period_s: float = 0.0
    report: Path | None = None


class Histogram:
    """Counts of µs values in 10 µs bins: percentiles of a long run in constant memory."""

    BIN_US = 10

    def __init__(self) -> None:
        self.counts: dict[int, int] = {}
        self.n = 0
        self.total = 0
        self.max = 0

    def add(self, value_us: int) -> None:
        b = value_us // self.BIN_US
        self.counts[b] = self.counts.get(b, 0) + 1
        self.n += 1
        self.total += value_us
        self.max = max(self.max, value_us)

    def percentile(self, q: float) -> int:
        """The upper edge of the bin holding the q-quantile (0 < q ≤ 1) [µs]."""
        rank = q * self.n
        seen = 0
        for b in sorted(self.counts):
            seen += self.counts[b]
            if seen >= rank:
                return min((b + 1) * self.BIN_US, self.max)
        return self.max

    def summary(self) -> dict[str, float]:
        if not self.n:
            return {}
        return {
            "p50": self.percentile(0.5),
            "p90": self.percentile(0.9),
            "p99": self.percentile(0.99),
            "max": self.max,
            "mean": round(self.total / self.n, 1),
        }


class StepStats:
    """Lateness and duration of the steps [µs], the steps skipped, CPU time."""

    def __init__(self) -> None:
        self.lateness_us = Histogram()
        self.duration_us = Histogram()
        self.skipped = 0
        self.catch_up_steps = 0
        self._cpu0 = _cpu_s()
        self._wall0 = time.monotonic()

    def summary(self) -> dict[str, object]:
        wall = time.monotonic() - self._wall0
        return {
            "steps": self.duration_us.n,
            "skipped_steps": self.skipped,
            "catch_up_steps": self.catch_up_steps,
            "lateness_us": self.lateness_us.summary(),
            "duration_us": self.duration_us.summary(),
            "cpu_percent": round(100.0 * (_cpu_s() - self._cpu0) / wall, 1) if wall > 0 else 0.0,
            "wall_s": round(wall, 3),
        }


def _cpu_s() -> float:
    usage = resource.getrusage(resource.RUSAGE_SELF)
    return usage.ru_utime + usage.ru_stime


class PixhawkSim:
    """The process: vehicle, protocol, link layer, wire, control channel and the paced loop."""

    def __init__(self, options: RunOptions) -> None:
        self.options = options
        self.vehicle = SimulatedPixhawk(options.vehicle, options.params, seed=options.seed)
        self.period_ns = self.vehicle.period_us * 1000
        self._start(time.monotonic_ns())
        self.faults = FaultInjector(options.faults, seed=options.seed)
        physical: PhysicalLink
        if options.pty_link is not None:
            physical = PtyUart(options.baud, options.pty_link)
        elif options.udp is not None:
            physical = UdpLink(options.udp)
        else:
            raise ValueError("the simulated Pixhawk needs a link: a UDP endpoint or a pty")
        self.wire = Wire(physical, self.faults)
        self.protocol = Px4Protocol(self.vehicle, self._send, options.system_id, options.component_id)
        self.link = MavlinkLink(
            self.wire.link_endpoint,
            system_id=options.system_id,
            component_id=options.component_id,
            heartbeat=self.protocol.heartbeat,
            clock_us=self.boot_time_us,
        )
        self.control = (
            ControlChannel(options.control_port, self.faults, self.status) if options.control_port is not None else None
        )
        self.stats = StepStats()
        self._stop = False

    def _start(self, start_ns: int) -> None:
        """The first step is due at ``start_ns``; the autopilot booted one period before."""
        self.start_ns = start_ns
        self.boot_ns = start_ns - self.period_ns

    def _send(self, msg: Message) -> None:
        self.link.send(msg)

    def boot_time_us(self) -> int:
        """The autopilot's boot time: the wall clock since one period before the first step."""
        return (time.monotonic_ns() - self.boot_ns) // 1000

    def stop(self, *_: object) -> None:
        self._stop = True

    def status(self) -> dict[str, object]:
        c = self.vehicle.commander
        return {
            "time_us": self.vehicle.time_us,
            "mode": c.mode.name,
            "user_mode": c.user_mode.name,
            "armed": c.armed,
            "failsafe": c.failsafe,
            "link_connected": self.link.connected,
            "link": {k: getattr(self.link.counters, k) for k in self.link.counters.__struct_fields__},
            "faults": self.faults.report(),
            "physical": self.wire.physical.describe(),
            "commands": self.protocol.commands,
            "setpoints": self.protocol.setpoints,
        }

    def describe_start(self) -> str:
        physical = self.wire.physical.describe()
        if "endpoint" in physical:
            where = str(physical["endpoint"])
        else:
            where = f"pty {physical['pty']}" + (f" (link {physical['link']})" if physical["link"] else "")
        control = f", control udp 127.0.0.1:{self.control.port}" if self.control is not None else ""
        return (
            f"[pixhawk-sim] {self.vehicle.sim.model.name}, MAVLink system {self.options.system_id} component "
            f"{self.options.component_id} on {where}{control}"
        )

    def run(self) -> dict[str, object]:
        """Run until stopped (SIGINT/SIGTERM, ``stop()``) or the duration is over; returns the report."""
        print(self.describe_start(), flush=True)
        gc.collect()
        gc.freeze()
        self._start(time.monotonic_ns())
        self.stats = StepStats()
        if self.options.cut_at_s is not None:
            self.faults.cut(self.start_ns * 1e-9 + self.options.cut_at_s, self.options.cut_for_s)
        fds = self.wire.fds() + ([self.control.fileno()] if self.control is not None else [])
        period_ns = self.period_ns
        next_step_ns = self.start_ns
        end_ns = self.start_ns + int(self.options.duration_s * 1e9) if self.options.duration_s is not None else None
        stats_period_ns = int(self.options.stats_period_s * 1e9)
        next_stats_ns = self.start_ns + stats_period_ns if stats_period_ns > 0 else None
        protocol, link, wire = self.protocol, self.link, self.wire
        try:
            while not self._stop:
                now_ns = time.monotonic_ns()
                if end_ns is not None and now_ns >= end_ns:
                    break
                wake_ns = next_step_ns
                event_s = wire.next_event_s(now_ns * 1e-9)
                if event_s is not None:
                    wake_ns = min(wake_ns, int(event_s * 1e9))
                if wake_ns > now_ns:
                    select.select(fds, [], [], (wake_ns - now_ns) * 1e-9)
                now_s = time.monotonic_ns() * 1e-9
                wire.service(now_s)
                for msg in link.poll(0.0):
                    protocol.handle(msg)
                if self.control is not None:
                    self.control.service(now_s)
                now_ns = time.monotonic_ns()
                if now_ns >= next_step_ns:
                    next_step_ns = self._steps(now_ns, next_step_ns, period_ns)
                    wire.service(time.monotonic_ns() * 1e-9)
                if next_stats_ns is not None and now_ns >= next_stats_ns:
                    next_stats_ns += stats_period_ns
                    print(json.dumps({"stats": self.stats.summary(), **self.status()}), file=sys.stderr, flush=True)
        finally:
            report = {"stats": self.stats.summary(), **self.status()}
            self.close()
        if self.options.report is not None:
            self.options.report.write_text(json.dumps(report, indent=2))
        return report

    def _steps(self, now_ns: int, due_ns: int, period_ns: int) -> int:
        """Run the steps due; returns when the next one is due."""
        stats = self.stats
        late = (now_ns - due_ns) // period_ns
        if late >= MAX_CATCH_UP_STEPS:
            self.vehicle.skip(late * period_ns // 1000)
            stats.skipped += late
            due_ns += late * period_ns
        elif late > 0:
            stats.catch_up_steps += late
        vehicle, protocol = self.vehicle, self.protocol
        while due_ns <= now_ns:
            start = time.monotonic_ns()
            stats.lateness_us.add((start - due_ns) // 1000)
            vehicle.step()
            protocol.publish()
            stats.duration_us.add((time.monotonic_ns() - start) // 1000)
            due_ns += period_ns
        return due_ns

    def close(self) -> None:
        self.link.close()
        self.wire.close()
        if self.control is not None:
            self.control.close()


def run(options: RunOptions) -> dict[str, object]:
    sim = PixhawkSim(options)
    signal.signal(signal.SIGTERM, sim.stop)
    signal.signal(signal.SIGINT, sim.stop)
    return sim.run()
