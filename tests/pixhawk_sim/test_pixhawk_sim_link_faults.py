"""Link faults, the UART's byte rate and the control channel, without any I/O or wall clock."""

from __future__ import annotations

import pytest

from stack.pixhawk_sim.control import apply_request
from stack.pixhawk_sim.faults import FaultInjector, FaultSettings
from stack.pixhawk_sim.uart import UartPacer

FRAME = bytes(range(40))


def test_no_faults_delivers_everything_at_once_and_in_order() -> None:
    f = FaultInjector()
    for i in range(10):
        f.send(bytes([i]) * 5, 1.0)
    assert f.outbound.pop_due(1.0) == [bytes([i]) * 5 for i in range(10)]
    assert f.outbound.counters.delivered == 10 and f.next_due() is None


def test_drop_loses_about_the_share_asked_in_each_direction() -> None:
    f = FaultInjector(FaultSettings(drop=0.05), seed=3)
    for _ in range(20000):
        f.send(FRAME, 0.0)
        f.receive(FRAME, 0.0)
    for channel in (f.outbound, f.inbound):
        share = channel.counters.dropped / channel.counters.packets
        assert 0.04 < share < 0.06
        assert len(channel.pop_due(0.0)) == channel.counters.packets - channel.counters.dropped


def test_corrupt_flips_one_bit_in_the_bytes_it_hits() -> None:
    f = FaultInjector(FaultSettings(corrupt=0.01), seed=1)
    for _ in range(2000):
        f.send(FRAME, 0.0)
    out = f.outbound.pop_due(0.0)
    flipped_bytes = 0
    for data in out:
        assert len(data) == len(FRAME)
        for a, b in zip(data, FRAME, strict=True):
            if a != b:
                assert bin(a ^ b).count("1") == 1
                flipped_bytes += 1
    expected = 0.01 * 2000 * len(FRAME)
    assert 0.8 * expected < flipped_bytes < 1.2 * expected
    assert f.outbound.counters.corrupted == sum(d != FRAME for d in out)


def test_latency_and_jitter_delay_packets_within_bounds_and_keep_their_order() -> None:
    f = FaultInjector(FaultSettings(latency_ms=20.0, jitter_ms=5.0), seed=2)
    for i in range(200):
        f.send(i.to_bytes(2, "big"), i * 0.001)
    assert f.outbound.pop_due(0.0149) == []
    delivered = []
    t = 0.0
    while len(delivered) < 200:
        t += 0.0005
        delivered += [(t, int.from_bytes(d, "big")) for d in f.outbound.pop_due(t)]
    assert [i for _, i in delivered] == list(range(200))
    for t_out, i in delivered:
        assert t_out - i * 0.001 >= 0.015 - 1e-9
    # FIFO may hold a packet behind a later-due one, but never past its predecessor's jitter bound.
    assert max(t_out - i * 0.001 for t_out, i in delivered) <= 0.0255 + 0.001


def test_a_cut_loses_everything_in_both_directions_for_its_duration() -> None:
    f = FaultInjector()
    f.cut(10.0, 2.0)
    f.send(FRAME, 9.99)
    f.send(FRAME, 10.0)
    f.receive(FRAME, 11.9)
    f.send(FRAME, 12.0)
    assert f.outbound.counters.cut == 1 and f.inbound.counters.cut == 1
    assert len(f.outbound.pop_due(12.0)) == 2
    assert f.report()["cuts"] == 1


def test_configure_is_all_or_nothing() -> None:
    f = FaultInjector()
    with pytest.raises(ValueError, match="drop"):
        f.configure(latency_ms=10.0, drop=1.5)
    assert f.settings == FaultSettings()
    with pytest.raises(ValueError, match="unknown"):
        f.configure(loss=0.1)
    f.configure(drop=0.1, jitter_ms=3)
    assert f.settings == FaultSettings(drop=0.1, jitter_ms=3.0)


def test_control_requests() -> None:
    f = FaultInjector()
    assert apply_request({"cut_s": 2}, f, 100.0) == {"ok": True}
    assert f.is_cut(101.9) and not f.is_cut(102.0)
    assert apply_request({"drop": 0.05, "latency_ms": 10}, f, 0.0) == {"ok": True}
    assert f.settings.drop == 0.05 and f.settings.latency_ms == 10.0
    assert apply_request({"status": True}, f, 0.0) == {"ok": True}
    for bad in ([1], {"cut_s": -1}, {"cut_s": "2"}, {"drop": True}, {"drop": 2.0}, {"nonsense": 1}):
        answer = apply_request(bad, f, 0.0)
        assert answer["ok"] is False and answer["error"]
    assert f.settings.drop == 0.05


def test_uart_carries_92160_bytes_per_second_at_921600_baud() -> None:
    uart = UartPacer(921600, buffer_bytes=1_000_000)
    for _ in range(1000):
        assert uart.offer(FRAME, 0.0)
    carried = b""
    t = 0.0
    while t < 0.25:
        t += 0.004
        carried += uart.take(t)
    assert abs(len(carried) - 92160 * t) <= 1
    assert carried == (FRAME * 1000)[: len(carried)]


def test_uart_drops_frames_that_do_not_fit_whole_and_counts_them() -> None:
    uart = UartPacer(921600, buffer_bytes=100)
    assert uart.offer(FRAME, 0.0) and uart.offer(FRAME, 0.0)
    assert not uart.offer(FRAME, 0.0)
    assert uart.counters.frames_dropped == 1 and uart.counters.bytes_dropped == len(FRAME)
    assert uart.queued == 2 * len(FRAME)


def test_an_idle_uart_does_not_burst() -> None:
    uart = UartPacer(921600)
    assert uart.take(0.0) == b""
    uart.offer(FRAME * 10, 5.0)  # nothing sent for 5 s: no credit saved up
    assert len(uart.take(5.001)) == 92


def test_a_byte_stream_keeps_what_fits_and_loses_the_rest() -> None:
    uart = UartPacer(921600, buffer_bytes=100)
    uart.offer_bytes(FRAME * 3, 0.0)
    assert uart.queued == 100 and uart.counters.bytes_dropped == 20
    assert uart.take(1.0) == (FRAME * 3)[:100]
