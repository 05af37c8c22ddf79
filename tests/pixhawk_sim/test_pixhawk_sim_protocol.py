"""The simulated Pixhawk's MAVLink behaviour on simulated time: streams, commands and their ACKs, telemetry."""

from __future__ import annotations

import itertools
import math
from collections import Counter

import pytest
from pymavlink.dialects.v20 import common as mavlink

from stack.airframe.model import load_vehicle
from stack.mathlib import quaternion as quat
from stack.mathlib.geo import MapProjection
from stack.mavlink import px4_modes
from stack.mavlink.px4_modes import Px4Mode
from stack.pixhawk_sim.params import parameter_values
from stack.pixhawk_sim.protocol import STREAM_RATES_HZ, Px4Protocol, stream_scheduler
from stack.pixhawk_sim.telemetry import Telemetry
from stack.pixhawk_sim.vehicle import SimulatedPixhawk
from stack.sim.sensors import ImuSample

GCS = (255, 190)


class Bench:
    """A simulated Pixhawk and its protocol, the messages it sends collected."""

    def __init__(self, **params: object) -> None:
        model = load_vehicle("sih_quad")
        self.vehicle = SimulatedPixhawk(model, parameter_values(model, params), seed=1)
        self.sent: list[mavlink.MAVLink_message] = []
        self.protocol = Px4Protocol(self.vehicle, self.sent.append)
        self.mav = mavlink.MAVLink(None, srcSystem=GCS[0], srcComponent=GCS[1])

    def run(self, seconds: float, each_step=None) -> None:
        for _ in range(round(seconds * 250)):
            if each_step is not None:
                each_step()
            self.vehicle.step()
            self.protocol.publish()

    def receive(self, msg: mavlink.MAVLink_message) -> None:
        """Deliver a message as the link would: packed by the GCS, decoded here."""
        self.protocol.handle(self.mav.decode(bytearray(msg.pack(self.mav))))

    def command(self, command: int, *params: float, target: tuple[int, int] = (1, 1)) -> list:
        self.sent.clear()
        p = list(params) + [0.0] * (7 - len(params))
        self.receive(mavlink.MAVLink_command_long_message(*target, command, 0, *p))
        return list(self.sent)

    def ack(self, command: int, *params: float) -> int:
        replies = self.command(command, *params)
        acks = [m for m in replies if m.get_msgId() == mavlink.MAVLINK_MSG_ID_COMMAND_ACK]
        assert len(acks) == 1 and acks[0].command == command
        assert (acks[0].target_system, acks[0].target_component) == GCS
        assert replies[-1] is acks[0]
        return acks[0].result

    def rates(self, thrust: float, rates=(0.0, 0.0, 0.0)) -> None:
        self.receive(mavlink.MAVLink_set_attitude_target_message(0, 1, 1, 128, [1, 0, 0, 0], *rates, thrust))

    def attitude(self, q, thrust: float) -> None:
        self.receive(mavlink.MAVLink_set_attitude_target_message(0, 1, 1, 7, list(q), 0.0, 0.0, 0.0, thrust))

    def take(self, msg_id: int) -> list:
        return [m for m in self.sent if m.get_msgId() == msg_id]


def test_default_stream_rates_are_px4_onboard_rates() -> None:
    bench = Bench()
    bench.run(10.0)
    counts = Counter(m.get_msgId() for m in bench.sent)
    for msg_id, rate in STREAM_RATES_HZ.items():
        if msg_id == mavlink.MAVLINK_MSG_ID_GPS_RAW_INT:
            assert counts[msg_id] == pytest.approx(100, abs=2)  # every GPS sample (10 Hz)
        else:
            assert counts[msg_id] == pytest.approx(rate * 10.0, abs=1.01), mavlink.mavlink_map[msg_id].msgname


def test_every_stream_has_a_builder() -> None:
    bench = Bench()
    assert set(stream_scheduler().streams()) <= set(Telemetry(bench.vehicle).builders)


