"""Lockstep flights are deterministic: the same seed gives the same flight, bit for bit, on either transport,
on both at once, and however the modules share processes.

``stack fly attitude_step --seed 3`` runs, on the shared-memory fast path with every module its own process,
with the lockstep over Zenoh, with the modules in two processes (sitl_quad_grouped), and with the position
chain taking part over Zenoh beside the shared memory (sitl_quad_mixed), and with the flight control on
another host than the simulator (sitl_quad_hosts, hosts made of network namespaces), are compared through
their recordings (read with the stack's RecordingReader):
every message any module published up to the scenario's last tick, with its bus header and every
field, must be identical, and none may be missing. A different seed draws different sensor noise, so
the estimates, and through the control loops the trajectory, differ (flown in one process: the same flights).
"""

from __future__ import annotations

import math
from collections.abc import Callable

import msgspec
import pytest

from stack.mathlib import quaternion as quat
from tests.flight.flights import Flight, InProcessFlight
from tests.hosts.split import fly_across_hosts
from tests.support.hosts import network

__all__ = ["network"]  # the fixture of tests/support/hosts.py

pytestmark = pytest.mark.flight
Fly = Callable[..., Flight]

STEP_US = 4000  # the SIH quad's IMU period, the lockstep step
_encode = msgspec.msgpack.Encoder().encode


def ground_truth(flight: Flight, until_us: int) -> list[tuple[int, int, int, int, bytes]]:
    """(publication time, publisher, topic index, flags, encoded message) of each ground-truth sample."""
    return [
        (m.pub_time_us, m.publisher_id, m.index, m.flags, _encode(m.msg))
        for m in flight.messages("sim_groundtruth")
        if m.pub_time_us <= until_us
    ]


def every_message(flight: Flight, until_us: int) -> list[tuple[str, int, int, int, int, int, bytes]]:
    """(topic, instance, publisher, topic index, publication time, flags, encoded message) of each message."""
    messages = [
        (m.topic, m.instance, m.publisher_id, m.index, m.pub_time_us, m.flags, _encode(m.msg))
        for m in flight.messages()
        if m.pub_time_us <= until_us
    ]
    return sorted(messages)


@pytest.mark.parametrize(
    "other",
    [{"transport": "zenoh"}, {"profile": "sitl_quad_grouped"}, {"profile": "sitl_quad_mixed"}],
    ids=["zenoh", "grouped", "mixed"],
)
def test_same_seed_gives_the_same_flight_whatever_carries_it(fly: Fly, other: dict[str, str]) -> None:
    a, b = fly(3, 0), fly(3, 0, **other)
    end = a.scenario_end_us()
    assert b.scenario_end_us() == end
    truth_a, truth_b = ground_truth(a, end), ground_truth(b, end)
    # One sample per lockstep step from the first, none lost: thousands of them.
    assert len(truth_a) == end // STEP_US > 2500
    assert [t[0] for t in truth_a] == [STEP_US * (i + 1) for i in range(len(truth_a))]
    assert len(truth_b) == len(truth_a)
    mismatch = next((i for i, (x, y) in enumerate(zip(truth_a, truth_b, strict=True)) if x != y), None)
    assert mismatch is None, f"ground truth differs from t = {truth_a[mismatch][0] / 1e6:.3f} s on"
    all_a, all_b = every_message(a, end), every_message(b, end)
    assert len(all_a) > 10 * len(truth_a)
    assert all_a == all_b
    assert a.report["metrics"] == b.report["metrics"]
    assert a.report["sim_time_s"] == b.report["sim_time_s"]


@pytest.mark.xdist_group("heavy_wall_clock")  # two hosts' stacks at full speed: not beside the Pixhawk's flights
def test_same_seed_gives_the_same_flight_split_across_hosts(fly: Fly, network, tmp_path) -> None:
    a, b = fly(3, 0), fly_across_hosts(network(["sim", "control"]), "attitude_step", 3, tmp_path)
    end = a.scenario_end_us()
    assert b.scenario_end_us() == end
    assert ground_truth(b, end) == ground_truth(a, end)
    assert every_message(b, end) == every_message(a, end)
    assert a.report["metrics"] == b.report["metrics"]


def test_a_different_seed_gives_a_different_trajectory(fly_here: Callable[..., InProcessFlight]) -> None:
    three, one = fly_here("attitude_step", 3), fly_here("attitude_step", 1)
    # The sensor noise differs from the first sample on, so do the estimates.
    est3, est1 = (f.messages("vehicle_attitude") for f in (three, one))
    assert est3[0].pub_time_us == est1[0].pub_time_us
    assert est3[0].msg.q != est1[0].msg.q
    truth3 = {m.pub_time_us: m.msg for m in three.messages("sim_groundtruth")}
    truth1 = {m.pub_time_us: m.msg for m in one.messages("sim_groundtruth")}
    common = sorted(truth3.keys() & truth1.keys())
    assert len(common) > 2500
    # On the ground the truth is the same (level, at rest); once flying the noise shows.
    differ = [t for t in common if truth3[t].q != truth1[t].q or truth3[t].position != truth1[t].position]
    assert len(differ) > len(common) // 2
    worst = max(math.degrees(quat.angle_between(truth3[t].q, truth1[t].q)) for t in common)
    assert worst > 0.05
