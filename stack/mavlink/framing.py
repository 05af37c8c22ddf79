"""MAVLink framing over a byte stream that may carry junk, truncated frames and flipped bits.

pymavlink's own parser (``MAVLink.parse_buffer``) raises on a bad prefix unless ``robust_parsing`` is set, and on a
bad CRC it drops the whole claimed frame length, which swallows the good frames behind a truncated one. Here a
frame that fails to decode is skipped by one byte only and the scan resumes at the next start marker, so every
good frame after damage is recovered; only ``MAVLink.decode`` (header, length, CRC with CRC_EXTRA, signature) is
pymavlink's.

Errors are counted once per gap between two good frames, when the gap begins: ``crc_errors`` when it begins with a
whole frame whose CRC failed, ``parse_errors`` when with bytes that are not MAVLink or a frame cut short by the next
one. Joining a stream mid-frame (opening a serial port while the autopilot talks) is no error.
"""

from __future__ import annotations

from pymavlink.dialects.v20 import common as mavlink2

V1, V2 = mavlink2.PROTOCOL_MARKER_V1, mavlink2.PROTOCOL_MARKER_V2
V1_OVERHEAD = mavlink2.HEADER_LEN_V1 + 2
V2_OVERHEAD = mavlink2.HEADER_LEN_V2 + 2
LONGEST_FRAME = V2_OVERHEAD + 255 + mavlink2.MAVLINK_SIGNATURE_BLOCK_LEN


class FrameParser:
    def __init__(self, mav: mavlink2.MAVLink) -> None:
        self.mav = mav
        self.buf = bytearray()
        self.crc_errors = 0
        self.parse_errors = 0
        self.unknown_messages = 0
        self.unknown_ids: dict[int, int] = {}
        self._in_gap = False  # bytes were dropped since the last good frame
        self._joined = False  # a good frame came since the stream began
        self._lead_bytes = 0  # dropped before that
        self._lead_counted = False

    def feed(self, data: bytes) -> list[mavlink2.MAVLink_message]:
        """Add bytes and return every good frame now complete, in order (MAVLink 1 and 2); frames of ids this
        dialect does not know come as ``MAVLink_unknown`` (no fields, but their header)."""
        self.buf += data
        messages: list[mavlink2.MAVLink_message] = []
        pos, end = 0, len(self.buf)
        while pos < end:
            start = self._next_marker(pos)
            if start < 0:
                self._drop_junk()
                pos = end
                break
            if start > pos:
                self._drop_junk()
            pos = start
            length = self._frame_length(pos)
            if length is None:  # header incomplete
                break
            if length == 0:  # a marker byte that cannot start a frame
                self._drop_junk()
                pos += 1
                continue
            if end - pos < length:
                if self._good_frame_within(pos + 1, end):  # cut short by the next frame: do not wait for the rest
                    self._drop_frame(crc=False)
                    pos += 1
                    continue
                break
            frame = self.buf[pos : pos + length]
            try:
                msg = self.mav.decode(frame)
            except mavlink2.MAVError as e:
                self._drop_frame(crc="CRC" in e.message and not self._good_frame_within(pos + 1, pos + length))
                pos += 1
                continue
            if isinstance(msg, mavlink2.MAVLink_unknown):
                if not self._followed_by_frame(pos + length):
                    self._drop_junk()
                    pos += 1
                    continue
                self.unknown_messages += 1
                msg._header = _header(frame)
                msg_id = msg._header.msgId
                self.unknown_ids[msg_id] = self.unknown_ids.get(msg_id, 0) + 1
            messages.append(msg)
            self._in_gap = False
            if not self._joined:
                self._joined = True
                self._count_lead(self._lead_bytes + pos)
            pos += length
        if not self._joined:
            self._lead_bytes += pos
            self._count_lead(self._lead_bytes)
        del self.buf[:pos]
        return messages

    def discard_partial_frame(self) -> None:
        """Forget bytes waiting for the rest of their frame: the stream they came from is gone."""
        self.buf.clear()
        self._in_gap = False
        self._joined = False
        self._lead_bytes = 0
        self._lead_counted = False

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

    def _good_frame_within(self, start: int, end: int) -> bool:
        """Whether a complete frame that decodes starts in buf[start:end] (only looked for after damage)."""
        pos = self._next_marker(start)
        while 0 <= pos < end:
            length = self._frame_length(pos)
            if length and pos + length <= len(self.buf):
                try:
                    msg = self.mav.decode(self.buf[pos : pos + length])
                except mavlink2.MAVError:
                    pass
                else:
                    if not isinstance(msg, mavlink2.MAVLink_unknown):
                        return True
            pos = self._next_marker(pos + 1)
        return False

    def _followed_by_frame(self, end: int) -> bool:
        """An unknown id cannot be CRC-checked; junk that happens to start with a marker is told apart from a real
        frame of another dialect by what follows: a real stream carries the next frame at once."""
        return end >= len(self.buf) or self.buf[end] in (V1, V2)

    def _count_lead(self, dropped: int) -> None:
        """A serial port opened mid-stream starts with the tail of a frame: no error unless more was dropped."""
        if dropped > LONGEST_FRAME and not self._lead_counted:
            self._lead_counted = True
            self.parse_errors += 1

    def _drop_junk(self) -> None:
        if self._joined and not self._in_gap:
            self._in_gap = True
            self.parse_errors += 1

    def _drop_frame(self, crc: bool) -> None:
        if self._joined and not self._in_gap:
            self._in_gap = True
            if crc:
                self.crc_errors += 1
            else:
                self.parse_errors += 1


def _header(frame: bytes | bytearray) -> mavlink2.MAVLink_header:
    """The header pymavlink leaves unset on a MAVLink_unknown, so its sender and sequence number still count."""
    if frame[0] == V1:
        return mavlink2.MAVLink_header(frame[5], mlen=frame[1], seq=frame[2], srcSystem=frame[3], srcComponent=frame[4])
    return mavlink2.MAVLink_header(
        frame[7] | frame[8] << 8 | frame[9] << 16,
        incompat_flags=frame[2],
        compat_flags=frame[3],
        mlen=frame[1],
        seq=frame[4],
        srcSystem=frame[5],
        srcComponent=frame[6],
    )
