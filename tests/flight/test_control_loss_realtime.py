"""In real time a control module killed in flight is a failsafe, and never a flyaway (one flight).

In real time the vehicle flies on without the dead module until the supervisor restarts it (0.5 s and more), so
the commander acts: a dead rate controller is a loss of attitude control (flight termination: the motors stop and
the vehicle falls where it was), a dead position controller a loss of position control (the vehicle lands once the
restarted controller flies again). Both are named in ``vehicle_status``. The clock is the wall clock, so the
margins are wide. A vehicle terminated on the ground can be disarmed and flown again; a commander stopped for
3 s (SIGSTOP) catches up with its inputs before it judges them, and the hover goes on.
"""

from __future__ import annotations

import math
import os
import signal
import time
from collections.abc import Iterator
from pathlib import Path

import pytest

from stack.msg.system import VehicleStatus as NS
from tests.support.harness import RunningStack, takeoff_when_ready, wait_no_processes
from tests.support.hover import echo, kill, restarted, start_hovering, truth, wait

# A real-time stack at real-time priority: never beside the multi-host real-time flights (tests/hosts), each of
# which it would starve, as they would it.
pytestmark = [pytest.mark.flight, pytest.mark.xdist_group("heavy_wall_clock")]

ALTITUDE_M = 5.0


@pytest.fixture
def hovering(tmp_path: Path) -> Iterator[RunningStack]:
    stack = start_hovering(tmp_path, ALTITUDE_M)
    try:
        yield stack
    finally:
        code = stack.stop()
    assert code == 0 or "stopped" in stack.output, stack.output
    assert "Traceback" not in stack.output
    assert not wait_no_processes(tmp_path)


def test_a_stopped_commander_a_dead_rate_controller_then_a_dead_position_controller(hovering: RunningStack) -> None:
    """One real-time flight, three faults in turn. SIGSTOP of the commander for 3 s: its inputs are 3 s old when
    it runs again, yet nothing has failed and the hover goes on. A dead rate controller terminates the flight
    where it was; on the ground the vehicle is disarmed and flies again. A dead position controller then lands
    it where it was."""
    stack = hovering
    north, east, down = truth(stack)
    pid = stack.module_pids()["commander"]
    os.kill(pid, signal.SIGSTOP)
    time.sleep(3.0)
    os.kill(pid, signal.SIGCONT)
    time.sleep(3.0)
    status = echo(stack, "vehicle_status")
    assert (status["nav_state"], status["failsafe"]) == (NS.NAVIGATION_STATE_AUTO_LOITER, False), status
    assert "catching up" in (stack.run_dir() / "commander.log").read_text()
    here = truth(stack)
    assert math.hypot(here[0] - north, here[1] - east) < 1.0 and abs(here[2] - down) < 1.0

    north, east, _, _ = kill(stack, "mc_rate_control")
    wait(
        stack,
        lambda: echo(stack, "vehicle_status")["nav_state"] == NS.NAVIGATION_STATE_TERMINATION,
        10.0,
        "termination",
    )
    assert echo(stack, "vehicle_status")["control_lost_modules"] == ["mc_rate_control"]
    assert echo(stack, "actuator_armed")["termination"]
    wait(stack, lambda: -truth(stack)[2] < 0.5, 20.0, "the fall")
    wait(stack, lambda: restarted(stack, "mc_rate_control"), 30.0, "restart")
    down = truth(stack)
    assert math.hypot(down[0] - north, down[1] - east) < 5.0  # fell where it was: no flyaway
    assert -down[2] < 0.5
    # On the ground, its motors stopped, it is landed: disarmed (COM_DISARM_LAND), which clears the termination,
    # and it flies again.
    wait(stack, lambda: echo(stack, "vehicle_status")["arming_state"] == NS.ARMING_STATE_DISARMED, 30.0, "disarm")
    assert echo(stack, "vehicle_status")["nav_state"] != NS.NAVIGATION_STATE_TERMINATION
    assert "Flight termination cleared" in (stack.run_dir() / "commander.log").read_text()
    again = takeoff_when_ready(stack, "--alt", "3")
    assert again.returncode == 0, again.stderr

    north, east, _, _ = kill(stack, "mc_pos_control")
    wait(stack, lambda: echo(stack, "vehicle_status")["nav_state"] == NS.NAVIGATION_STATE_AUTO_LAND, 10.0, "Land")
    wait(stack, lambda: restarted(stack, "mc_pos_control"), 30.0, "restart")
    wait(stack, lambda: echo(stack, "vehicle_status")["arming_state"] == NS.ARMING_STATE_DISARMED, 60.0, "landing")
    down = truth(stack)
    assert math.hypot(down[0] - north, down[1] - east) < 5.0
    assert -down[2] < 0.5
