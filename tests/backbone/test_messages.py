"""The message catalogue: PX4 names, compact encoding, stable schema fingerprints."""

import math

import msgspec
import pytest

from stack.cli.message_json import parse_message
from stack.msg.base import Message
from stack.msg.registry import TOPICS, fingerprint, message_type, schema_text

REQUIRED = [
    "sensor_gyro",
    "sensor_accel",
    "sensor_mag",
    "sensor_baro",
    "sensor_gps",
    "vehicle_angular_velocity",
    "vehicle_attitude",
    "vehicle_local_position",
    "vehicle_global_position",
    "vehicle_attitude_setpoint",
    "vehicle_rates_setpoint",
    "vehicle_torque_setpoint",
    "vehicle_thrust_setpoint",
    "actuator_motors",
    "actuator_outputs",
    "control_allocator_status",
    "rate_ctrl_status",
    "trajectory_setpoint",
    "vehicle_control_mode",
    "vehicle_status",
    "actuator_armed",
    "manual_control_setpoint",
    "vehicle_command",
    "vehicle_command_ack",
    "parameter_update",
    "sim_groundtruth",
]


def test_catalogue_has_the_px4_topics():
    missing = [t for t in REQUIRED if t not in TOPICS]
    assert not missing


@pytest.mark.parametrize("topic", sorted(TOPICS))
def test_every_message_starts_with_timestamp_and_round_trips(topic):
    msg_type = TOPICS[topic].type
    assert msg_type.__struct_fields__[0] == "timestamp"
    msg = msg_type(timestamp=123)
    data = msgspec.msgpack.encode(msg)
    assert data[0] & 0xF0 in (0x90, 0xD0) or data[0] == 0xDC  # a msgpack array, not a map
    back = msgspec.msgpack.decode(data, type=msg_type)
    assert msgspec.structs.asdict(back).keys() == msgspec.structs.asdict(msg).keys()
    assert back.timestamp == 123


def test_array_encoding_is_compact():
    from stack.msg.estimation import VehicleAttitude

    msg = VehicleAttitude(timestamp=10**9, timestamp_sample=10**9, q=(1.0, 0.0, 0.0, 0.0))
    assert len(msgspec.msgpack.encode(msg)) < len(msgspec.msgpack.encode(msgspec.structs.asdict(msg)))


def test_fingerprints_are_stable_and_distinct():
    # Golden value: changing VehicleAttitude's wire schema must change this on purpose.
    attitude = message_type("vehicle_attitude")
    assert schema_text(attitude) == (
        "VehicleAttitude(timestamp:int,timestamp_sample:int,q:tuple[float,float,float,float],"
        "delta_q_reset:tuple[float,float,float,float],quat_reset_counter:int)"
    )
    types = {t.type for t in TOPICS.values()}
    assert len({fingerprint(t) for t in types}) == len(types)


def test_a_changed_definition_gets_another_fingerprint():
    class V1(Message):
        roll: float = 0.0

    class V1Renamed(Message):
        pitch: float = 0.0

    class V1Appended(Message):
        roll: float = 0.0
        pitch: float = 0.0

    V1Renamed.__name__ = V1Appended.__name__ = "V1"
    assert len({fingerprint(V1), fingerprint(V1Renamed), fingerprint(V1Appended)}) == 3


def test_pub_json_is_checked_against_the_schema():
    msg = parse_message("vehicle_rates_setpoint", '{"roll": 0.1, "thrust_body": [0, 0, -0.5], "yaw": NaN}')
    assert msg.roll == 0.1 and msg.thrust_body == (0.0, 0.0, -0.5) and math.isnan(msg.yaw)
    for bad, why in (
        ('{"rol": 0.1}', "unknown field `rol`"),
        ('{"roll": "fast"}', "Expected `float`, got `str`"),
        ('{"thrust_body": [0, 0]}', "length 3"),
        ("[1, 2]", "expected a JSON object"),
        ("{roll: 1}", "not valid JSON"),
    ):
        with pytest.raises(ValueError, match=why):
            parse_message("vehicle_rates_setpoint", bad)
