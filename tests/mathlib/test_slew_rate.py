"""SlewRate: PX4's rate-of-change limiter."""

from stack.mathlib.filters import SlewRate


def test_moves_by_at_most_rate_times_dt_and_stops_at_target():
    s = SlewRate(0.5)
    assert s.update(1.0, 0.1) == 0.05
    for _ in range(100):
        s.update(1.0, 0.1)
    assert s.state == 1.0


def test_small_step_is_taken_exactly_and_downward_is_limited_too():
    s = SlewRate(2.0, initial=1.0)
    assert s.update(1.05, 0.1) == 1.05
    assert s.update(0.0, 0.1) == 1.05 - 0.2


def test_forced_value_bypasses_the_limit():
    s = SlewRate(0.1)
    s.set_forced_value(0.7)
    assert s.state == 0.7
