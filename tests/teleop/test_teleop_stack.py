"""`stack teleop` against a real-time stack, typed at through a pseudo-terminal: a flight by keyboard (arm, climb in
Altitude, move in Position, land, disarm), a gamepad (a FIFO standing in for /dev/input/js0: arm by a button,
climb by an axis, the stick values on the bus, the device lost), and every way out giving the terminal back with
the sticks centred. The clock is the wall clock on a loaded machine, so the margins are wide."""

from __future__ import annotations

import math
import os
import re
import time
from collections.abc import Callable, Iterator
from pathlib import Path

import pytest

from stack.teleop.joystick import JS_EVENT, JS_EVENT_AXIS, JS_EVENT_BUTTON, JS_EVENT_INIT
from tests.support.harness import RunningStack, launch_profile, wait_no_processes
from tests.teleop.terminal import SticksOnTheBus, Teleop

# Send rates checked on the wall clock: never beside the hosts tests' three real-time stacks, which starve the rest of
# a two-core machine.
pytestmark = [pytest.mark.flight, pytest.mark.xdist_group("heavy_wall_clock")]

ALTITUDE = r"altitude (-?\d+\.\d) m above"


@pytest.fixture(scope="module")
def stack(tmp_path_factory: pytest.TempPathFactory) -> Iterator[RunningStack]:
    home = tmp_path_factory.mktemp("teleop")
    running = RunningStack(home, launch_profile(home / "profile"), "--realtime", "--quiet")
    try:
        running.wait_up()
        yield running
    finally:
        code = running.stop()
    assert code == 0, running.output
    assert "Traceback" not in running.output
    assert not wait_no_processes(home)


@pytest.fixture
def sticks(stack: RunningStack) -> Iterator[SticksOnTheBus]:
    bus = SticksOnTheBus(stack.home)
    yield bus
    bus.close()


@pytest.fixture
def teleop(stack: RunningStack) -> Iterator[list[Teleop]]:
    started: list[Teleop] = []
    yield started
    for t in started:
        t.close()


def position(t: Teleop) -> tuple[float, float]:
    north, east = t.wait_for(r"position N (-?\d+\.\d) E (-?\d+\.\d) m").groups()
    return float(north), float(east)


def wait_altitude(t: Teleop, ok: Callable[[float], bool], timeout: float) -> None:
    deadline = time.monotonic() + timeout
    while not ok(float(t.wait_for(ALTITUDE).group(1))):
        assert time.monotonic() < deadline, f"the altitude not as wanted within {timeout:g} s:\n{t.screen()}"
        time.sleep(0.1)


def land_and_disarm(t: Teleop, disarm: Callable[[], None]) -> None:
    """With the throttle down: on the ground and still, disarm (the land detector may have done it already)."""
    wait_altitude(t, lambda a: a < 0.3, 40.0)
    t.wait_for(r"climb [+-]0\.[01] m/s", 20.0)
    t.until_accepted(disarm, "disarm", 30.0)
    t.wait_for(r"vehicle: \w+, disarmed")


def test_a_flight_by_keyboard(stack: RunningStack, sticks: SticksOnTheBus, teleop: list[Teleop]) -> None:
    t = Teleop(stack.home)
    teleop.append(t)
    t.wait_for(r"sticks \(keyboard, stick limit 50 %\), sent at (4[5-9]|5[0-5]) Hz")
    assert "arrows pitch/roll, a/d yaw, w/s throttle" in t.screen()
    assert t.command(lambda: t.type("3"), "mode Altitude") == "accepted"
    t.until_accepted(lambda: t.type("m"), "arm")
    t.wait_for(r"vehicle: Altitude, armed")

    t.type("w", 30)  # throttle −1 → +0.5: climb
    t.wait_for(r"throttle \[-+\|#####-+\] \+0\.50")
    wait_altitude(t, lambda a: a > 3.0, 30.0)
    t.type(" ")  # centred: hold the altitude
    t.wait_for(r"throttle \[-+\|-+\] \+0\.00")
    t.wait_for(r"climb [+-]0\.[0-3] m/s", 10.0)

    assert t.command(lambda: t.type("4"), "mode Position") == "accepted"
    start = position(t)
    t.hold(b"\x1b[A", 2.5)  # forward
    assert re.search(r"pitch +\[-+\|#+-*\] \+0\.[3-5]", t.screen()), t.screen()
    t.wait_for(r"pitch +\[-+\|-+\] \+0\.00", 5.0)  # let go: springs back
    here = position(t)
    assert math.dist(start, here) > 3.0
    wait_altitude(t, lambda a: a > 2.0, 1.0)

    t.type("s", 25)  # down to −1: descend
    t.wait_for(r"throttle \[#+\|-+\] -1\.00")
    land_and_disarm(t, lambda: t.type("x"))

    t.type("q")
    assert t.exit_code() == 0
    assert t.terminal_restored()
    summary = re.search(r"\x1b\[\?1049lteleop: quit; \d+ setpoints sent in [\d.]+ s \(([\d.]+) Hz\)", t.output)
    assert summary, t.output
    # The live rate above is the sending check; this average over the whole session also counts the stalls of
    # a loaded machine, which the sender does not make up in a burst.
    assert 20.0 < float(summary[1]) < 55.0, summary[0]
    sticks.settle()
    last = sticks.messages[-1]
    assert (last["roll"], last["pitch"], last["yaw"], last["throttle"]) == (0.0, 0.0, 0.0, 0.0)  # Position
    span_s = (sticks.messages[-1]["timestamp"] - sticks.messages[0]["timestamp"]) / 1e6
    assert (len(sticks.messages) - 1) / span_s > 45.0


