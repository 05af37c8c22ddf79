"""FastMessageWriter writes the very bytes mcap's own Writer writes, chunk boundaries included."""

from __future__ import annotations

import io
import random

from mcap.reader import make_reader
from mcap.writer import CompressionType, Writer

from stack.record.mcapwrite import FastMessageWriter


def write(writer_type: type[Writer], messages: list[tuple[int, int, bytes, int, int]]) -> bytes:
    out = io.BytesIO()
    writer = writer_type(out, chunk_size=4096, compression=CompressionType.ZSTD)
    writer.start(profile="", library="test")
    schema = writer.register_schema(name="s", encoding="jsonschema", data=b"{}")
    for channel in range(3):
        writer.register_channel(topic=f"t{channel}", message_encoding="json", schema_id=schema)
    for channel, log_time, data, publish_time, sequence in messages:
        writer.add_message(channel + 1, log_time, data, publish_time, sequence)
    writer.finish()
    return out.getvalue()


def test_same_bytes_as_mcap_including_out_of_order_times():
    rng = random.Random(3)
    messages = [
        (rng.randrange(3), max(0, i * 1000 + rng.randrange(-5000, 5000)), rng.randbytes(rng.randrange(200)), i, i)
        for i in range(3000)
    ]
    fast = write(FastMessageWriter, messages)
    assert fast == write(Writer, messages)
    read = [
        (m.channel_id - 1, m.log_time, m.data, m.publish_time, m.sequence)
        for _, _, m in make_reader(io.BytesIO(fast)).iter_messages(log_time_order=False)
    ]
    assert read == messages
