"""What a fast-path subscription lets a run see: the lockstep visibility rules on shared-memory rings."""

from collections import deque
from dataclasses import dataclass, field

import msgspec
import pytest

from stack.bus.topics import Received
from stack.fastpath.attach import Attachment
from stack.fastpath.host import FastPathHost
from stack.fastpath.inputs import FastInput, Source
from stack.msg.setpoints import VehicleRatesSetpoint

encode = msgspec.msgpack.Encoder().encode
TOPIC = "vehicle_rates_setpoint/0"


@dataclass
class OutsideSub:
    """Stands in for the Zenoh subscription that brings messages from outside the run."""

    suffix: str = TOPIC
    msg_type: type = VehicleRatesSetpoint
    arrived: deque[Received] = field(default_factory=deque)
    received: int = 0
    decode_errors: int = 0
    schema_errors: int = 0
    foreign: int = 0


@pytest.fixture
def run():
    host = FastPathHost(["a", "b", "reader"], run_id=5)
    a, b = Attachment(host.region, "a", 101), Attachment(host.region, "b", 102)
    writers = {
        "a": a.publication(TOPIC, 1, 40),
        "b": b.publication(TOPIC, 1, 40),
    }
    sources = [Source(a.slot, 0, 101), Source(b.slot, 0, 102)]
    yield host, writers, sources
    host.close()


def publish(writer, roll: float, t: int, seq: int) -> None:
    writer.write(encode(VehicleRatesSetpoint(timestamp=t, roll=roll)), writer.count + 1, t, seq)


def make_input(host, sources, queue: bool, now: int = 0) -> tuple[FastInput, OutsideSub]:
    sub = OutsideSub()
    inp = FastInput(host.region, sub, queue)
    inp.resolve(sources, frozenset({101, 102}), now)
    return inp, sub


def test_a_run_sees_what_was_published_before_its_time_only(run):
    host, w, sources = run
    inp, _ = make_input(host, sources, queue=False)
    publish(w["a"], 1.0, 4000, 1)
    publish(w["a"], 2.0, 8000, 2)
    inp.refresh(8000)
    assert inp.update().roll == 1.0  # the record of time 8000 waits for the next run
    inp.refresh(12000)
    assert inp.update().roll == 2.0
    assert inp.update() is None


def test_the_trigger_publisher_s_earlier_records_of_the_same_time_are_visible(run):
    host, w, sources = run
    inp, _ = make_input(host, sources, queue=False)
    publish(w["a"], 1.0, 4000, 5)
    publish(w["b"], 9.0, 4000, 1)
    inp.refresh(4000, trigger_publisher=101, trigger_seq=6)
    assert inp.latest.roll == 1.0  # a's record (seq 5 < 6) yes, b's record of the same time no


def test_the_newest_of_several_publishers_wins(run):
    host, w, sources = run
    inp, _ = make_input(host, sources, queue=False)
    publish(w["a"], 1.0, 4000, 1)
    publish(w["b"], 2.0, 8000, 1)
    inp.refresh(12000)
    assert inp.latest.roll == 2.0


def test_a_queue_takes_every_visible_record_in_order(run):
    host, w, sources = run
    inp, _ = make_input(host, sources, queue=True)
    publish(w["a"], 1.0, 4000, 1)
    publish(w["b"], 2.0, 4000, 1)
    publish(w["a"], 3.0, 8000, 2)
    publish(w["a"], 4.0, 12000, 3)
    inp.refresh(12000)
    assert [m.roll for m in inp.take()] == [1.0, 2.0, 3.0]
    inp.refresh(16000)
    assert [m.roll for m in inp.take()] == [4.0]


def test_outside_messages_are_seen_at_once_and_copies_of_ring_records_skipped(run):
    host, w, sources = run
    inp, sub = make_input(host, sources, queue=True)
    publish(w["a"], 1.0, 4000, 1)
    sub.arrived.extend(
        [
            Received(-1, 555, 1, VehicleRatesSetpoint(roll=7.0), 1),
            Received(4000, 101, 1, VehicleRatesSetpoint(roll=1.0), 1),
        ]
    )
    inp.refresh(8000)
    assert sorted(m.roll for m in inp.take()) == [1.0, 7.0]


def test_a_queue_joining_late_starts_with_the_records_of_its_first_step(run):
    host, w, sources = run
    publish(w["a"], 1.0, 4000, 1)
    publish(w["a"], 2.0, 8000, 2)
    inp, _ = make_input(host, sources, queue=True, now=8000)
    publish(w["a"], 3.0, 12000, 3)
    inp.refresh(16000)
    assert [m.roll for m in inp.take()] == [2.0, 3.0]
