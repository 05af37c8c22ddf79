import socket
import time
from collections.abc import Callable

from pymavlink.dialects.v20 import common as mavlink2

from stack.mavlink.link import MavlinkLink

PATIENCE_S = 30.0  # generous: the test machine may be heavily loaded


def free_udp_port() -> int:
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def autopilot_heartbeat() -> dict:
    return {
        "type": mavlink2.MAV_TYPE_QUADROTOR,
        "autopilot": mavlink2.MAV_AUTOPILOT_PX4,
        "base_mode": mavlink2.MAV_MODE_FLAG_CUSTOM_MODE_ENABLED,
        "custom_mode": 0,
        "system_status": mavlink2.MAV_STATE_STANDBY,
    }


def pump(links: list[MavlinkLink], until: Callable[[], bool], patience_s: float = PATIENCE_S) -> list:
    """Poll every link until the condition holds; returns what the first link received."""
    received = []
    deadline = time.monotonic() + patience_s
    while not until():
        assert time.monotonic() < deadline, "condition not met in time"
        received += links[0].poll(0.005)
        for link in links[1:]:
            link.poll(0.005)
    return received


def udp_pair(**companion_options) -> tuple[MavlinkLink, MavlinkLink]:
    port = free_udp_port()
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
