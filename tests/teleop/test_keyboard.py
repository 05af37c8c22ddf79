"""The keyboard as sticks: a press holds a stick past the auto-repeat delay, repeats ramp it up, a release (no
more repeats) springs it back; the throttle stays; keys for actions and quitting."""

import pytest

from stack.teleop.actions import ARM, DISARM
from stack.teleop.keyboard import (
    DECAY_PER_S,
    DEFAULT_LIMIT,
    FIRST_HOLD_S,
    QUIT,
    REPEAT_HOLD_S,
    STEP,
    TAP,
    THROTTLE_STEP,
    Keyboard,
)
from stack.teleop.sticks import Sticks

REPEAT_S = 0.033
"""An auto-repeat interval (30 Hz)."""


def hold(kb: Keyboard, key: str, start: float, duration: float, delay: float = 0.5) -> float:
    """A key held from ``start`` for ``duration`` s, as a terminal reports it: a press, then after ``delay`` a
    press every REPEAT_S; the time of the last press."""
    kb.key(key, start)
    t = start + delay
    last = start
    while t <= start + duration:
        kb.key(key, t)
        last = t
        t += REPEAT_S
    return last


def test_sticks_start_centred_with_the_throttle_at_minimum():
    assert Keyboard().sticks(0.0) == Sticks(0.0, 0.0, 0.0, -1.0)


def test_a_tap_deflects_holds_through_the_auto_repeat_delay_then_springs_back():
    kb = Keyboard()
    kb.key("up", 10.0)
    tap = TAP * DEFAULT_LIMIT
    assert kb.sticks(10.0).pitch == tap
    assert kb.sticks(10.0 + FIRST_HOLD_S).pitch == tap  # longer than a 660 ms X11 repeat delay
    assert 0.0 < kb.sticks(10.0 + FIRST_HOLD_S + 0.05).pitch < tap
    assert kb.sticks(10.0 + FIRST_HOLD_S + tap / DECAY_PER_S + 1e-6).pitch == 0.0


def test_a_held_key_ramps_to_the_limit_and_is_let_go_soon_after_its_repeats_stop():
    kb = Keyboard()
    last = hold(kb, "left", 0.0, 1.0)
    assert kb.sticks(last).roll == pytest.approx(-DEFAULT_LIMIT)
    assert kb.sticks(last + REPEAT_HOLD_S).roll == pytest.approx(-DEFAULT_LIMIT)
    assert kb.sticks(last + REPEAT_HOLD_S + DEFAULT_LIMIT / DECAY_PER_S + 1e-6).roll == 0.0


def test_repeats_add_a_step_each():
    kb = Keyboard()
    kb.key("d", 0.0)
    kb.key("d", 0.5)
    assert kb.sticks(0.5).yaw == pytest.approx((TAP + STEP) * DEFAULT_LIMIT)


def test_the_opposite_key_reverses_at_once():
    kb = Keyboard()
    hold(kb, "up", 0.0, 1.0)
    kb.key("down", 1.01)
    assert kb.sticks(1.01).pitch == -TAP * DEFAULT_LIMIT


def test_sticks_are_independent_but_a_terminal_repeats_only_the_last_key():
    kb = Keyboard()
    kb.key("up", 0.0)
    kb.key("right", 0.1)
    assert kb.sticks(0.2)[:2] == (TAP * DEFAULT_LIMIT, TAP * DEFAULT_LIMIT)


def test_the_throttle_stays_where_it_is_put_within_its_range():
    kb = Keyboard()
    for i in range(10):
        kb.key("w", i * REPEAT_S)
    assert kb.sticks(100.0).throttle == pytest.approx(-1.0 + 10 * THROTTLE_STEP)
    for i in range(100):
        kb.key("W", 1.0 + i * REPEAT_S)  # Caps Lock on
    assert kb.sticks(100.0).throttle == 1.0
    for i in range(100):
        kb.key("s", 10.0 + i * REPEAT_S)
    assert kb.sticks(100.0).throttle == -1.0


def test_space_centres_every_stick_and_the_throttle():
    kb = Keyboard()
    kb.key("up", 0.0)
    kb.key("w", 0.0)
    kb.key(" ", 0.1)
    assert kb.sticks(0.1) == Sticks(0.0, 0.0, 0.0, 0.0)


def test_the_stick_limit_steps_and_bounds_the_deflection():
    kb = Keyboard()
    kb.key("]", 0.0)
    kb.key("]", 0.0)
    kb.key("]", 0.0)
    assert kb.limit == 1.0
    last = hold(kb, "right", 1.0, 2.0)
    assert kb.sticks(last).roll == pytest.approx(1.0)
    for _ in range(5):
        kb.key("[", last)
    assert kb.limit == 0.25
    assert kb.sticks(last).roll == pytest.approx(0.25)


def test_keys_for_actions_and_quitting():
    kb = Keyboard()
    assert [kb.key(k, 0.0) for k in "mx145"] == [ARM, DISARM, "stabilized", "posctl", "rotors"]
    assert [kb.key(k, 0.0) for k in ("q", "Q", "\x03", "\x04")] == [QUIT] * 4
    assert kb.key("z", 0.0) is None
    assert kb.sticks(0.0) == Sticks()
