"""InProcessStack: a profile's real modules in one process give what the multi-process stack gives.

The test chain of tests/support/modules.py (a 250 Hz clock, a doubler and a summer triggered in
turn, a 50 Hz pacer and a probe) makes every output depend on which inputs each run saw, so a run
that saw a message one step early or late changes the trace. The same chain under a real
``stack up`` (a process per module, lockstep over the shared-memory fast path or over Zenoh) must
give the same trace and probe, value for value.
"""

from __future__ import annotations

import json
from pathlib import Path
from types import SimpleNamespace
from typing import cast

import pytest

from stack.bus.node import stable_publisher_id
from stack.bus.topics import Received
from stack.msg.sensors import SensorAccel, SensorGyro
from stack.runtime.inprocess import InProcessRuntime, InProcessStack
from stack.runtime.membus import MemoryBus
from stack.supervisor.profile import load_profile
from tests.runtime.same_time_modules import SameTimeProbe
from tests.support.harness import RunningStack, traced_chain, wait_no_processes

STEPS = 3000


def chain(tmp_path: Path, name: str, extra: str = "", transport: str = "shm") -> tuple[Path, Path, Path]:
    """The chain's profile (stopping after STEPS steps), with where its trace and probe go."""
    return traced_chain(tmp_path, name, STEPS, extra=extra, transport=transport)


def in_process(tmp_path: Path, name: str, wire: bool = True) -> tuple[list, list]:
    profile, trace, probe = chain(tmp_path, name)
    stack = InProcessStack(load_profile(profile), wire=wire)
    stack.run()
    assert stack.steps == STEPS
    return json.loads(trace.read_text()), json.loads(probe.read_text())


def test_the_chain_in_process_sees_what_lockstep_allows(tmp_path: Path) -> None:
    trace, probe = in_process(tmp_path, "a")
    # As tests/backbone/test_lockstep.py asserts of the multi-process chain: one torque per 4 ms step,
    # each from the previous step; dt from timestamp_sample, the first run's clamped to 20 ms.
    assert [row[0] for row in trace] == [8000 + 4000 * i for i in range(STEPS - 1)]
    assert trace[0][3] == 0.02 and {row[3] for row in trace[1:]} == {0.004}
    for now, sample, sp_time, av_time, dt in probe[1:]:
        assert now == sample
        assert av_time == now - 4000
        assert sp_time == max(4000, ((now - 1) // 20000) * 20000)
        assert dt == 0.004
    # Sharing the published objects instead of decoding a copy per subscriber changes nothing here.
    assert in_process(tmp_path, "b", wire=False) == (trace, probe)


@pytest.mark.parametrize("transport", ["shm", "zenoh"])
def test_the_chain_in_process_is_the_chain_of_stack_up(tmp_path: Path, transport: str) -> None:
    expected = in_process(tmp_path, "inproc")
    profile, trace, probe = chain(tmp_path, "up", transport=transport)
    home = tmp_path / "home"
    stack = RunningStack(home, profile)
    assert stack.wait(timeout=300) == 0, stack.output
    assert not wait_no_processes(home)
    got = json.loads(trace.read_text()), json.loads(probe.read_text())
    assert got[0] == expected[0]
    # The probe's last run may or may not happen before the stack stops.
    assert got[1][: STEPS - 1] == expected[1][: STEPS - 1]


def test_a_module_that_exits_leaves_and_only_a_critical_one_ends_the_run(tmp_path: Path) -> None:
    profile, trace, _ = chain(
        tmp_path, "exit", extra='[[module]]\nmodule = "tests.support.modules:Crasher"\nargs = { ticks = 3 }\n'
    )
    stack = InProcessStack(load_profile(profile))
    stack.run()
    assert "crasher" not in stack.runtimes
    assert stack.steps == STEPS  # the crasher (not critical) left after 3 ticks; the tick source ended the run
    assert len(json.loads(trace.read_text())) == STEPS - 1


def publishing_module(name: str) -> InProcessRuntime:
    """What the memory bus uses of a module's runtime: its publisher id and sequence."""
    return cast(InProcessRuntime, SimpleNamespace(name=name, publisher_id=stable_publisher_id("v1", name), seq=0))


@pytest.mark.parametrize("wire", [True, False])
def test_messages_carry_the_bus_header_and_subscribers_get_a_copy_on_the_wire(wire: bool) -> None:
    bus = MemoryBus(wire=wire, record=True)
    sim = publishing_module("sim")
    first: list[Received] = []
    second: list[Received] = []
    bus.subscribe(sim, "sensor_gyro", 0, first.append), bus.subscribe(sim, "sensor_gyro", 0, second.append)
    sent = SensorGyro(x=1.5, temperature=20.0)
    bus.publisher(sim, "sensor_accel", 0).publish(SensorAccel(), 4000)  # nobody subscribes
    bus.publisher(sim, "sensor_gyro", 0).publish(sent, 4000)
    assert len(first) == len(second) == 1
    a, b = first[0], second[0]
    assert (a.time_us, a.publisher, a.seq, a.index) == (4000, sim.publisher_id, 2, 1)  # one sequence, all topics
    assert a.msg == sent == b.msg and sent.timestamp == 4000  # stamped as TopicPublisher.publish does
    # On the wire each subscriber decodes its own copy; shared, all get the publisher's object.
    assert (a.msg is sent, b.msg is sent) == (not wire, not wire)
    assert [(m.topic, m.index, m.pub_time_us, m.flags) for m in bus.published] == [
        ("sensor_accel", 1, 4000, 1),
        ("sensor_gyro", 1, 4000, 1),
    ]


def test_a_message_that_does_not_decode_is_counted_and_dropped() -> None:
    bus = MemoryBus(wire=True, record=False)
    sim = publishing_module("sim")
    delivered: list[Received] = []
    sub = bus.subscribe(sim, "sensor_gyro", 0, delivered.append)
    bus.publisher(sim, "sensor_gyro", 0).publish(SensorGyro(x="fast"), 4000)  # type: ignore[arg-type]
    assert delivered == []
    assert sub.decode_errors == 1


def test_a_triggered_run_sees_its_trigger_publishers_earlier_messages_of_the_same_time(tmp_path: Path) -> None:
    profile = tmp_path / "same_time.toml"
    profile.write_text(
        """
[[module]]
module = "tests.runtime.same_time_modules:AccelThenGyro"
[[module]]
module = "tests.support.modules:Doubler"
[[module]]
module = "tests.runtime.same_time_modules:SameTimeProbe"
"""
    )
    stack = InProcessStack(load_profile(profile))
    stack.run(max_steps=50)
    seen = cast(SameTimeProbe, stack.runtimes["same_time_probe"].module).seen
    # The accelerometer sample its trigger's publisher sent just before the gyro; the doubler's output of
    # the same time (another publisher) only on the next run.
    assert seen == [(t, t, t - 4000 if t > 4000 else -1) for t in range(4000, 50 * 4000 + 1, 4000)]
