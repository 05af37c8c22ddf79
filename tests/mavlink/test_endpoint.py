import pytest

from stack.mavlink.endpoint import DEFAULT_BAUD, Endpoint, parse_endpoint


@pytest.mark.parametrize(
    ("text", "expected"),
    [
        ("serial:/dev/ttyACM0:921600", Endpoint("serial", device="/dev/ttyACM0", baud=921600)),
        ("serial:/dev/ttyS1:57600", Endpoint("serial", device="/dev/ttyS1", baud=57600)),
        ("serial:/dev/ttyUSB0", Endpoint("serial", device="/dev/ttyUSB0", baud=DEFAULT_BAUD)),
        (
            "serial:/dev/serial/by-path/pci-0000:00:14.0-usb-0:1:1.0",
            Endpoint("serial", device="/dev/serial/by-path/pci-0000:00:14.0-usb-0:1:1.0", baud=DEFAULT_BAUD),
        ),
        ("udp:127.0.0.1:14540", Endpoint("udpin", host="127.0.0.1", port=14540)),
        ("udpin:127.0.0.1:14540", Endpoint("udpin", host="127.0.0.1", port=14540)),
        ("udpout:127.0.0.1:14580", Endpoint("udpout", host="127.0.0.1", port=14580)),
        ("tcp:localhost:5760", Endpoint("tcp", host="localhost", port=5760)),
        ("tcpin:127.0.0.1:5760", Endpoint("tcpin", host="127.0.0.1", port=5760)),
    ],
)
def test_parses_every_kind(text: str, expected: Endpoint) -> None:
    assert parse_endpoint(text) == expected


def test_round_trips_through_str() -> None:
    for text in ("serial:/dev/ttyACM0:921600", "udpin:127.0.0.1:14540", "tcp:127.0.0.1:5760"):
        assert str(parse_endpoint(text)) == text


@pytest.mark.parametrize(
    ("text", "problem"),
    [
        ("/dev/ttyACM0", "expected KIND"),
        ("bogus:1.2.3.4:5", "unknown kind 'bogus'"),
        ("udp:14540", "expected udpin:HOST:PORT"),
        ("udp:127.0.0.1:port", "port 'port' is not a number"),
        ("tcp:127.0.0.1:70000", "port 70000 out of range"),
        ("serial::921600", "expected serial:DEVICE"),
        ("serial:/dev/ttyACM0:0", "baud 0 out of range"),
    ],
)
def test_refuses_with_the_problem_named(text: str, problem: str) -> None:
    with pytest.raises(ValueError, match=problem):
        parse_endpoint(text)
