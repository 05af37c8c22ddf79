"""MAVLink 2 message signing on a link (https://mavlink.io/en/guide/message_signing.html), opt-in per link.

With a key, every message sent is signed, and a received message is taken only when its signature checks with
the key (and its timestamp is newer than the last one from that sender, pymavlink's replay check); unsigned
messages other than HEARTBEAT are refused, as PX4 does with MAV_SIGN_CFG set (``MavlinkSignControl``), so a
ground station without the key still sees the vehicle but cannot command it. The key is 32 bytes, kept in a
file as 64 hexadecimal digits (or as the 32 raw bytes); SETUP_SIGNING over the link is not accepted.
"""

from __future__ import annotations

import string
import time
from pathlib import Path

from pymavlink.dialects.v20 import common as mavlink2

KEY_BYTES = 32
SIGNING_EPOCH_UNIX_S = 1_420_070_400
"""Signing timestamps count 10 µs units since 2015-01-01 (``common.xml``)."""
UNSIGNED_ALLOWED = frozenset({mavlink2.MAVLINK_MSG_ID_HEARTBEAT})


def load_key(path: str | Path) -> bytes:
    """The key in a file; ValueError saying what is wrong with the file."""
    data = Path(path).read_bytes()
    text = data.decode("ascii", errors="replace").strip()
    if len(text) == 2 * KEY_BYTES and all(c in string.hexdigits for c in text):
        return bytes.fromhex(text)
    if len(data) == KEY_BYTES:
        return data
    raise ValueError(f"signing key {path}: expected {2 * KEY_BYTES} hexadecimal digits or {KEY_BYTES} bytes")


def _allow_unsigned(mav: mavlink2.MAVLink, msg_id: int) -> bool:
    return msg_id in UNSIGNED_ALLOWED


def enable(mav: mavlink2.MAVLink, key: bytes, link_id: int = 0) -> None:
    """Sign everything ``mav`` sends and refuse what it receives unsigned (HEARTBEAT excepted)."""
    mav.signing.secret_key = key
    mav.signing.link_id = link_id
    mav.signing.sign_outgoing = True
    mav.signing.allow_unsigned_callback = _allow_unsigned
    mav.signing.timestamp = max(0, int((time.time() - SIGNING_EPOCH_UNIX_S) * 100_000))


def refused(mav: mavlink2.MAVLink) -> int:
    """Messages refused for a missing or wrong signature so far."""
    return mav.signing.reject_count
