import os
import random
import select
import socket
import time
from collections.abc import Callable
from pathlib import Path

from pymavlink.dialects.v20 import common as mavlink2

from stack.mavlink.framing import FrameParser
from stack.mavlink.link import MavlinkLink, monotonic_us
from tests.support.harness import udp_port

PATIENCE_S = 30.0  # generous: the test machine may be heavily loaded


def autopilot_heartbeat() -> dict:
    return {
        "type": mavlink2.MAV_TYPE_QUADROTOR,
        "autopilot": mavlink2.MAV_AUTOPILOT_PX4,
        "base_mode": mavlink2.MAV_MODE_FLAG_CUSTOM_MODE_ENABLED,
        "custom_mode": 0,
        "system_status": mavlink2.MAV_STATE_STANDBY,
    }


def pump(
    links: list[MavlinkLink],
    until: Callable[[], bool],
    patience_s: float = PATIENCE_S,
    also: Callable[[], object] | None = None,
) -> list:
    """Poll every link (and call ``also``) until the condition holds; returns what the first link received."""
    received = []
    deadline = time.monotonic() + patience_s
    while not until():
        assert time.monotonic() < deadline, "condition not met in time"
        received += links[0].poll(0.005)
        for link in links[1:]:
            link.poll(0.005)
        if also is not None:
            also()
    return received


def udp_pair(**companion_options) -> tuple[MavlinkLink, MavlinkLink]:
    port = udp_port()
    autopilot = MavlinkLink(f"udpin:127.0.0.1:{port}", system_id=1, component_id=1, heartbeat=autopilot_heartbeat)
    companion = MavlinkLink(f"udpout:127.0.0.1:{port}", system_id=1, component_id=191, **companion_options)
    return autopilot, companion


def test_heartbeats_both_ways_connect_the_link() -> None:
    autopilot, companion = udp_pair()
    try:
        received = pump([companion, autopilot], lambda: companion.connected and autopilot.connected)
        assert companion.peer == (1, 1) and companion.peer_is_autopilot
        assert autopilot.peer == (1, 191) and not autopilot.peer_is_autopilot
        heartbeat = next(m for m in received if m.get_type() == "HEARTBEAT")
        assert heartbeat.autopilot == mavlink2.MAV_AUTOPILOT_PX4
        assert companion.counters.packets_in >= 1 and companion.counters.packets_out >= 1
        assert companion.counters.bytes_in > 0 and companion.counters.bytes_out > 0
        assert companion.counters.quality == 1.0
    finally:
        autopilot.close()
        companion.close()


def test_messages_arrive_in_order_as_mavlink2() -> None:
    autopilot, companion = udp_pair()
    try:
        pump([autopilot, companion], lambda: autopilot.connected)
        for i in range(50):
            companion.mav.command_long_send(1, 1, mavlink2.MAV_CMD_REQUEST_MESSAGE, 0, float(i), 0, 0, 0, 0, 0, 0)
        commands: list = []

        def got_all() -> bool:
            commands.extend(m for m in autopilot.poll(0.005) if m.get_type() == "COMMAND_LONG")
            companion.poll()
            return len(commands) == 50

        pump([companion], got_all)
        assert [int(c.param1) for c in commands] == list(range(50))
        assert commands[0]._msgbuf[0] == mavlink2.PROTOCOL_MARKER_V2
        assert autopilot.counters.seq_gaps == 0
    finally:
        autopilot.close()
        companion.close()


def test_timesync_maps_the_autopilot_clock_onto_ours() -> None:
    autopilot_offset_us = 7_000_000_000  # the autopilot's clock reads 7000 s more than ours

    def autopilot_clock() -> int:
        return monotonic_us() + autopilot_offset_us

    port = udp_port()
    autopilot = MavlinkLink(
        f"udpin:127.0.0.1:{port}",
        system_id=1,
        component_id=1,
        heartbeat=autopilot_heartbeat,
        clock_us=autopilot_clock,
    )
    companion = MavlinkLink(f"udpout:127.0.0.1:{port}", system_id=1, component_id=191, timesync=True)
    try:
        pump([companion, autopilot], lambda: companion.timesync.synced)
        error_us = companion.timesync.to_local_us(autopilot_clock()) - monotonic_us()
        assert abs(error_us) < 10_000
        assert companion.timesync.rtt_us > 0
    finally:
        autopilot.close()
        companion.close()


