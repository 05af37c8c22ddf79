import random

from stack.mavlink.timesync import MAX_RTT_US, SYNCED_SAMPLES, TimeSync


class RemoteClock:
    """A peer booted 5 s before us whose crystal runs 40 ppm fast."""

    def __init__(self, offset_us: float = -5_000_000.0, skew: float = 40e-6) -> None:
        self.offset_us = offset_us
        self.skew = skew

    def at(self, local_us: float) -> float:
        return local_us * (1 + self.skew) - self.offset_us


def exchange(sync: TimeSync, remote: RemoteClock, now_us: int, up_us: int, down_us: int) -> None:
    ts1 = sync.request(now_us)
    tc1_ns = round(remote.at(now_us + up_us) * 1000)
    sync.on_reply(tc1_ns, ts1, now_us + up_us + down_us)


def run(sync: TimeSync, remote: RemoteClock, seconds: float, rng: random.Random, start_us: int = 1_000_000) -> int:
    now = start_us
    for _ in range(int(seconds * 10)):
        exchange(sync, remote, now, rng.randint(200, 3000), rng.randint(200, 3000))
        now += 100_000
    return now


def mapping_error_us(sync: TimeSync, remote: RemoteClock, local_us: int) -> float:
    return sync.to_local_us(round(remote.at(local_us))) - local_us


def test_first_samples_map_within_half_the_round_trip() -> None:
    sync, remote = TimeSync(), RemoteClock()
    assert not sync.synced
    now = run(sync, remote, SYNCED_SAMPLES / 10, random.Random(1))
    assert sync.synced
    assert abs(mapping_error_us(sync, remote, now)) < 3000


def test_converges_on_offset_and_skew_with_jittery_delays() -> None:
    sync, remote = TimeSync(), RemoteClock()
    now = run(sync, remote, 120, random.Random(2))
    assert abs(mapping_error_us(sync, remote, now)) < 300
    assert abs(sync.skew + remote.skew) < 10e-6  # the offset (local - remote) shrinks as the peer runs fast
    assert 400 <= sync.rtt_us <= 6000


def test_replies_with_a_long_round_trip_are_rejected() -> None:
    sync, remote = TimeSync(), RemoteClock()
    now = run(sync, remote, 2, random.Random(3))
    samples = sync.samples
    # a reply delayed on the way back: its offset would be MAX_RTT/2 off
    exchange(sync, remote, now, 100, MAX_RTT_US + 5000)
    assert sync.samples == samples and sync.rejected_rtt == 1
    assert sync.rtt_us == MAX_RTT_US + 5100


def test_replies_to_requests_not_ours_are_ignored() -> None:
    sync = TimeSync()
    sync.request(1_000_000)
    sync.on_reply(5_000_000_000, 999, 1_001_000)
    assert sync.samples == 0
    ts1 = sync.request(2_000_000)
    sync.on_reply(5_000_000_000, ts1, 2_001_000)
    sync.on_reply(5_000_000_000, ts1, 2_001_000)  # a duplicate
    assert sync.samples == 1


def test_a_time_jump_of_the_peer_resets_and_resyncs() -> None:
    sync, remote = TimeSync(), RemoteClock()
    rng = random.Random(4)
    now = run(sync, remote, 10, rng)
    remote.offset_us += 30_000_000  # the autopilot rebooted: its clock restarts
    now = run(sync, remote, 1, rng, now)
    assert sync.resets == 1
    now = run(sync, remote, 2, rng, now)
    assert sync.synced
    assert abs(mapping_error_us(sync, remote, now)) < 3000


def test_an_outlier_after_sync_is_dropped_without_reset() -> None:
    sync, remote = TimeSync(), RemoteClock()
    rng = random.Random(5)
    now = run(sync, remote, 5, rng)
    offset = sync.offset_us
    ts1 = sync.request(now)
    sync.on_reply(round((remote.at(now) + 500_000) * 1000), ts1, now + 1000)
    assert sync.offset_us == offset and sync.resets == 0
