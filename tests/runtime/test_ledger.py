"""The step's accounting on its own: when lockstep time may advance, from the participants' counters."""

import pytest

from stack.runtime.ledger import (
    VERDICT_TIMEOUT_S,
    Departures,
    LockstepError,
    StallWatch,
    StepLedger,
    TimedMember,
    TriggeredMember,
    TriggerSource,
    Word,
    timer_due,
)

# Counter indices: a timed member (0 started, 1 finished, 2 ticks issued), a triggered member (3 started,
# 4 finished, 5 index of the last trigger it took) and its trigger's publisher (6 messages written).
TIMED = TimedMember("commander", key=1, started=0, finished=1, ticks=2)


def triggered(base: int = 0) -> TriggeredMember:
    return TriggeredMember("rate_control", key=2, started=3, finished=4, sources=(TriggerSource(6, 5, base),))


def ledger(base: int = 0) -> StepLedger:
    return StepLedger([TIMED], [triggered(base)])


def test_a_step_is_over_when_every_tick_and_every_trigger_has_been_run():
    assert ledger().complete([3, 3, 3, 7, 7, 7, 7])
    assert ledger().with_work([3, 3, 3, 7, 7, 7, 7]) == []


def test_a_tick_not_yet_started_is_work_left_but_no_run_going():
    counters = [3, 3, 4, 7, 7, 7, 7]
    assert not ledger().complete(counters)
    assert ledger().with_work(counters) == [(TIMED, False)]


def test_a_run_in_progress_holds_the_step():
    counters = [4, 3, 4, 7, 7, 7, 7]
    assert not ledger().complete(counters)
    assert ledger().with_work(counters) == [(TIMED, True)]


def test_a_trigger_message_not_yet_taken_holds_the_step():
    counters = [3, 3, 3, 7, 7, 7, 8]
    assert not ledger().complete(counters)
    assert ledger().with_work(counters) == [(triggered(), False)]
    taken = [3, 3, 3, 8, 7, 8, 8]  # taken, and its run started
    assert ledger().with_work(taken) == [(triggered(), True)]
    assert ledger().complete([3, 3, 3, 8, 8, 8, 8])


def test_a_member_never_waits_for_messages_written_before_it_was_admitted():
    # Restarted: its new process took nothing yet, but the publisher had written 8 when it came back.
    assert ledger(base=8).complete([3, 3, 3, 0, 0, 0, 8])
    assert not ledger(base=8).complete([3, 3, 3, 0, 0, 0, 9])


def test_time_waits_for_a_member_being_restarted_and_goes_on_without_one_that_is_gone():
    departures = Departures()
    departures.left("commander", now_s=10.0)
    departures.left("navigator", now_s=10.0)
    said = {"commander": Word.RESTARTING, "navigator": Word.GONE}
    assert departures.awaited(lambda d: said[d.name], 10.1) == ["commander to restart"]
    assert departures.awaited(lambda d: said[d.name], 99.0) == ["commander to restart"]  # as long as it takes
    departures.back("commander")
    assert not departures and departures.awaited(lambda d: said[d.name], 99.0) == []


def test_without_a_word_from_the_supervisor_time_waits_only_so_long():
    departures = Departures()
    departures.left("commander", now_s=10.0)
    assert departures.awaited(lambda _: Word.NONE, 10.0 + VERDICT_TIMEOUT_S) == [
        "the supervisor's word on commander"
    ]
    assert departures.awaited(lambda _: Word.NONE, 10.1 + VERDICT_TIMEOUT_S) == []
    assert departures.silent == ["commander"] and not departures


def test_a_timer_fires_on_the_first_step_of_each_period_aligned_interval():
    fired, last = [], None
    for t in range(4000, 60001, 4000):  # 250 Hz steps, a 50 Hz timer
        if timer_due(t, last, 20000):
            fired.append(t)
            last = t
    assert fired == [4000, 20000, 40000, 60000]


def test_a_step_is_stalled_only_after_the_timeout_without_any_progress() -> None:
    watch = StallWatch(4.0)
    watch.start(100.0)
    named = []

    def waiting() -> list[str]:
        named.append(True)
        return ["rate (sensor_gyro/0)", "alloc (vehicle_torque_setpoint/0)"]

    watch.check((1, 2), 100.0, 8000, waiting)
    watch.check((1, 2), 103.9, 8000, waiting)  # no progress, but not for 4 s yet
    watch.check((1, 3), 104.5, 8000, waiting)  # progress: the 4 s start again
    watch.check((1, 3), 108.4, 8000, waiting)
    assert not named
    with pytest.raises(LockstepError) as stalled:
        watch.check((1, 3), 108.6, 8000, waiting)
    assert str(stalled.value) == (
        "lockstep stalled at t=0.008 s: no progress for 4 s, waiting for "
        "alloc (vehicle_torque_setpoint/0), rate (sensor_gyro/0)"
    )
    # A new step's wait starts afresh.
    watch.start(200.0)
    watch.check((1, 3), 200.0, 12000, waiting)
    watch.check((1, 3), 203.0, 12000, waiting)
