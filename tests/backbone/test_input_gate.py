"""What a module never sees: a value its message type does not allow (NaN in a state, infinity anywhere it
does not mean "unlimited"), and a message from a publisher that is not a module of its vehicle on a topic not
open to tools. Either is counted, and the last good message stays the latest."""

from __future__ import annotations

import math

import pytest

from stack.bus.access import OPEN_TO_TOOLS, Access, tool_may_publish
from stack.bus.node import stable_publisher_id
from stack.bus.topics import Received
from stack.msg.actuators import ActuatorMotors
from stack.msg.estimation import VehicleAttitude, VehicleLocalPosition
from stack.msg.fixedwing import PositionSetpoint, PositionSetpointTriplet
from stack.msg.navigation import Mission, MissionItemEntry
from stack.msg.registry import TOPICS
from stack.msg.sensors import SensorGps, SensorGyro
from stack.msg.setpoints import HoverThrustEstimate, TrajectorySetpoint
from stack.msg.system import VehicleCommand
from stack.msg.validity import refusal
from stack.runtime.inputs import InputBuffer
from stack.supervisor.profile import load_profile

NAN, INF = math.nan, math.inf


@pytest.mark.parametrize("topic", sorted(TOPICS))
def test_every_message_as_defined_is_allowed(topic: str) -> None:
    assert refusal(TOPICS[topic].type()) is None


@pytest.mark.parametrize(
    ("msg", "why"),
    [
        (VehicleLocalPosition(z=NAN), "z = nan"),
        (VehicleLocalPosition(vx=-INF), "vx = -inf"),
        (VehicleLocalPosition(vxy_max=NAN), "vxy_max = nan"),  # infinite when unlimited, never NaN
        (SensorGps(vel_d_m_s=INF), "vel_d_m_s = inf"),  # NaN when not reported, never infinite
        (VehicleAttitude(q=(1.0, 0.0, INF, 0.0)), "q[2] = inf"),
        (SensorGyro(x=NAN), "x = nan"),
        (HoverThrustEstimate(hover_thrust=INF), "hover_thrust = inf"),
        (TrajectorySetpoint(velocity=(0.0, INF, 0.0)), "velocity[1] = inf"),
        (ActuatorMotors(control=(INF,) * 12), "control[0] = inf"),
        (PositionSetpointTriplet(current=PositionSetpoint(x=-INF)), "current.x = -inf"),
        (Mission(items=[MissionItemEntry(), MissionItemEntry(hold_time=NAN)]), "items[1].hold_time = nan"),
    ],
)
def test_a_value_the_type_does_not_allow_is_named(msg: object, why: str) -> None:
    assert refusal(msg) == why


@pytest.mark.parametrize(
    "msg",
    [
        VehicleLocalPosition(x=1.0, y=-2.0, z=-5.0, vxy_max=INF, eph=0.5),  # unlimited, and a real accuracy
        VehicleLocalPosition(x=1e308, y=1e308),  # finite, though their sum is not
        SensorGyro(x=0.1, temperature=NAN),  # an unknown temperature
        SensorGps(vel_d_m_s=NAN, cog_rad=NAN),  # not in MAVLink's GPS_RAW_INT
        VehicleLocalPosition(eph=NAN, epv=NAN),  # not in MAVLink's LOCAL_POSITION_NED
        HoverThrustEstimate(hover_thrust=NAN),  # no estimate yet
        TrajectorySetpoint(position=(NAN, NAN, -5.0), yaw=NAN),  # PX4's "not controlled"
        ActuatorMotors(control=(NAN,) * 12),  # motors stopped
        PositionSetpointTriplet(current=PositionSetpoint(x=1.0, y=2.0, z=NAN)),
        VehicleCommand(command=176, param1=INF),  # the commander refuses it, saying why
    ],
)
def test_what_a_value_may_mean_is_allowed(msg: object) -> None:
    assert refusal(msg) is None


class _Sub:
    suffix = "vehicle_local_position/0"

    def __init__(self) -> None:
        self.items: list[tuple] = []

    def poll(self):
        return self.items.pop(0) if self.items else None


