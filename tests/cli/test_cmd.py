"""`stack cmd` against the first-flight stack (the default profile without position estimation and
navigation): the commander's acknowledgements, refusals with their reasons, and input refused before
anything is sent."""

import json
import time

import pytest

from tests.support.harness import REPO, RunningStack, attitude_only_profile, run_cli, wait_no_processes

NOWHERE = "tcp/127.0.0.1:9"
"""An endpoint nothing listens on: a command that reaches for the bus cannot succeed there."""


@pytest.fixture(scope="module")
def stack(tmp_path_factory):
    tmp = tmp_path_factory.mktemp("cmd")
    home = tmp / "home"
    running = RunningStack(home, attitude_only_profile(tmp / "first_flight.toml"), "--quiet", "--speed", "1")
    running.wait_up()
    wait_sim_time(running, 10.0)
    yield running
    assert running.stop() == 0
    assert not wait_no_processes(home)


def wait_sim_time(stack: RunningStack, seconds: float) -> None:
    """Let the lockstep simulation run past ``seconds``: without a vertical velocity estimate the land
    detector only reports landed once minimum thrust has been held for 8 s, and disarming needs landed."""
    deadline = time.monotonic() + 120.0
    while time.monotonic() < deadline:
        out = stack.cli("topic", "echo", "vehicle_status", "-n", "1", "--field", "timestamp")
        if out.returncode == 0 and int(out.stdout) >= seconds * 1e6:
            return
    raise AssertionError(f"the simulation did not reach {seconds:g} s")


def refused(out, code: int = 1) -> str:
    """The one line a refused command prints (on stderr), after checking its exit code."""
    assert out.returncode == code, (out.stdout, out.stderr)
    assert "accepted" not in out.stdout
    lines = out.stderr.strip().splitlines()
    assert len(lines) == 1, out.stderr
    return lines[0]


def test_arm_then_disarm_are_accepted(stack):
    armed = stack.cli("cmd", "arm")
    assert armed.returncode == 0, armed.stderr
    assert armed.stdout.strip() == "arm: accepted"
    disarmed = stack.cli("cmd", "disarm")
    assert disarmed.returncode == 0, disarmed.stderr
    assert disarmed.stdout.strip() == "disarm: accepted"


def test_modes_by_px4_name(stack):
    assert stack.cli("cmd", "mode", "acro").stdout.strip() == "mode Acro: accepted"
    assert stack.cli("cmd", "mode", "stabilized").stdout.strip() == "mode Stabilized: accepted"
    status = json.loads(stack.cli("topic", "echo", "vehicle_status", "-n", "1", "--json").stdout)
    assert status["nav_state"] == 15  # NAVIGATION_STATE_STAB
    offboard = refused(stack.cli("cmd", "mode", "offboard"))
    assert offboard.startswith("mode Offboard: TEMPORARILY_REJECTED: ") and "no offboard signal" in offboard


def test_unknown_mode_is_refused_before_sending(stack):
    line = refused(stack.cli("cmd", "mode", "bogus"), code=2)
    assert line.startswith("error: unknown mode 'bogus' (valid: manual, stabilized, acro,")
    assert "auto:loiter" in line and "nothing sent" in line
    # Refused without touching the bus: the same answer where no stack could be reached.
    unreachable = run_cli(stack.home, "cmd", "mode", "bogus", "--endpoint", NOWHERE)
    assert refused(unreachable, code=2) == line


def test_takeoff_without_a_position_estimate_is_rejected_with_the_reason(stack):
    line = refused(stack.cli("cmd", "takeoff", "--alt", "5"))
    assert line.startswith("takeoff: TEMPORARILY_REJECTED: ") and "local position" in line


def test_goto_while_landed_is_rejected(stack):
    line = refused(stack.cli("cmd", "goto", "10", "0", "-5", "--yaw", "-90"))
    assert line == "goto: TEMPORARILY_REJECTED: Reposition denied: the vehicle is not flying"


def test_return_needs_an_armed_vehicle(stack):
    for name in ("rtl", "return"):
        line = refused(stack.cli("cmd", name))
        assert line.startswith("rtl: TEMPORARILY_REJECTED: ") and "disarmed" in line
    assert refused(stack.cli("cmd", "land")).startswith("land: TEMPORARILY_REJECTED: ")
    # The commander logs refusals by the command's MAVLink name.
    log = (stack.run_dir() / "commander.log").read_text()
    assert "command NAV_LAND (21) refused: " in log and "command NAV_RETURN_TO_LAUNCH (20) refused: " in log


def test_the_commander_denies_out_of_range_parameters(stack):
    low = refused(stack.cli("cmd", "takeoff", "--alt", "-5"))
    assert low == "takeoff: DENIED: Takeoff: -5.0 m above home is outside MIS_TAKEOFF_ALT's range (0, 80] m"
    far = refused(stack.cli("cmd", "goto", "--lat", "100", "--lon", "8"))
    assert far == "goto: DENIED: Reposition: latitude 100 is outside ±90°"


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (("goto", "nan", "0", "-5"), "error: north must be a finite number, got nan; nothing sent"),
        (("goto", "10", "0", "-5", "--speed", "inf"), "error: --speed must be a finite number, got inf; nothing sent"),
        (("takeoff", "--alt", "-inf"), "error: --alt must be a finite number, got -inf; nothing sent"),
        (("goto", "10", "0"), "error: give the target as N E D (metres, local NED) or as --lat/--lon [--alt]"),
        (("goto", "1", "2", "3", "--lat", "47"), "error: a global target needs both --lat and --lon (and no N E D)"),
    ],
)
def test_unusable_numbers_are_refused_before_sending(stack, args, message):
    line = refused(run_cli(stack.home, "cmd", *args, "--endpoint", NOWHERE), code=2)
    assert line.startswith(message)


def test_a_broken_mission_file_is_one_line_naming_it(stack, tmp_path):
    broken = tmp_path / "broken.txt"
    broken.write_text("takeoff 5\n10 0 -5\nwaypoint 10 ten -5\n")
    line = refused(stack.cli("cmd", "mission", str(broken)), code=2)
    assert line == f"error: {broken}: line 3 (item 2): east must be a number, got 'ten'"
    missing = refused(stack.cli("cmd", "mission", str(tmp_path / "nope.plan")), code=2)
    assert missing.startswith(f"error: {tmp_path / 'nope.plan'}: no such mission file; the shipped missions are ")
    assert refused(stack.cli("cmd", "mission", "boxx"), code=2).startswith(
        "error: boxx: no such mission file (did you mean box?); the shipped missions are box.plan, box.txt,"
    )


def test_a_global_mission_needs_the_vehicle_home(stack):
    plan = REPO / "tests" / "mission" / "data" / "square.plan"
    line = refused(stack.cli("cmd", "mission", str(plan)), code=2)
    assert line.startswith(f"error: {plan}: the vehicle has no home position yet")


def test_a_mission_without_a_navigator_gets_no_answer(stack, tmp_path):
    waypoints = tmp_path / "square.txt"
    waypoints.write_text("takeoff 5\n10 0 -5\n10 10 -5\nland\n")
    line = refused(stack.cli("cmd", "mission", str(waypoints), "--timeout", "1"))
    assert line.startswith("error: no answer from the navigator (is flight_mode_manager running?)")
