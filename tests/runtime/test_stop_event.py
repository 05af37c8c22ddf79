"""StopEvent: a stop a signal handler may request, waking every waiter at once, and staying set."""

import signal
import threading
import time

from stack.runtime.stop_event import StopEvent


def test_a_signal_handler_stops_a_wait_in_the_main_thread_at_once():
    stop = StopEvent()
    previous = signal.signal(signal.SIGALRM, lambda *_: stop.set())
    try:
        signal.setitimer(signal.ITIMER_REAL, 0.05)
        started = time.monotonic()
        assert stop.wait(30.0)
        assert time.monotonic() - started < 10.0
    finally:
        signal.setitimer(signal.ITIMER_REAL, 0)
        signal.signal(signal.SIGALRM, previous)


def test_every_waiter_wakes_and_it_stays_set():
    stop = StopEvent()
    assert not stop.wait(0.01) and not stop.is_set()
    woken = []
    waiters = [threading.Thread(target=lambda: woken.append(stop.wait(30.0))) for _ in range(3)]
    for t in waiters:
        t.start()
    stop.set()
    stop.set()
    for t in waiters:
        t.join(10.0)
    assert woken == [True, True, True]
    assert stop.is_set() and stop.wait(0) and stop.wait()
