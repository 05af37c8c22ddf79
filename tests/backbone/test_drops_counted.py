"""Every malformed message a module drops is counted where `stack status` shows it: real processes over Zenoh,
in real time (keep-last inputs) and in lockstep (the fast path's outside subscribers)."""

import contextlib

import pytest
import zenoh

from stack.bus import keys
from stack.bus.topics import FLAG_LOCKSTEP_TIME, HEADER
from stack.cli.common import find_stack
from stack.msg.registry import fingerprint, message_type
from tests.support.harness import RunningStack, chain_profile, eventually, wait_no_processes

N = 50
# Who reads what in the test chain: sensor_gyro triggers the doubler; both doubler and summer read the latest
# vehicle_rates_setpoint. A burst of garbage must be counted in full, whatever a keep-last input keeps.
READERS = {"sensor_gyro": ("doubler",), "vehicle_rates_setpoint": ("doubler", "summer")}
COUNTERS = ("decode_errors", "schema_errors", "foreign")


def send_garbage(pubs: dict[str, zenoh.Publisher]) -> None:
    """N samples of each malformed kind on each topic, once every publisher reaches a subscriber."""
    for pub in pubs.values():
        eventually(lambda pub=pub: pub.matching_status.matching, what=f"a subscriber of {pub.key_expr}")
    for topic, pub in pubs.items():
        fp = fingerprint(message_type(topic))
        for i in range(N):
            pub.put(b"\xc1")  # no stack header: schema
            pub.put(b"\x90", attachment=b"short")  # malformed header: schema
            pub.put(b"\x90", attachment=HEADER.pack(fp ^ 1, 7, i, i, 0, 0, 0))  # another schema
            pub.put(b"\xc1\xc1", attachment=HEADER.pack(fp, 7, i, i, 0, 0, 0))  # does not decode
            pub.put(b"\x90", attachment=HEADER.pack(fp, 7, i, i, 5, FLAG_LOCKSTEP_TIME, 99))  # another run


def counts(stack: RunningStack) -> dict[str, tuple[int, ...]]:
    return {m["module"]: tuple(m.get(k, 0) for k in COUNTERS) for m in stack.status()["modules"]}


@pytest.mark.parametrize("lockstep", [False, True], ids=["realtime", "lockstep"])
def test_every_malformed_message_is_counted(tmp_path, monkeypatch, lockstep):
    home = tmp_path / "home"
    monkeypatch.setenv("STACK_HOME", str(home))
    stack = RunningStack(home, chain_profile(tmp_path / "chain.toml", lockstep=lockstep))
    try:
        stack.wait_up()
        before = counts(stack)
        # Outside a lockstep run a lockstep-stamped message is just a message (no run to be foreign to).
        per_message = (1, 3, 1 if lockstep else 0)
        expected = dict(before)
        for readers in READERS.values():
            for module in readers:
                expected[module] = tuple(c + N * k for c, k in zip(expected[module], per_message, strict=True))
        vehicle, bus = find_stack(None, None)
        with zenoh.open(bus.zenoh_config("garbage")) as session:  # open until every sample is counted
            send_garbage({t: session.declare_publisher(keys.topic_key(vehicle, t, 0)) for t in READERS})
            with contextlib.suppress(AssertionError):  # the assertion below says what differs
                eventually(lambda: counts(stack) == expected, what="every sample counted")
            assert counts(stack) == expected
        rows = [line.split() for line in stack.cli("status").stdout.splitlines()]
        errors = {row[0]: int(row[10]) for row in rows if row and row[0] in expected}  # the ERR column
        assert errors["summer"] >= sum(expected["summer"])
    finally:
        assert stack.stop() == 0
    assert not wait_no_processes(home)
