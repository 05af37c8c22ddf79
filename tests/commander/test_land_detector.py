import dataclasses
import math

import pytest

from stack.commander.fw_land_detector import fixedwing_inputs
from stack.commander.land_detector import LandDetectorInputs, MulticopterLandDetector, multicopter_inputs
from stack.msg.estimation import VehicleLocalPosition
from stack.msg.setpoints import (
    HoverThrustEstimate,
    TakeoffState,
    TakeoffStatus,
    TrajectorySetpoint,
    VehicleThrustSetpoint,
)
from stack.msg.system import VehicleStatus

DT_US = 10_000
STAGE_US = 333_333  # LNDMC_TRIG_TIME / 3


class Flight:
    """A land detector fed at 100 Hz with a fresh local position."""

    def __init__(self, **params) -> None:
        self.detector = MulticopterLandDetector(params)
        self.t = 1_000_000
        self.inp = LandDetectorInputs(
            armed=True, z_valid=True, v_xy_valid=True, v_z_valid=True, climb_rate_control=True, throttle=0.5
        )

    def run(self, seconds: float, **fields):
        """Hold ``fields`` for ``seconds``; return the times (µs after the start) each flag first became true.
        The altitude derivative follows the vertical velocity unless given."""
        if "vz" in fields:
            fields.setdefault("z_deriv", fields["vz"])
        self.inp = dataclasses.replace(self.inp, **fields)
        start = self.t
        first: dict[str, int] = {}
        state = self.detector.state
        for _ in range(round(seconds * 1e6 / DT_US)):
            self.t += DT_US
            self.inp.local_position_timestamp_us = self.t
            state = self.detector.update(self.t, self.inp)
            for name, value in state._asdict().items():
                if value and name not in first:
                    first[name] = self.t - start
        return state, first


def _descending():
    flight = Flight()
    state, _ = flight.run(0.5, vz=0.0)
    assert not (state.landed or state.maybe_landed or state.ground_contact)
    state, _ = flight.run(2.0, vz=0.7, throttle=0.45, velocity_setpoint_z=0.7)
    assert state.in_descend and state.in_ground_effect and state.vertical_movement
    assert not (state.landed or state.maybe_landed or state.ground_contact)
    return flight


def test_synthetic_landing_goes_through_the_three_stages_in_lndmc_trig_time():
    flight = _descending()
    state, first = flight.run(1.5, vz=0.0, throttle=0.1)
    assert state.landed and state.maybe_landed and state.ground_contact and state.at_rest
    # Each stage starts on the update after the previous one and ends on the first update past its time.
    assert first["ground_contact"] == pytest.approx(STAGE_US, abs=2 * DT_US)
    assert first["maybe_landed"] == pytest.approx(2 * STAGE_US, abs=3 * DT_US)
    assert first["landed"] == pytest.approx(3 * STAGE_US, abs=4 * DT_US)


def test_takeoff_clears_landed_at_once():
    flight = _descending()
    flight.run(1.5, vz=0.0, throttle=0.1)
    state, _ = flight.run(0.01, throttle=0.5, velocity_setpoint_z=-1.5)
    assert not (state.landed or state.maybe_landed or state.ground_contact)


def test_no_ground_contact_without_a_commanded_descent_in_climb_rate_modes():
    flight = _descending()
    state, _ = flight.run(2.0, vz=0.0, throttle=0.1, velocity_setpoint_z=0.0)
    assert not state.ground_contact and not state.landed
    # Manual-thrust modes need no descent setpoint.
    state, _ = flight.run(2.0, climb_rate_control=False, throttle=0.05)
    assert state.landed


def test_moving_or_rotating_vehicle_is_not_landed():
    flight = _descending()
    state, _ = flight.run(2.0, vz=0.0, throttle=0.1, vx=2.0)
    assert state.horizontal_movement and not state.ground_contact and not state.landed
    state, _ = flight.run(2.0, vx=0.0, angular_velocity=(math.radians(30.0), 0.0, 0.0))
    assert state.ground_contact and state.rotational_movement and not state.maybe_landed


def test_high_thrust_blocks_maybe_landed():
    flight = _descending()
    state, _ = flight.run(2.0, vz=0.0, throttle=0.2)
    assert state.has_low_throttle and state.ground_contact and not state.maybe_landed


def test_hover_thrust_estimate_moves_the_low_thrust_threshold():
    flight = _descending()
    # MPC_THR_HOVER 0.5: low thrust is 0.12 + 0.3 × 0.38 = 0.234.
    state, _ = flight.run(0.05, vz=0.0, throttle=0.27)
    assert not state.has_low_throttle
    # A fresh estimate of 0.4 relaxes it to 0.12 + 0.6 × 0.28 = 0.288.
    state, _ = flight.run(0.05, hover_thrust=0.4, hover_thrust_timestamp_us=flight.t)
    assert state.has_low_throttle


def test_disarmed_is_always_landed():
    flight = Flight()
    state, _ = flight.run(0.01, armed=False, vz=3.0, throttle=0.9)
    assert state.landed and state.maybe_landed and state.ground_contact


def test_freefall_after_0_3_s_of_low_specific_force():
    flight = Flight()
    _, first = flight.run(0.5, acceleration=(0.0, 0.0, -1.0))
    assert first["freefall"] == pytest.approx(300_000, abs=DT_US)
    state, _ = flight.run(0.01, acceleration=(0.0, 0.0, -9.8))
    assert not state.freefall