def test_a_flight_by_gamepad(stack: RunningStack, sticks: SticksOnTheBus, teleop: list[Teleop], tmp_path: Path) -> None:
    fifo = tmp_path / "js0"
    os.mkfifo(fifo)
    device = os.open(fifo, os.O_RDWR)  # a writer from the start, as a device is there before its reader

    def event(type_: int, number: int, value: int) -> None:
        os.write(device, JS_EVENT.pack(0, value, type_, number))

    for number in range(6):  # the state on opening: sticks centred but the throttle stick down
        event(JS_EVENT_AXIS | JS_EVENT_INIT, number, 32767 if number == 1 else 0)
    for number in range(11):
        event(JS_EVENT_BUTTON | JS_EVENT_INIT, number, 0)
    try:
        t = Teleop(stack.home, "--joystick", str(fifo))
        teleop.append(t)
        t.wait_for(rf"sticks \(gamepad {re.escape(str(fifo))}\), sent at")
        assert "buttons: 0 Position, 1 Altitude" in t.screen()
        sticks.wait_for(lambda m: m["throttle"] == -1.0)

        def press(button: int) -> None:
            event(JS_EVENT_BUTTON, button, 1)
            event(JS_EVENT_BUTTON, button, 0)

        assert t.command(lambda: press(0), "mode Position") == "accepted"  # A
        t.until_accepted(lambda: press(7), "arm")  # Start
        event(JS_EVENT_AXIS, 1, -16384)  # left stick half forward: climb
        event(JS_EVENT_AXIS, 0, 16384)  # left stick half right: yaw
        os.write(device, JS_EVENT.pack(0, 9, 0, 0)[:5])  # half a record, and a record of no known type
        os.write(device, JS_EVENT.pack(0, 9, 0, 0)[5:] + JS_EVENT.pack(0, 1, 0x40, 3))
        half = (16384 / 32767 - 0.05) / 0.95  # past joy_node's dead zone
        arrived = sticks.wait_for(lambda m: m["throttle"] > 0.0 and m["yaw"] > 0.0)  # the events are read one by one
        assert arrived["throttle"] == pytest.approx(half) and arrived["yaw"] == pytest.approx(half)
        assert (arrived["roll"], arrived["pitch"], arrived["valid"]) == (0.0, 0.0, True)
        wait_altitude(t, lambda a: a > 1.5, 30.0)

        event(JS_EVENT_AXIS, 0, 0)
        event(JS_EVENT_AXIS, 1, 32767)  # stick down: descend
        land_and_disarm(t, lambda: press(6))  # Back
    finally:
        os.close(device)  # unplugged
    # Lost, and looked for again: a FIFO without a writer opens, but has no state to tell.
    t.wait_for(r"gamepad \S+ (LOST: the device closed, looking for it again|waiting for its state)\), NOT sent")
    t.wait_for("log: Manual control lost")
    sent = len(sticks.messages)
    sticks.settle(0.5)
    assert len(sticks.messages) - sent <= 1  # nothing since

    t.type("\x03")  # Ctrl-C
    assert t.exit_code() == 130
    assert t.terminal_restored()
    assert t.output.rstrip().endswith("teleop: stopped by Ctrl-C")


def test_ctrl_d_quits_with_the_sticks_centred_but_a_thrust_throttle_where_it_was(
    stack: RunningStack, sticks: SticksOnTheBus, teleop: list[Teleop]
) -> None:
    t = Teleop(stack.home)
    teleop.append(t)
    t.wait_for(r"sent at \d+ Hz")
    sticks.wait_for(lambda m: True, timeout=30.0)  # the listener is up (it starts beside teleop)
    assert t.command(lambda: t.type("5"), "mode RotorS") == "accepted"
    t.type("w", 4)
    # What the sticks mean there, scaled as RotorS' joy.cpp scales them by the stack's RJOY_* parameters.
    t.holding(b"\x1b[C", r"RotorS: roll \+(?!0\.0)\d+\.\d°, pitch \+0\.0° \(nose up \+\), yaw rate \+0°/s, thrust \d")
    t.type("\x04")
    assert t.exit_code() == 0
    assert t.terminal_restored()
    sticks.settle()
    last = sticks.messages[-1]
    assert (last["roll"], last["pitch"], last["yaw"], last["throttle"]) == (0.0, 0.0, 0.0, -0.8)
