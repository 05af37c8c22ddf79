"""Position and Altitude modes: sticks to velocity, climb rate, yaw rate and tilt; position and altitude locks."""

from __future__ import annotations

import math

import pytest

from stack.mathlib.scalar import CONSTANTS_ONE_G
from stack.mathlib.vector import Vec3
from stack.msg.setpoints import ManualControlSetpoint
from stack.posctl.flight_task import TrajectoryCommand, VehicleState
from stack.posctl.manual_tasks import ManualAltitudeTask, ManualPositionTask, Sticks, heading_to_ned

DT = 0.02
NAN = math.nan
START: Vec3 = (1.0, 2.0, -5.0)


def sticks(pitch: float = 0.0, roll: float = 0.0, throttle: float = 0.0, yaw: float = 0.0) -> ManualControlSetpoint:
    """Valid sticks; all centred by default (throttle 0 is mid-stick)."""
    return ManualControlSetpoint(valid=True, pitch=pitch, roll=roll, throttle=throttle, yaw=yaw)


def state(position: Vec3 = START, velocity: Vec3 = (0.0, 0.0, 0.0), yaw: float = 0.0) -> VehicleState:
    return VehicleState(0, position, velocity, yaw, False, True)


def position_task(params: dict[str, object] | None = None, at: VehicleState | None = None) -> ManualPositionTask:
    task = ManualPositionTask(params or {})
    task.activate(at or state())
    return task


def altitude_task(at: VehicleState | None = None) -> ManualAltitudeTask:
    task = ManualAltitudeTask({})
    task.activate(at or state())
    return task


def fly(task: ManualAltitudeTask, manual: ManualControlSetpoint | None, at: VehicleState | None = None):
    return task.update(at or state(), manual, DT)


# ---------------------------------------------------------------------------------------------- sticks


def test_heading_to_ned_rotates_by_the_heading():
    assert heading_to_ned(1.0, 0.0, 0.0) == (1.0, 0.0)
    assert heading_to_ned(1.0, 0.0, math.pi / 2) == pytest.approx((0.0, 1.0))
    assert heading_to_ned(0.0, 1.0, math.pi / 2) == pytest.approx((-1.0, 0.0))
    assert heading_to_ned(1.0, 1.0, math.pi) == pytest.approx((-1.0, -1.0))


def test_sticks_apply_the_dead_zone_and_rescale_to_full_deflection():
    s = Sticks(sticks(pitch=0.55, roll=-0.55, throttle=0.1, yaw=1.0), 0.1)
    assert (s.forward, s.right, s.up, s.yaw) == pytest.approx((0.5, -0.5, 0.0, 1.0))
    s = Sticks(sticks(pitch=0.6), 0.2)
    assert s.forward == pytest.approx(0.5)


@pytest.mark.parametrize("manual", [None, ManualControlSetpoint(valid=False, pitch=1.0, roll=1.0, yaw=1.0)])
def test_missing_or_invalid_sticks_read_as_centred(manual):
    s = Sticks(manual, 0.1)
    assert (s.forward, s.right, s.up, s.yaw) == (0.0, 0.0, 0.0, 0.0)


# ---------------------------------------------------------------------------------------------- position mode


def test_centred_sticks_hold_the_position_where_the_mode_started():
    task = position_task()
    for _ in range(10):
        command = fly(task, sticks(), state(position=(1.3, 1.8, -5.2)))
        assert command.position == START
        assert command.velocity == (0.0, 0.0, 0.0)
        assert command.yaw == 0.0 and command.yawspeed == 0.0


def test_sticks_inside_the_dead_zone_still_hold():
    task = position_task()
    command = fly(task, sticks(pitch=0.09, roll=-0.09, throttle=0.1, yaw=0.05))
    assert command.position == START and command.velocity == (0.0, 0.0, 0.0) and command.yawspeed == 0.0


