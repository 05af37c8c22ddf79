"""MAVLink endpoints as the user writes them: ``serial:/dev/ttyACM0:921600``, ``udp:HOST:PORT``, ``tcp:HOST:PORT``.

The prefixes follow pymavlink's ``mavutil.mavlink_connection``: ``udp``/``udpin`` listen on HOST:PORT and answer
whoever sent last, ``udpout`` sends to HOST:PORT from an ephemeral port, ``tcp`` connects to a server, ``tcpin``
accepts one client at a time.
"""

from __future__ import annotations

from dataclasses import dataclass

KINDS = ("serial", "udpin", "udpout", "tcp", "tcpin")
DEFAULT_BAUD = 921600  # the TELEM2 baud of PX4's companion-computer setup (SER_TEL2_BAUD)


@dataclass(frozen=True)
class Endpoint:
    kind: str
    host: str = ""
    port: int = 0
    device: str = ""
    baud: int = 0

    def __str__(self) -> str:
        if self.kind == "serial":
            return f"serial:{self.device}:{self.baud}"
        return f"{self.kind}:{self.host}:{self.port}"


def parse_endpoint(text: str) -> Endpoint:
    """Parse an endpoint; a ValueError names what is wrong with it."""
    kind, sep, rest = text.strip().partition(":")
    if not sep:
        raise ValueError(
            f"endpoint {text!r}: expected KIND:..., e.g. serial:/dev/ttyACM0:921600 or udp:127.0.0.1:14540"
        )
    kind = "udpin" if kind == "udp" else kind
    if kind == "serial":
        return _parse_serial(text, rest)
    if kind not in KINDS:
        raise ValueError(f"endpoint {text!r}: unknown kind {kind!r} (serial, udp, udpin, udpout, tcp, tcpin)")
    host, sep, port_text = rest.rpartition(":")
    if not sep or not host:
        raise ValueError(f"endpoint {text!r}: expected {kind}:HOST:PORT")
    return Endpoint(kind, host=host, port=_number(text, "port", port_text, 1, 65535))


def _parse_serial(text: str, rest: str) -> Endpoint:
    device, _, baud_text = rest.rpartition(":")
    if not baud_text.isdigit():  # no baud given; device paths such as /dev/serial/by-path/...:1.0 hold colons
        device, baud_text = rest, ""
    if not device:
        raise ValueError(f"endpoint {text!r}: expected serial:DEVICE[:BAUD]")
    baud = _number(text, "baud", baud_text, 50, 20_000_000) if baud_text else DEFAULT_BAUD
    return Endpoint("serial", device=device, baud=baud)


def _number(text: str, what: str, value: str, low: int, high: int) -> int:
    try:
        number = int(value)
    except ValueError:
        raise ValueError(f"endpoint {text!r}: {what} {value!r} is not a number") from None
    if not low <= number <= high:
        raise ValueError(f"endpoint {text!r}: {what} {number} out of range {low}..{high}")
    return number