def test_set_message_interval_changes_disables_and_restores_a_stream() -> None:
    bench = Bench()
    imu = mavlink.MAVLINK_MSG_ID_HIGHRES_IMU
    assert bench.ack(mavlink.MAV_CMD_SET_MESSAGE_INTERVAL, imu, 4000) == mavlink.MAV_RESULT_ACCEPTED
    bench.sent.clear()
    bench.run(2.0)
    assert len(bench.take(imu)) == 500  # every IMU sample
    assert bench.ack(mavlink.MAV_CMD_SET_MESSAGE_INTERVAL, imu, 1000) == mavlink.MAV_RESULT_ACCEPTED
    bench.sent.clear()
    bench.run(2.0)
    assert len(bench.take(imu)) == 500  # faster than the sensor: still one per sample
    assert bench.ack(mavlink.MAV_CMD_SET_MESSAGE_INTERVAL, imu, -1) == mavlink.MAV_RESULT_ACCEPTED
    bench.sent.clear()
    bench.run(1.0)
    assert bench.take(imu) == []
    assert bench.ack(mavlink.MAV_CMD_SET_MESSAGE_INTERVAL, imu, 0) == mavlink.MAV_RESULT_ACCEPTED
    bench.sent.clear()
    bench.run(2.0)
    assert len(bench.take(imu)) == pytest.approx(100, abs=1)
    replies = bench.command(mavlink.MAV_CMD_GET_MESSAGE_INTERVAL, imu)
    assert replies[0].get_msgId() == mavlink.MAVLINK_MSG_ID_MESSAGE_INTERVAL and replies[0].interval_us == 20000


@pytest.mark.parametrize(
    "params",
    [
        (mavlink.MAVLINK_MSG_ID_HEARTBEAT, 100000),  # PX4 refuses HEARTBEAT
        (mavlink.MAVLINK_MSG_ID_RC_CHANNELS, 100000),  # not a stream here
        (mavlink.MAVLINK_MSG_ID_HIGHRES_IMU, 4000, 0, 0, 0, 0, 1),  # a response target
    ],
)
def test_set_message_interval_failures(params: tuple) -> None:
    assert Bench().ack(mavlink.MAV_CMD_SET_MESSAGE_INTERVAL, *params) == mavlink.MAV_RESULT_FAILED


def test_request_message_sends_it_before_the_ack() -> None:
    bench = Bench()
    bench.run(0.2)
    replies = bench.command(mavlink.MAV_CMD_REQUEST_MESSAGE, mavlink.MAVLINK_MSG_ID_AUTOPILOT_VERSION)
    version, ack = replies
    assert version.get_msgId() == mavlink.MAVLINK_MSG_ID_AUTOPILOT_VERSION
    assert version.capabilities & mavlink.MAV_PROTOCOL_CAPABILITY_MAVLINK2
    assert version.flight_sw_version >> 24 == 1 and ack.result == mavlink.MAV_RESULT_ACCEPTED
    gps = bench.command(mavlink.MAV_CMD_REQUEST_MESSAGE, mavlink.MAVLINK_MSG_ID_GPS_RAW_INT)
    assert gps[0].get_msgId() == mavlink.MAVLINK_MSG_ID_GPS_RAW_INT  # the latest, though already streamed
    assert bench.ack(mavlink.MAV_CMD_REQUEST_MESSAGE, 12345) == mavlink.MAV_RESULT_FAILED
    replies = bench.command(mavlink.MAV_CMD_REQUEST_AUTOPILOT_CAPABILITIES, 1)
    assert [m.get_msgId() for m in replies] == [
        mavlink.MAVLINK_MSG_ID_AUTOPILOT_VERSION,
        mavlink.MAVLINK_MSG_ID_COMMAND_ACK,
    ]