MEMBER = stable_publisher_id("v1", "local_position_estimator")
STRANGER = 0x5EED


def test_an_input_keeps_the_last_good_message_and_counts_the_rest() -> None:
    buf = InputBuffer(_Sub(), False)
    buf.members = frozenset({MEMBER})
    good = VehicleLocalPosition(z=-5.0)
    buf.sub.items += [Received(-1, MEMBER, 1, good, 1), Received(-1, MEMBER, 2, VehicleLocalPosition(z=NAN), 2)]
    buf.sub.items += [Received(-1, STRANGER, 1, VehicleLocalPosition(z=-10.0), 1)]
    buf.pull()
    buf.promote_all()
    assert buf.latest is good and (buf.invalid, buf.unauthorized) == (1, 1)
    # In lockstep the same: the barrier still counts each message as received.
    buf.sub.items += [
        Received(10, MEMBER, 3, VehicleLocalPosition(z=INF), 3),
        Received(-1, STRANGER, 2, VehicleLocalPosition(), 2),
    ]
    buf.pull()
    buf.promote_visible(20, -1, 0, frozenset({MEMBER}))
    assert buf.latest is good and (buf.invalid, buf.unauthorized) == (2, 2) and buf.last_index[MEMBER] == 3


def test_a_module_of_the_vehicle_is_heard_only_on_the_topics_it_declares() -> None:
    access = Access.of("v1", load_profile("sitl_quad").publishers())
    assert access.publishers_of("vehicle_local_position") == {MEMBER}
    buf = InputBuffer(_Sub(), False)
    buf.members = access.publishers_of("vehicle_local_position")
    estimate, rate_control = VehicleLocalPosition(z=-5.0), stable_publisher_id("v1", "mc_rate_control")
    buf.sub.items += [Received(-1, MEMBER, 1, estimate, 1), Received(-1, rate_control, 1, VehicleLocalPosition(), 1)]
    buf.pull()
    buf.promote_all()
    assert buf.latest is estimate and buf.unauthorized == 1


def test_an_offboard_setpoint_from_a_tool_is_heard_only_in_offboard() -> None:
    offboard = [False]
    buf = InputBuffer(_Sub(), True)
    buf.members, buf.open_while = frozenset({MEMBER}), lambda: offboard[0]
    buf.sub.items.append(Received(-1, STRANGER, 1, TrajectorySetpoint(position=(0.0, 0.0, -3.0)), 1))
    buf.pull()
    buf.promote_all()
    assert buf.take() == [] and buf.unauthorized == 1
    offboard[0] = True
    buf.sub.items.append(Received(-1, STRANGER, 2, TrajectorySetpoint(position=(0.0, 0.0, -3.0)), 2))
    buf.pull()
    buf.promote_all()
    assert len(buf.take()) == 1 and buf.unauthorized == 1


def test_who_may_publish_what() -> None:
    modules = {"commander": ["vehicle_status"], "mc_pos_control": ["takeoff_status", "vehicle_attitude_setpoint"]}
    access = Access.of("v1", modules, ["telemetry_status"])
    assert access.publishers_of("takeoff_status") == {stable_publisher_id("v1", "mc_pos_control")}
    assert access.publishers_of("vehicle_status") == {stable_publisher_id("v1", "commander")}
    assert access.publishers_of("vehicle_attitude") == set()
    assert [access.rule(t) for t in ("vehicle_attitude", "vehicle_command", "trajectory_setpoint")] == [
        "members",
        "anyone",
        "offboard",
    ]
    assert access.rule("telemetry_status") == "anyone" and access.rule("offboard_control_mode") == "anyone"
    assert {
        "vehicle_command", "manual_control_setpoint", "mission", "offboard_control_mode", "trajectory_setpoint",
        "vehicle_attitude_setpoint", "vehicle_rates_setpoint", "vehicle_torque_setpoint", "vehicle_thrust_setpoint",
        "actuator_motors",
    } == OPEN_TO_TOOLS  # fmt: skip
    assert all(tool_may_publish(t) for t in OPEN_TO_TOOLS)
    assert not tool_may_publish("vehicle_local_position") and tool_may_publish("telemetry_status", ["telemetry_status"])
