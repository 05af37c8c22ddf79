import socket

import pytest

from stack.bus import ports
from stack.bus.ports import ephemeral_range, free_port


def test_ports_are_free_distinct_and_outside_the_ephemeral_range():
    low, high = ephemeral_range()
    ports = [free_port() for _ in range(50)]
    assert len(set(ports)) == len(ports)
    assert all(not low <= p <= high for p in ports)
    with socket.socket(socket.AF_INET, socket.SOCK_STREAM) as s:
        s.bind(("127.0.0.1", ports[0]))  # nobody holds it


def test_a_port_someone_listens_on_is_skipped(monkeypatch):
    with socket.socket(socket.AF_INET, socket.SOCK_STREAM) as held:
        for candidate in range(20000, 30000):
            try:
                held.bind(("127.0.0.1", candidate))
                break
            except OSError:
                continue
        held.listen()
        picks = iter([candidate, candidate, candidate + 1 if candidate < 29999 else candidate - 1])
        monkeypatch.setattr(ports._random, "randrange", lambda *_: next(picks))
        assert free_port() != candidate


def test_a_held_port_cannot_be_bound_until_it_is_released():
    held = ports.hold_port()
    port = held.getsockname()[1]
    with held, socket.socket(socket.AF_INET, socket.SOCK_STREAM) as other, pytest.raises(OSError):
        other.bind(("127.0.0.1", port))  # what free_port and a listener elsewhere try
    with socket.socket(socket.AF_INET, socket.SOCK_STREAM) as s:
        s.bind(("127.0.0.1", port))


def test_a_port_held_again_for_a_restart_refuses_strangers_and_admits_the_restarted_listener():
    port = free_port()
    held = ports.hold_again(port)
    assert held is not None
    with held:
        with socket.socket(socket.AF_INET, socket.SOCK_STREAM) as stranger, pytest.raises(OSError):
            stranger.bind(("127.0.0.1", port))
        with socket.socket(socket.AF_INET, socket.SOCK_STREAM) as restarted:  # as Zenoh's listener binds
            restarted.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
            restarted.bind(("127.0.0.1", port))
            restarted.listen()
            assert ports.hold_again(port) is None  # someone listens there now
