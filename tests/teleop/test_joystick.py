"""The Linux joystick device's js_event records: whole, split between reads, of no known type."""

from stack.teleop.joystick import JS_EVENT, JS_EVENT_AXIS, JS_EVENT_BUTTON, JS_EVENT_INIT, JsDecoder, JsEvent


def record(value: int, type_: int, number: int, time_ms: int = 0) -> bytes:
    return JS_EVENT.pack(time_ms, value, type_, number)


def test_records_decode_with_their_init_flag():
    data = record(-32767, JS_EVENT_AXIS | JS_EVENT_INIT, 1, 5) + record(1, JS_EVENT_BUTTON, 7, 9)
    events = JsDecoder().feed(data)
    assert events == [JsEvent(5, -32767, JS_EVENT_AXIS | JS_EVENT_INIT, 1), JsEvent(9, 1, JS_EVENT_BUTTON, 7)]
    assert (events[0].kind, events[0].init, events[1].kind, events[1].init) == (JS_EVENT_AXIS, True, 1, False)


def test_a_record_split_between_reads_waits_for_its_rest():
    data = record(1234, JS_EVENT_AXIS, 3) * 2
    d = JsDecoder()
    assert d.feed(data[:5]) == []
    assert d.feed(data[5:11]) == [JsEvent(0, 1234, JS_EVENT_AXIS, 3)]
    assert d.feed(data[11:]) == [JsEvent(0, 1234, JS_EVENT_AXIS, 3)]


def test_records_of_no_known_type_are_counted_and_skipped():
    d = JsDecoder()
    events = d.feed(record(1, 0, 0) + record(1, 0x7F, 200) + b"\xff" * 8 + record(1, JS_EVENT_BUTTON, 0))
    assert events == [JsEvent(0, 1, JS_EVENT_BUTTON, 0)]
    assert d.malformed == 3