def test_link_loss_after_the_timeout_and_recovery_when_the_peer_returns() -> None:
    autopilot, companion = udp_pair()
    port = companion.endpoint.port
    try:
        pump([companion, autopilot], lambda: companion.connected)
        autopilot.close()
        lost_at = time.monotonic()
        pump([companion], lambda: not companion.connected)
        assert time.monotonic() - lost_at >= 0.5  # the timeout counts from the last heartbeat (1.5 s)
        assert companion.counters.link_losses == 1 and companion.counters.quality == 0.0
        autopilot = MavlinkLink(f"udpin:127.0.0.1:{port}", system_id=1, component_id=1, heartbeat=autopilot_heartbeat)
        pump([companion, autopilot], lambda: companion.connected)
        assert companion.peer == (1, 1) and companion.counters.link_losses == 1
    finally:
        autopilot.close()
        companion.close()


def test_send_on_a_dead_link_is_counted_not_raised(tmp_path: Path) -> None:
    link = MavlinkLink(f"serial:{tmp_path / 'ttyACM9'}:921600", system_id=1, component_id=191)
    try:
        assert link.fileno() is None and "cannot open" in (link.error or "")
        link.send(link.mav.heartbeat_encode(18, 8, 0, 0, 4))
        link.mav.command_long_send(1, 1, mavlink2.MAV_CMD_REQUEST_MESSAGE, 0, 148, 0, 0, 0, 0, 0, 0)
        assert link.poll(0.01) == []
        assert link.counters.send_drops == 2 and link.counters.packets_out == 0
    finally:
        link.close()


def test_garbage_is_counted_and_dropped() -> None:
    port = udp_port()
    link = MavlinkLink(f"udpin:127.0.0.1:{port}", system_id=1, component_id=191)
    mav = mavlink2.MAVLink(None, srcSystem=1, srcComponent=1)
    heartbeat = mav.heartbeat_encode(2, 12, 1, 0, 3)
    rng = random.Random(3)
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as peer:
        peer.connect(("127.0.0.1", port))

        def frame(seq: int) -> bytes:
            mav.seq = seq
            return heartbeat.pack(mav)

        corrupt = bytearray(frame(2))
        corrupt[12] ^= 0x04
        unknown = bytes([0xFD, 2, 0, 0, 4, 1, 1, 0x39, 0x30, 0x00, 0xAA, 0xBB, 0x12, 0x34])
        peer.send(frame(0) + bytes(rng.randrange(256) for _ in range(255)) + frame(1))
        peer.send(bytes(corrupt) + frame(3) + unknown + frame(5))
        peer.send(frame(6)[:9])  # a frame cut short: the datagram ends
        peer.send(frame(7) + frame(20))  # 12 lost by sequence number
        try:
            received = pump([link], lambda: link.counters.packets_in >= 6)
        finally:
            link.close()
    assert [m.get_seq() for m in received] == [0, 1, 3, 5, 7, 20]
    c = link.counters
    assert (c.parse_errors, c.crc_errors, c.unknown_messages) == (2, 1, 1)
    assert c.packets_in == 7  # the unknown one counts as received, not lost
    # seq 2 (corrupt), 6 (cut) and 8..19 are missing
    assert c.seq_gaps == 14
    assert 0.2 < c.quality < 0.5


class PtyAutopilot:
    """The far end of a pseudo-terminal, reached by the link through a symlink that can be unplugged."""

    def __init__(self, link_path: Path) -> None:
        self.link_path = link_path
        self.mav = mavlink2.MAVLink(None, srcSystem=1, srcComponent=1)
        self.parser = FrameParser(mavlink2.MAVLink(None))
        self.master: int | None = None
        self.next_beat = 0.0
        self.heard_heartbeat = False
        self.plug()

    def plug(self) -> None:
        self.master, slave = os.openpty()
        self.link_path.symlink_to(os.ttyname(slave))
        os.close(slave)

    def unplug(self) -> None:
        assert self.master is not None
        os.close(self.master)
        self.master = None
        self.link_path.unlink()

    def beat(self) -> None:
        """Send a heartbeat every 50 ms; note the companion's heartbeats."""
        assert self.master is not None
        now = time.monotonic()
        if now >= self.next_beat:
            self.next_beat = now + 0.05
            os.write(self.master, self.mav.heartbeat_encode(2, 12, 1, 0, 3).pack(self.mav))
            self.mav.seq = (self.mav.seq + 1) % 256
        while select.select([self.master], [], [], 0)[0]:
            try:
                data = os.read(self.master, 4096)
            except OSError:  # EIO: nobody has the device open (yet)
                return
            self.heard_heartbeat |= any(m.get_type() == "HEARTBEAT" for m in self.parser.feed(data))