def test_every_command_is_acked_and_unknown_ones_are_unsupported() -> None:
    bench = Bench()
    assert bench.ack(mavlink.MAV_CMD_DO_MOTOR_TEST, 1, 0, 0.1, 1) == mavlink.MAV_RESULT_UNSUPPORTED
    assert bench.ack(mavlink.MAV_CMD_NAV_TAKEOFF) == mavlink.MAV_RESULT_UNSUPPORTED
    assert bench.command(mavlink.MAV_CMD_COMPONENT_ARM_DISARM, 1, target=(2, 1)) == []  # not addressed to it
    assert bench.ack(mavlink.MAV_CMD_COMPONENT_ARM_DISARM, 2) == mavlink.MAV_RESULT_DENIED
    # COMMAND_INT is answered the same way.
    bench.sent.clear()
    bench.receive(
        mavlink.MAVLink_command_int_message(
            1, 1, 0, mavlink.MAV_CMD_SET_MESSAGE_INTERVAL, 0, 0, 31, 10000, 0, 0, 0, 0, 0
        )
    )
    assert [(m.command, m.result) for m in bench.sent] == [(mavlink.MAV_CMD_SET_MESSAGE_INTERVAL, 0)]


def test_arming_refusal_is_acked_with_a_statustext_reason() -> None:
    bench = Bench()
    bench.run(0.1)
    replies = bench.command(mavlink.MAV_CMD_COMPONENT_ARM_DISARM, 1)
    text, ack = replies
    assert text.get_msgId() == mavlink.MAVLINK_MSG_ID_STATUSTEXT and text.severity == mavlink.MAV_SEVERITY_CRITICAL
    assert text.text == "Arming denied: no manual control input for POSCTL"
    assert ack.result == mavlink.MAV_RESULT_TEMPORARILY_REJECTED


def test_long_statustext_is_sent_in_chunks() -> None:
    bench = Bench()
    bench.protocol.statustext(mavlink.MAV_SEVERITY_INFO, "x" * 120)
    chunks = bench.take(mavlink.MAVLINK_MSG_ID_STATUSTEXT)
    assert [c.chunk_seq for c in chunks] == [0, 1, 2] and len({c.id for c in chunks}) == 1 and chunks[0].id
    assert "".join(c.text for c in chunks) == "x" * 120


def test_heartbeat_reports_px4_mode_armed_state_and_status() -> None:
    bench = Bench()
    hb = bench.protocol.heartbeat()
    assert hb["type"] == mavlink.MAV_TYPE_QUADROTOR and hb["autopilot"] == mavlink.MAV_AUTOPILOT_PX4
    assert px4_modes.decode(hb["custom_mode"]) is Px4Mode.POSCTL
    assert hb["system_status"] == mavlink.MAV_STATE_STANDBY
    assert hb["base_mode"] & mavlink.MAV_MODE_FLAG_CUSTOM_MODE_ENABLED
    assert not hb["base_mode"] & mavlink.MAV_MODE_FLAG_SAFETY_ARMED
    bench.rates(0.0)
    mode = px4_modes.Px4Mode.OFFBOARD
    assert bench.ack(mavlink.MAV_CMD_DO_SET_MODE, 1, mode.main_mode, mode.sub_mode) == mavlink.MAV_RESULT_ACCEPTED
    assert bench.ack(mavlink.MAV_CMD_COMPONENT_ARM_DISARM, 1) == mavlink.MAV_RESULT_ACCEPTED
    hb = bench.protocol.heartbeat()
    assert px4_modes.decode(hb["custom_mode"]) is Px4Mode.OFFBOARD
    assert hb["base_mode"] & mavlink.MAV_MODE_FLAG_SAFETY_ARMED
    assert not hb["base_mode"] & mavlink.MAV_MODE_FLAG_STABILIZE_ENABLED  # body rates: attitude not controlled
    assert hb["system_status"] == mavlink.MAV_STATE_ACTIVE
    bench.run(1.5)  # the stream stopped: failsafe
    hb = bench.protocol.heartbeat()
    assert px4_modes.decode(hb["custom_mode"]) is Px4Mode.AUTO_LOITER
    assert hb["system_status"] == mavlink.MAV_STATE_CRITICAL
    assert hb["base_mode"] & mavlink.MAV_MODE_FLAG_AUTO_ENABLED