def test_range_finder_out_of_range_triples_the_stages():
    flight = _descending()
    _, first = flight.run(4.0, vz=0.0, throttle=0.1, dist_bottom_observable=True)
    assert first["landed"] == pytest.approx(9 * STAGE_US, abs=4 * DT_US)


def test_range_finder_must_read_close_to_the_ground():
    flight = _descending()
    state, _ = flight.run(
        2.0, vz=0.0, throttle=0.1, dist_bottom_observable=True, dist_bottom_valid=True, dist_bottom=3.0
    )
    assert not state.close_to_ground_or_skipped_check and not state.landed
    state, _ = flight.run(2.0, dist_bottom=0.2)
    assert state.landed


def test_without_vertical_velocity_minimum_thrust_for_8_s_means_landed():
    flight = _descending()
    state, first = flight.run(9.0, vz=0.0, throttle=0.1, v_z_valid=False, z_valid=False)
    assert state.vertical_movement and not state.ground_contact
    assert first["maybe_landed"] == pytest.approx(8_000_000 + STAGE_US, abs=3 * DT_US)


def test_vertical_threshold_is_capped_by_the_landing_speeds():
    assert MulticopterLandDetector({"LNDMC_Z_VEL_MAX": 0.5}).vertical_speed_threshold == pytest.approx(0.25)
    detector = MulticopterLandDetector({"LNDMC_Z_VEL_MAX": 0.5, "MPC_LAND_CRWL": 1.0})
    assert detector.vertical_speed_threshold == 0.5


def test_ground_effect_during_takeoff_ramp():
    flight = Flight()
    state, _ = flight.run(0.05, takeoff_state=TakeoffState.RAMPUP)
    assert state.in_ground_effect
    state, _ = flight.run(0.05, takeoff_state=TakeoffState.FLIGHT)
    assert not state.in_ground_effect
    state, _ = flight.run(0.05, dist_bottom_valid=True, dist_bottom=1.5)
    assert state.in_ground_effect


def test_a_parameter_change_in_flight_does_not_land_the_vehicle():
    flight = Flight()
    state, _ = flight.run(1.0, vz=0.0)
    assert not (state.landed or state.maybe_landed or state.ground_contact)
    flight.detector.set_params({"LNDMC_TRIG_TIME": 0.3, "MPC_THR_MIN": 0.1, "LNDMC_Z_VEL_MAX": 0.3})
    state, first = flight.run(1.0)
    assert not ({"landed", "maybe_landed", "ground_contact"} & first.keys())


def test_a_parameter_change_on_the_ground_keeps_it_landed_and_times_the_next_landing():
    flight = _descending()
    state, _ = flight.run(1.5, vz=0.0, throttle=0.1)
    assert state.landed
    flight.detector.set_params({"LNDMC_TRIG_TIME": 3.0})
    state, _ = flight.run(0.05)
    assert state.landed
    state, _ = flight.run(0.5, vz=0.0, throttle=0.5, velocity_setpoint_z=-1.5)
    assert not state.landed
    flight.run(1.0, vz=0.7, throttle=0.45, velocity_setpoint_z=0.7)
    state, first = flight.run(4.0, vz=0.0, throttle=0.1)
    assert state.landed and first["landed"] == pytest.approx(3 * 1_000_000, abs=4 * DT_US)


def test_inputs_from_the_messages_with_the_modes_climb_rate_control_and_no_throttle_in_termination():
    lpos = VehicleLocalPosition(timestamp=5, z_valid=True, v_z_valid=True, vz=0.3, z_deriv=0.2)
    thrust = VehicleThrustSetpoint(xyz=(0.4, 0.0, -0.6))
    mission, termination = VehicleStatus.NAVIGATION_STATE_AUTO_MISSION, VehicleStatus.NAVIGATION_STATE_TERMINATION
    nothing = multicopter_inputs(False, VehicleStatus.NAVIGATION_STATE_MANUAL, None, None, None, None, None, None)
    assert nothing.throttle == 0.0 and not nothing.climb_rate_control and math.isnan(nothing.velocity_setpoint_z)
    inp = multicopter_inputs(
        True, mission, lpos, None, thrust, TrajectorySetpoint(velocity=(0.0, 0.0, 0.7)),
        HoverThrustEstimate(timestamp=9, hover_thrust=0.45, valid=True),
        TakeoffStatus(takeoff_state=TakeoffStatus.TAKEOFF_STATE_FLIGHT),
    )
    assert (inp.armed, inp.local_position_timestamp_us, inp.vz, inp.z_deriv, inp.throttle) == (True, 5, 0.3, 0.2, 0.6)
    assert inp.climb_rate_control and inp.velocity_setpoint_z == 0.7
    assert (inp.hover_thrust, inp.hover_thrust_timestamp_us, inp.takeoff_state) == (0.45, 9, TakeoffState.FLIGHT)
    invalid_hover = multicopter_inputs(True, mission, None, None, None, None, HoverThrustEstimate(hover_thrust=0.45),
                                       TakeoffStatus(takeoff_state=TakeoffStatus.TAKEOFF_STATE_UNINITIALIZED))
    assert math.isnan(invalid_hover.hover_thrust) and invalid_hover.takeoff_state == TakeoffState.DISARMED
    stopped = multicopter_inputs(True, termination, lpos, None, thrust, None, None, None)
    assert stopped.throttle == 0.0 and not stopped.climb_rate_control
    assert fixedwing_inputs(True, mission, lpos, None, None, thrust).throttle == 0.4
    assert fixedwing_inputs(True, termination, lpos, None, None, thrust).throttle == 0.0