def test_unplugged_serial_device_is_reopened_when_plugged_again(tmp_path: Path) -> None:
    device = tmp_path / "ttyACM0"
    autopilot = PtyAutopilot(device)
    link = MavlinkLink(f"serial:{device}:921600", system_id=1, component_id=191)
    try:
        pump([link], lambda: link.connected and autopilot.heard_heartbeat, also=autopilot.beat)
        autopilot.unplug()
        pump([link], lambda: link.fileno() is None)
        assert not link.connected and link.counters.link_losses == 1
        assert "ttyACM0" in (link.error or "")
        link.send(link.mav.heartbeat_encode(18, 8, 0, 0, 4))  # dropped, not raised
        assert link.counters.send_drops >= 1
        autopilot.plug()
        autopilot.heard_heartbeat = False
        pump([link], lambda: link.connected and autopilot.heard_heartbeat, also=autopilot.beat)
        assert link.counters.reconnects == 1 and link.error is None
    finally:
        link.close()
        autopilot.unplug()


def free_tcp_port() -> int:
    with socket.socket(socket.AF_INET, socket.SOCK_STREAM) as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def test_tcp_client_reconnects_to_a_restarted_server() -> None:
    port = free_tcp_port()

    def server() -> MavlinkLink:
        return MavlinkLink(f"tcpin:127.0.0.1:{port}", system_id=1, component_id=1, heartbeat=autopilot_heartbeat)

    autopilot = server()
    companion = MavlinkLink(f"tcp:127.0.0.1:{port}", system_id=1, component_id=191)
    try:
        pump([companion, autopilot], lambda: companion.connected and autopilot.connected)
        autopilot.close()
        pump([companion], lambda: companion.fileno() is None)
        assert companion.counters.link_losses == 1
        pump([companion], lambda: "refused" in (companion.error or ""))  # nobody listens: retried, not raised
        autopilot = server()
        pump([companion, autopilot], lambda: companion.connected and autopilot.connected)
        assert companion.counters.reconnects >= 1
    finally:
        autopilot.close()
        companion.close()


def test_tcp_server_takes_the_next_client_when_one_leaves() -> None:
    port = free_tcp_port()
    autopilot = MavlinkLink(f"tcpin:127.0.0.1:{port}", system_id=1, component_id=1, heartbeat=autopilot_heartbeat)
    first = MavlinkLink(f"tcp:127.0.0.1:{port}", system_id=1, component_id=191)
    second = None
    try:
        pump([first, autopilot], lambda: first.connected)
        first.close()
        second = MavlinkLink(f"tcp:127.0.0.1:{port}", system_id=2, component_id=191)
        pump([second, autopilot], lambda: second.connected and autopilot.peer == (2, 191))
    finally:
        autopilot.close()
        first.close()
        if second is not None:
            second.close()


class FakeClock:
    def __init__(self) -> None:
        self.now_us = 1_000_000

    def __call__(self) -> int:
        return self.now_us


def test_heartbeat_and_timesync_rates_and_the_loss_timeout_follow_the_clock() -> None:
    clock = FakeClock()
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as peer:
        peer.bind(("127.0.0.1", 0))
        peer.settimeout(PATIENCE_S)
        link = MavlinkLink(
            f"udpout:127.0.0.1:{peer.getsockname()[1]}",
            system_id=1,
            component_id=191,
            timesync=True,
            link_timeout_s=1.5,
            clock_us=clock,
        )
        mav = mavlink2.MAVLink(None, srcSystem=1, srcComponent=1)
        peer.connect(link.transport.sock.getsockname())
        peer.send(mav.heartbeat_encode(2, 12, 1, 0, 3).pack(mav))
        sent = FrameParser(mavlink2.MAVLink(None))
        kinds: list[str] = []
        try:
            pump([link], lambda: link.connected)
            connected_at = clock.now_us
            lost_at = None
            for _ in range(100):  # 10 s in steps of 0.1 s
                clock.now_us += 100_000
                link.poll()
                if lost_at is None and not link.connected:
                    lost_at = clock.now_us
            while len(kinds) < link.counters.packets_out:
                kinds += [m.get_type() for m in sent.feed(peer.recv(4096))]
        finally:
            link.close()
    assert lost_at is not None and 1_500_000 < lost_at - connected_at <= 1_600_000
    assert kinds.count("HEARTBEAT") in (10, 11)
    assert kinds.count("TIMESYNC") in (100, 101)
