"""STATUSTEXT chunks, signing and the PX4-style UDP transport."""

import select
import socket

import pytest
from pymavlink.dialects.v20 import common as M

from stack.bus.ports import free_port
from stack.mavlink import signing
from stack.mavlink.framing import FrameParser
from stack.mavlink.statustext import StatustextSender
from stack.mavlink.transport import UdpPeerTransport
from stack.pixhawk.convert import StatustextAssembler

KEY = bytes(range(32))


@pytest.mark.parametrize("length", [0, 12, 49, 50, 51, 100, 149, 600])
def test_statustext_chunks_come_back_whole(length):
    text = ("Arming denied: " + "x" * 600)[:length]
    msgs = StatustextSender().messages(2, text)
    assembler = StatustextAssembler()
    whole = [assembler.add(m.text, m.id, m.chunk_seq) for m in msgs]
    assert whole[-1] == text[:400] and all(w is None for w in whole[:-1])
    assert all(m.severity == 2 for m in msgs) and (len(msgs) == 1) == (length < 50)


def test_the_signing_key_file(tmp_path):
    (tmp_path / "hex").write_text(KEY.hex() + "\n")
    (tmp_path / "raw").write_bytes(KEY)
    (tmp_path / "bad").write_text("not a key")
    assert signing.load_key(tmp_path / "hex") == KEY == signing.load_key(tmp_path / "raw")
    with pytest.raises(ValueError, match="64 hexadecimal digits"):
        signing.load_key(tmp_path / "bad")


class _Sink:
    def __init__(self) -> None:
        self.frames: list[bytes] = []

    def write(self, data: bytes) -> None:
        self.frames.append(bytes(data))


def _sender(key: bytes | None, system: int = 245) -> tuple[M.MAVLink, _Sink]:
    sink = _Sink()
    mav = M.MAVLink(sink, system, 190)
    if key is not None:
        signing.enable(mav, key)
    return mav, sink


def test_signed_messages_are_taken_unsigned_and_wrongly_signed_ones_refused_but_heartbeats():
    vehicle = M.MAVLink(None, 1, 1)
    signing.enable(vehicle, KEY)
    parser = FrameParser(vehicle)
    received = []
    for key, system in ((KEY, 245), (None, 246), (bytes(32), 247)):
        mav, sink = _sender(key, system)
        mav.command_long_send(1, 1, 400, 0, 1, 0, 0, 0, 0, 0, 0)
        mav.heartbeat_send(6, 8, 0, 0, 0)
        for frame in sink.frames:
            received += [(m.get_type(), m.get_srcSystem()) for m in parser.feed(frame)]
    assert ("COMMAND_LONG", 245) in received
    assert ("COMMAND_LONG", 246) not in received and ("COMMAND_LONG", 247) not in received
    assert {("HEARTBEAT", s) for s in (245, 246, 247)} <= set(received)
    assert signing.refused(vehicle) == 2
    sink = _Sink()
    vehicle.file = sink
    vehicle.heartbeat_send(2, 12, 0, 0, 0)
    assert sink.frames[0][2] & M.MAVLINK_IFLAG_SIGNED


def test_udp_sends_to_the_remote_until_a_peer_writes_then_to_the_peer():
    port = free_port(kind=socket.SOCK_DGRAM)
    with (
        socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as remote,
        socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as peer,
    ):
        remote.bind(("127.0.0.1", 0))
        peer.bind(("127.0.0.1", 0))
        remote.settimeout(2.0)
        peer.settimeout(2.0)
        link = UdpPeerTransport("127.0.0.1", port, remote.getsockname())
        try:
            assert link.write(b"hello")
            assert remote.recvfrom(100)[0] == b"hello"
            peer.sendto(b"hi", ("127.0.0.1", port))
            assert select.select([link.fileno()], [], [], 2.0)[0] and link.read() == b"hi"
            assert link.write(b"back")
            assert peer.recvfrom(100)[0] == b"back"
        finally:
            link.close()


def test_udp_never_shares_its_port():
    port = free_port(kind=socket.SOCK_DGRAM)
    first = UdpPeerTransport("127.0.0.1", port)
    assert not first.write(b"x")  # no remote, no peer yet: nowhere to send
    try:
        with pytest.raises(OSError):
            UdpPeerTransport("127.0.0.1", port)
    finally:
        first.close()