def test_highres_imu_carries_the_sensors_with_the_boot_time_of_the_sample() -> None:
    bench = Bench()
    bench.ack(mavlink.MAV_CMD_SET_MESSAGE_INTERVAL, mavlink.MAVLINK_MSG_ID_HIGHRES_IMU, 4000)
    bench.vehicle.skip(1_000_000)  # the wall clock ran ahead by 1 s
    bench.sent.clear()
    bench.run(1.0)
    imus = bench.take(mavlink.MAVLINK_MSG_ID_HIGHRES_IMU)
    assert len(imus) == 250
    times = [m.time_usec for m in imus]
    assert times[0] == 1_000_000 + 4000 and all(b - a == 4000 for a, b in itertools.pairwise(times))
    last = bench.vehicle.samples[ImuSample]
    assert imus[-1].time_usec == last.boot_us == bench.vehicle.time_us
    assert imus[-1].xgyro == pytest.approx(last.value.gyro[0], abs=1e-6)
    assert imus[-1].zacc == pytest.approx(-9.81, abs=0.3)  # at rest: the specific force points up
    mags = [m for m in imus if m.fields_updated & mavlink.HIGHRES_IMU_UPDATED_XMAG]
    baros = [m for m in imus if m.fields_updated & mavlink.HIGHRES_IMU_UPDATED_ABS_PRESSURE]
    assert len(mags) == pytest.approx(50, abs=1) and len(baros) == pytest.approx(20, abs=1)
    assert all(m.fields_updated & 0x3F == 0x3F for m in imus)
    assert 950.0 < imus[-1].abs_pressure < 970.0  # hPa at SIH's 489 m home


def test_the_battery_is_px4s_simulated_pack_with_no_current_sensor() -> None:
    bench = Bench()
    bench.run(1.0)
    status = bench.take(mavlink.MAVLINK_MSG_ID_SYS_STATUS)[-1]
    battery = bench.take(mavlink.MAVLINK_MSG_ID_BATTERY_STATUS)[-1]
    # Full and at rest: 4 cells at BAT1_V_CHARGED; the current and the charge drawn unknown (-1), as PX4 sends them.
    assert (status.voltage_battery, status.current_battery, status.battery_remaining) == (16200, -1, 100)
    assert battery.voltages[:5] == [4050] * 4 + [65535]
    assert (battery.current_battery, battery.current_consumed, battery.battery_remaining) == (-1, -1, 100)
    assert battery.charge_state == mavlink.MAV_BATTERY_CHARGE_STATE_OK


def test_sim_state_gives_the_truth_and_the_ned_position_about_the_origin() -> None:
    bench = Bench()
    bench.ack(mavlink.MAV_CMD_SET_MESSAGE_INTERVAL, mavlink.MAVLINK_MSG_ID_SIM_STATE, 4000)
    bench.vehicle.sim.reset_pose(position=(3.0, -4.0, -10.0))
    bench.run(1.0)
    state = bench.take(mavlink.MAVLINK_MSG_ID_SIM_STATE)[-1]
    origin = bench.take(mavlink.MAVLINK_MSG_ID_GPS_GLOBAL_ORIGIN)[-1]
    projection = MapProjection(origin.latitude * 1e-7, origin.longitude * 1e-7)
    north, east = projection.project(state.lat_int * 1e-7, state.lon_int * 1e-7)
    truth = bench.vehicle.truth.position
    assert north == pytest.approx(truth[0], abs=0.02) and east == pytest.approx(truth[1], abs=0.02)
    assert origin.altitude * 1e-3 - state.alt == pytest.approx(truth[2], abs=0.01)
    assert state.q1 == pytest.approx(bench.vehicle.truth.q[0], abs=1e-6)