@pytest.mark.parametrize(
    ("pitch", "roll", "yaw", "velocity"),
    [
        (1.0, 0.0, 0.0, (10.0, 0.0)),  # full forward: MPC_VEL_MANUAL north
        (0.55, -0.55, 0.0, (5.0, -5.0)),  # half way past the 0.1 dead zone
        (1.0, 0.0, math.pi / 2, (0.0, 10.0)),  # heading east: forward is east
        (0.0, 1.0, math.pi / 2, (-10.0, 0.0)),  # heading east: right is south
    ],
)
def test_right_stick_commands_a_horizontal_velocity_in_the_heading_frame(pitch, roll, yaw, velocity):
    task = position_task(at=state(yaw=yaw))
    command = fly(task, sticks(pitch=pitch, roll=roll), state(yaw=yaw))
    assert command.velocity[:2] == pytest.approx(velocity)
    assert math.isnan(command.position[0]) and math.isnan(command.position[1])
    assert command.position[2] == START[2]  # the altitude stays locked


def test_mpc_vel_manual_and_mpc_hold_dz_set_the_stick_scale():
    task = position_task({"MPC_VEL_MANUAL": 4.0, "MPC_HOLD_DZ": 0.2})
    assert fly(task, sticks(pitch=0.6)).velocity[0] == pytest.approx(0.5 * 4.0)


@pytest.mark.parametrize(
    ("throttle", "vz"),
    [(1.0, -3.0), (0.55, -1.5), (-0.55, 0.75), (-1.0, 1.5)],  # MPC_Z_VEL_MAX_UP 3, MPC_Z_VEL_MAX_DN 1.5
)
def test_throttle_stick_commands_the_climb_rate(throttle, vz):
    command = fly(position_task(), sticks(throttle=throttle))
    assert command.velocity[2] == pytest.approx(vz)
    assert math.isnan(command.position[2])
    assert command.position[:2] == START[:2]


def test_yaw_stick_turns_at_up_to_mpc_man_y_max():
    task = position_task(at=state(yaw=3.0))
    commands = [fly(task, sticks(yaw=0.55)) for _ in range(50)]
    rate = 0.5 * math.radians(150.0)
    assert all(c.yawspeed == pytest.approx(rate) for c in commands)
    assert commands[-1].yaw == pytest.approx(3.0 + 50 * DT * rate - 2.0 * math.pi)  # wrapped into ±π


def test_released_stick_locks_only_once_slower_than_mpc_hold_max_xy():
    task = position_task()
    fly(task, sticks(pitch=1.0), state(velocity=(10.0, 0.0, 0.0)))
    braking = fly(task, sticks(), state(position=(20.0, 2.0, -5.0), velocity=(3.0, 0.0, 0.0)))
    assert math.isnan(braking.position[0]) and braking.velocity[:2] == (0.0, 0.0)
    slow = fly(task, sticks(), state(position=(22.0, 2.0, -5.0), velocity=(0.7, 0.0, 0.0)))
    assert slow.position == (22.0, 2.0, -5.0)
    drifted = fly(task, sticks(), state(position=(22.4, 2.1, -5.0), velocity=(0.1, 0.0, 0.0)))
    assert drifted.position == (22.0, 2.0, -5.0)


def test_released_throttle_locks_the_altitude_only_once_slower_than_mpc_hold_max_z():
    task = position_task()
    fly(task, sticks(throttle=1.0), state(velocity=(0.0, 0.0, -3.0)))
    climbing = fly(task, sticks(), state(position=(1.0, 2.0, -9.0), velocity=(0.0, 0.0, -1.0)))
    assert math.isnan(climbing.position[2]) and climbing.velocity[2] == 0.0
    slow = fly(task, sticks(), state(position=(1.0, 2.0, -9.5), velocity=(0.0, 0.0, -0.5)))
    assert slow.position[2] == -9.5
    assert fly(task, sticks(), state(position=(1.0, 2.0, -9.7))).position[2] == -9.5


def test_a_mode_entered_at_speed_brakes_before_it_locks():
    task = position_task(at=state(velocity=(8.0, 0.0, -2.0)))  # e.g. switching from a mission leg
    braking = fly(task, sticks(), state(position=(9.0, 2.0, -7.0), velocity=(3.0, 0.0, -1.0)))
    assert math.isnan(braking.position[0]) and math.isnan(braking.position[2])
    assert braking.velocity == (0.0, 0.0, 0.0)
    stopped = fly(task, sticks(), state(position=(11.0, 2.0, -7.5), velocity=(0.2, 0.0, 0.1)))
    assert stopped.position == (11.0, 2.0, -7.5)


