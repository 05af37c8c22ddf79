"""Flight recording and replay, like PX4's logger and its log tools, in MCAP.

- :mod:`stack.record.format`: the file layout (what Foxglove, PlotJuggler and replay read).
- :mod:`stack.record.jsoncodec`: messages as JSON objects with JSON Schemas, exactly.
- :mod:`stack.record.recorder`: ``RecordingWriter`` and ``RecordingReader`` (the API every
  consumer builds on), ``RecordedMessage``, ``RecordingError``.
- :mod:`stack.record.mcapscan`: reading what a cut or damaged file still holds.
- :mod:`stack.record.module`: the ``recorder`` module.
- :mod:`stack.record.replay`, :mod:`stack.record.csvexport`, :mod:`stack.record.overview`: what
  ``stack replay``, ``stack log export --csv`` and ``stack log info`` do.
"""