def test_offboard_body_rates_and_hover_thrust_keep_it_level_then_hold_holds_it() -> None:
    bench = Bench()
    bench.rates(0.0)
    mode = Px4Mode.OFFBOARD
    bench.ack(mavlink.MAV_CMD_DO_SET_MODE, 1, mode.main_mode, mode.sub_mode)
    assert bench.ack(mavlink.MAV_CMD_COMPONENT_ARM_DISARM, 1) == mavlink.MAV_RESULT_ACCEPTED
    step = [0]

    def stream() -> None:
        step[0] += 1
        bench.rates(0.65 if step[0] < 500 else 0.55)

    bench.run(4.0, stream)
    truth = bench.vehicle.truth
    roll, pitch, _ = quat.to_euler(truth.q)
    assert truth.position[2] < -2.0 and abs(roll) < math.radians(2.0) and abs(pitch) < math.radians(2.0)
    while bench.vehicle.commander.mode is Px4Mode.OFFBOARD:  # the stream stopped: COM_OF_LOSS_T, then Hold
        bench.run(0.004)
    assert bench.vehicle.commander.mode is Px4Mode.AUTO_LOITER
    assert bench.vehicle.time_us == pytest.approx(5_000_000, abs=20_000)
    entry = bench.vehicle.truth
    bench.run(8.0)
    final = bench.vehicle.truth
    assert math.dist(final.position, entry.position) < 1.5  # it brakes to its stopping point and holds it
    assert math.hypot(*final.velocity) < 0.2
    texts = [m.text for m in bench.take(mavlink.MAVLINK_MSG_ID_STATUSTEXT)]
    assert any("offboard signal lost" in t for t in texts)


def test_hold_entered_again_holds_where_it_began_again() -> None:
    bench = Bench()
    bench.rates(0.0)
    mode = Px4Mode.OFFBOARD
    bench.ack(mavlink.MAV_CMD_DO_SET_MODE, 1, mode.main_mode, mode.sub_mode)
    bench.ack(mavlink.MAV_CMD_COMPONENT_ARM_DISARM, 1)
    bench.run(1.5, lambda: bench.rates(0.65))
    bench.run(6.0)  # Hold
    assert bench.vehicle.commander.mode is Px4Mode.AUTO_LOITER
    first = bench.vehicle.truth.position
    bench.run(1.5, lambda: bench.rates(0.6))  # Offboard again: climb
    assert bench.vehicle.commander.mode is Px4Mode.OFFBOARD
    bench.run(10.0)  # Hold again, well above the first
    second = bench.vehicle.truth.position
    assert bench.vehicle.commander.mode is Px4Mode.AUTO_LOITER
    assert second[2] < first[2] - 2.0 and math.hypot(*bench.vehicle.truth.velocity) < 0.3


def test_offboard_attitude_setpoints_are_tracked() -> None:
    bench = Bench()
    q = quat.from_euler(math.radians(10.0), 0.0, 0.0)
    bench.attitude(q, 0.0)
    mode = Px4Mode.OFFBOARD
    bench.ack(mavlink.MAV_CMD_DO_SET_MODE, 1, mode.main_mode, mode.sub_mode)
    assert bench.ack(mavlink.MAV_CMD_COMPONENT_ARM_DISARM, 1) == mavlink.MAV_RESULT_ACCEPTED
    bench.run(0.6, lambda: bench.attitude(quat.IDENTITY, 0.7))  # take off level
    bench.run(1.0, lambda: bench.attitude(q, 0.6))
    roll = quat.to_euler(bench.vehicle.truth.q)[0]
    assert roll == pytest.approx(math.radians(10.0), abs=math.radians(1.5))
    assert bench.protocol.heartbeat()["base_mode"] & mavlink.MAV_MODE_FLAG_STABILIZE_ENABLED


def test_land_failsafe_lands_and_disarms() -> None:
    bench = Bench(COM_OBL_RC_ACT=4)
    bench.rates(0.0)
    mode = Px4Mode.OFFBOARD
    bench.ack(mavlink.MAV_CMD_DO_SET_MODE, 1, mode.main_mode, mode.sub_mode)
    bench.ack(mavlink.MAV_CMD_COMPONENT_ARM_DISARM, 1)
    bench.run(1.2, lambda: bench.rates(0.7))
    assert bench.vehicle.truth.position[2] < -1.0
    bench.run(2.0)
    assert bench.vehicle.commander.mode is Px4Mode.AUTO_LAND
    states = bench.take(mavlink.MAVLINK_MSG_ID_EXTENDED_SYS_STATE)
    assert states[-1].landed_state == mavlink.MAV_LANDED_STATE_LANDING
    bench.run(16.0)
    assert not bench.vehicle.commander.armed
    assert bench.vehicle.truth.on_ground
    assert bench.take(mavlink.MAVLINK_MSG_ID_EXTENDED_SYS_STATE)[-1].landed_state == mavlink.MAV_LANDED_STATE_ON_GROUND