def test_invalid_sticks_hold_even_when_deflected():
    task = position_task()
    command = fly(task, ManualControlSetpoint(valid=False, pitch=1.0, roll=1.0, throttle=1.0, yaw=1.0))
    assert command.position == START and command.velocity == (0.0, 0.0, 0.0) and command.yawspeed == 0.0
    assert fly(task, None).position == START


def test_position_lock_is_taken_once_the_position_is_valid_again():
    # Entered (or released) while the horizontal position was invalid: hold it as soon as it is known.
    task = position_task(at=state(position=(NAN, NAN, -5.0)))
    assert math.isnan(fly(task, sticks(), state(position=(NAN, NAN, -5.0))).position[0])
    assert fly(task, sticks(), state(position=(3.0, 4.0, -5.0))).position == (3.0, 4.0, -5.0)
    assert fly(task, sticks(), state(position=(3.2, 4.1, -5.0))).position == (3.0, 4.0, -5.0)
    fly(task, sticks(pitch=1.0), state(position=(NAN, NAN, -5.0)))
    fly(task, sticks(), state(position=(NAN, NAN, -5.0)))
    assert fly(task, sticks(), state(position=(8.0, 4.0, -5.0))).position == (8.0, 4.0, -5.0)


def test_altitude_lock_is_taken_once_the_altitude_is_valid_again():
    task = position_task(at=state(position=(1.0, 2.0, NAN)))
    assert math.isnan(fly(task, sticks(), state(position=(1.0, 2.0, NAN))).position[2])
    assert fly(task, sticks(), state(position=(1.0, 2.0, -6.0))).position[2] == -6.0
    assert fly(task, sticks(), state(position=(1.0, 2.0, -6.3))).position[2] == -6.0


def test_nan_heading_leaves_the_yaw_uncontrolled_without_failing():
    task = position_task(at=state(yaw=NAN))
    command = fly(task, sticks(pitch=1.0, yaw=1.0), state(yaw=NAN))
    assert math.isnan(command.yaw)
    assert command.yawspeed == pytest.approx(math.radians(150.0))


# ---------------------------------------------------------------------------------------------- altitude mode


def _horizontal_acceleration(command: TrajectoryCommand) -> tuple[float, float]:
    return command.acceleration[0], command.acceleration[1]


def test_altitude_mode_tilts_with_the_right_stick_up_to_mpc_man_tilt_max():
    task = altitude_task()
    full = fly(task, sticks(pitch=1.0, roll=0.55))
    g_tan = CONSTANTS_ONE_G * math.tan(math.radians(35.0))
    assert _horizontal_acceleration(full) == pytest.approx((g_tan, CONSTANTS_ONE_G * math.tan(math.radians(17.5))))
    assert all(math.isnan(v) for v in (*full.position[:2], *full.velocity[:2], full.acceleration[2]))
    assert full.position[2] == START[2] and full.velocity[2] == 0.0
    east = altitude_task(at=state(yaw=math.pi / 2))
    assert _horizontal_acceleration(fly(east, sticks(pitch=1.0))) == pytest.approx((0.0, g_tan))


def test_altitude_mode_centred_sticks_level_and_hold_the_altitude_only():
    task = altitude_task()
    command = fly(task, sticks(), state(position=(9.0, 9.0, -5.1)))
    assert _horizontal_acceleration(command) == (0.0, 0.0)
    assert math.isnan(command.position[0]) and command.position[2] == START[2]


def test_altitude_mode_throttle_commands_the_climb_rate():
    command = fly(altitude_task(), sticks(throttle=-0.55))
    assert command.velocity[2] == pytest.approx(0.75) and math.isnan(command.position[2])


def test_set_params_rescales_the_sticks():
    task = altitude_task()
    task.set_params({"MPC_MAN_TILT_MAX": 20.0, "MPC_Z_VEL_MAX_UP": 2.0})
    command = fly(task, sticks(pitch=1.0, throttle=1.0))
    assert command.acceleration[0] == pytest.approx(CONSTANTS_ONE_G * math.tan(math.radians(20.0)))
    assert command.velocity[2] == pytest.approx(-2.0)
