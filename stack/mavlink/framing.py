"""MAVLink framing over a byte stream that may carry junk, truncated frames and flipped bits.

pymavlink's own parser (``MAVLink.parse_buffer``) raises on a bad prefix unless ``robust_parsing`` is set, and on a
bad CRC it drops the whole claimed frame length, which swallows the good frames behind a truncated one. Here a
frame that fails to decode is skipped by one byte only and the scan resumes at the next start marker, so every
good frame after damage is recovered; only ``MAVLink.decode`` (header, length, CRC with CRC_EXTRA, signature) is
pymavlink's.

Errors are counted once per gap between two good frames: ``crc_errors`` when the gap is a whole frame whose CRC
failed, ``parse_errors`` when it holds bytes that are not MAVLink or a frame cut short by the next one.
"""

from __future__ import annotations

from pymavlink.dialects.v20 import common as mavlink2

V1, V2 = mavlink2.PROTOCOL_MARKER_V1, mavlink2.PROTOCOL_MARKER_V2
V1_OVERHEAD = mavlink2.HEADER_LEN_V1 + 2
V2_OVERHEAD = mavlink2.HEADER_LEN_V2 + 2
MAX_FRAME = V2_OVERHEAD + 255 + mavlink2.MAVLINK_SIGNATURE_BLOCK_LEN


class FrameParser:
    def __init__(self, mav: mavlink2.MAVLink) -> None:
        self.mav = mav
        self.buf = bytearray()
        self.base = 0  # stream offset of buf[0]
        self.crc_errors = 0
        self.parse_errors = 0
        self.unknown_messages = 0
        self.unknown_ids: dict[int, int] = {}
        self._gap_open = False
        self._gap_crc_end: int | None = None  # where the gap's first failed frame ended, if its CRC failed

    def feed(self, data: bytes) -> list[mavlink2.MAVLink_message]:
        """Add bytes and return every good frame now complete, in order (MAVLink 1 and 2)."""
        self.buf += data
        messages: list[mavlink2.MAVLink_message] = []
        pos = 0
        while pos < len(self.buf):
            start = self._next_marker(pos)
            if start < 0:
                self._skip()
                pos = len(self.buf)
                break
            if start > pos:
                self._skip()
            pos = start
            length = self._frame_length(pos)
            if length is None:  # header incomplete
                break
            if length == 0:  # a marker byte that cannot start a frame
                self._skip()
                pos += 1
                continue
            if len(self.buf) - pos < length:
                break
            frame = self.buf[pos : pos + length]
            try:
                msg = self.mav.decode(frame)
            except mavlink2.MAVError as e:
                self._skip(failed_end=self.base + pos + length, crc="CRC" in e.message)
                pos += 1
                continue
            if isinstance(msg, mavlink2.MAVLink_unknown):
                if not self._followed_by_frame(pos + length):
                    self._skip()
                    pos += 1
                    continue
                self.unknown_messages += 1
                msg_id = _msg_id(frame)
                self.unknown_ids[msg_id] = self.unknown_ids.get(msg_id, 0) + 1
            else:
                messages.append(msg)
            self._close_gap(self.base + pos)
            pos += length
        del self.buf[:pos]
        self.base += pos
        return messages

    def _next_marker(self, pos: int) -> int:
        v2 = self.buf.find(V2, pos)
        v1 = self.buf.find(V1, pos, v2 if v2 >= 0 else len(self.buf))
        return v1 if v1 >= 0 else v2

    def _frame_length(self, pos: int) -> int | None:
        """The frame's length from its header, None if the header is not complete, 0 if it cannot be a frame."""
        if len(self.buf) - pos < 3:
            return None
        payload = self.buf[pos + 1]
        if self.buf[pos] == V1:
            return V1_OVERHEAD + payload
        flags = self.buf[pos + 2]
        if flags & ~mavlink2.MAVLINK_IFLAG_SIGNED:
            return 0
        signature = mavlink2.MAVLINK_SIGNATURE_BLOCK_LEN if flags & mavlink2.MAVLINK_IFLAG_SIGNED else 0
        return V2_OVERHEAD + payload + signature

    def _followed_by_frame(self, end: int) -> bool:
        """An unknown id cannot be CRC-checked; junk that happens to start with a marker is told apart from a real
        frame of another dialect by what follows: a real stream carries the next frame at once."""
        return end >= len(self.buf) or self.buf[end] in (V1, V2)

    def _skip(self, failed_end: int | None = None, crc: bool = False) -> None:
        if not self._gap_open:
            self._gap_open = True
            self._gap_crc_end = failed_end if crc else None

    def _close_gap(self, good_start: int) -> None:
        if not self._gap_open:
            return
        if self._gap_crc_end is not None and self._gap_crc_end <= good_start:
            self.crc_errors += 1
        else:
            self.parse_errors += 1
        self._gap_open = False
        self._gap_crc_end = None


def _msg_id(frame: bytes | bytearray) -> int:
    if frame[0] == V1:
        return frame[5]
    return frame[7] | frame[8] << 8 | frame[9] << 16
