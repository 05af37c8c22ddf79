"""A router's denials, read from Zenoh's access-control log lines (stack.security.denials): the messages it dropped,
not the kinds of message it worked out it would drop on a key a session declared."""

from __future__ import annotations

from stack.security.denials import EVALUATION_WINDOW_S, Denial, DenialCounts, DenialReader

ZID = "1315260506a4c53c118552165b4a9637"
PREFIX = (
    "\x1b[2m2026-12-04T16:50:43.821109Z\x1b[0m \x1b[35mTRACE\x1b[0m rx-0 ThreadId(11) "
    "\x1b[2mzenoh::net::routing::interceptor::access_control\x1b[0m\x1b[2m:\x1b[0m "
)


def line(what: str, key: str, subject: str = "Interface(veth-g)+CertCommonName(bob)+Transport(Tls)") -> str:
    return f"{PREFIX}{ZID} on {subject}+{ZID} is unauthorized to {what} on {key}"


def cached(what: str, key: str) -> str:
    return f"{PREFIX}Using cached result: {ZID} is unauthorized to {what} on {key}"


COMMAND, ATTITUDE = "stack/v1/vehicle_command/0", "stack/v1/vehicle_attitude/0"


def test_a_message_denied_names_the_certificate_the_kind_of_message_and_the_key() -> None:
    reader = DenialReader()
    assert reader.feed(line("Put (ingress)", COMMAND), 0.0) == []  # whole once no other kind follows on the key
    assert reader.flush(EVALUATION_WINDOW_S) == [Denial("bob", "put", "ingress", COMMAND)]


def test_what_zenoh_works_out_on_a_declared_key_is_no_denial_and_what_is_then_sent_there_is() -> None:
    reader = DenialReader()
    evaluation = ["Query (ingress)", "Reply (ingress)", "Put (ingress)", "Declare/Undeclare Queryable (ingress)",
                  "Declare Liveliness Subscriber (egress)"]  # fmt: skip
    for what in evaluation:  # bob declared a publisher on the command topic
        assert reader.feed(line(what, COMMAND), 0.001) == []
    assert reader.flush(1.0) == []
    sent = [reader.feed(cached("Put (ingress)", COMMAND), 1.0 + i) for i in range(3)]
    assert sent == [[Denial("bob", "put", "ingress", COMMAND)]] * 3


def test_without_a_certificate_the_interface_names_who_and_other_lines_tell_nothing() -> None:
    reader = DenialReader()
    reader.feed(line("Declare Subscriber (egress)", "stack/**", "Interface(lo)+Transport(Tcp)"), 0.0)
    assert reader.flush() == [Denial("interface lo", "declare_subscriber", "egress", "stack/**")]
    assert reader.feed(line("Put (ingress)", ATTITUDE).replace("unauthorized", "authorized"), 0.0) == []
    assert reader.feed("[stack] router of host sim: on tcp/127.0.0.1:1", 0.0) == []
    assert reader.flush() == []


def test_counts_by_kind_most_frequent_first_and_the_first_of_each_kind_told() -> None:
    counts = DenialCounts()
    bob = Denial("bob", "put", "ingress", COMMAND)
    alice = Denial("alice", "put", "ingress", "stack/v1/sensor_gyro/0")
    assert counts.add(alice, 1.0) and counts.add(bob, 2.0)
    assert not counts.add(bob, 3.0)
    assert counts.total == 3
    assert [(r["who"], r["count"], r["last"]) for r in counts.rows()] == [("bob", 2, 3.0), ("alice", 1, 1.0)]
