"""PX4's fixed-wing land detector against hand-worked cases (FixedwingLandDetector.cpp, at 50 Hz)."""

import dataclasses
import math

from stack.commander.fw_land_detector import FixedwingLandDetector, FixedwingLandDetectorInputs

DT_US = 20_000
GRAVITY = (0.0, 0.0, -9.80665)


class Plane:
    """A fixed-wing land detector fed every 20 ms with a fresh local position and airspeed."""

    def __init__(self, **params) -> None:
        self.detector = FixedwingLandDetector(params)
        self.t = 1_000_000
        self.inp = FixedwingLandDetectorInputs(armed=True, v_xy_valid=True, acceleration=GRAVITY)

    def run(self, seconds: float, **fields):
        """Hold ``fields`` for ``seconds``; return the last state and the update (count from 1) that first
        found the vehicle's landed state changed (None if none did)."""
        self.inp = dataclasses.replace(self.inp, **fields)
        changed = None
        state = self.detector.state
        before = state.landed
        for n in range(1, round(seconds * 1e6 / DT_US) + 1):
            self.t += DT_US
            self.inp.local_position_timestamp_us = self.t
            self.inp.airspeed_timestamp_us = self.t
            state = self.detector.update(self.t, self.inp)
            if state.landed != before and changed is None:
                changed = n
        return state, changed

    def cruise(self) -> None:
        """Ten seconds at 15 m/s: every filter settles on flight."""
        state, _ = self.run(10.0, vx=15.0, vy=0.0, vz=0.0, true_airspeed=15.0)
        assert not state.landed


def test_disarmed_it_is_landed_and_armed_in_flight_the_filters_rise_to_flying():
    plane = Plane()
    state, _ = plane.run(1.0, armed=False, vx=15.0, true_airspeed=15.0)
    assert state.landed and state.at_rest
    state, took_off = plane.run(1.0, armed=True)
    # The filters start from zero; the airspeed one (0.95/0.05) passes 6 m/s first: 15 · (1 − 0.95^n) ≥ 6 from
    # n = 10 (the ground speed's passes 5 m/s at n = 14). Taking off needs no hold time.
    assert took_off == 10
    assert not state.landed and not state.at_rest


def test_a_flying_state_never_lands():
    plane = Plane()
    plane.cruise()
    # A glide, a climb and a slow turn: fast through the air and over the ground.
    for fields in (
        {"vx": 12.0, "vz": 2.0, "true_airspeed": 13.0},
        {"vx": 8.0, "vy": 9.0, "vz": -3.0, "true_airspeed": 14.0, "angular_velocity": (0.3, 0.0, 0.4)},
        {"vx": 11.0, "vy": 0.0, "vz": 0.0, "true_airspeed": 11.0, "acceleration": (0.5, 4.0, -9.0)},
    ):
        state, landed = plane.run(60.0, **fields)
        assert landed is None and not state.landed  # never landed, not for one update
    assert not (state.freefall or state.ground_contact or state.maybe_landed or state.in_ground_effect)


def test_slow_and_still_for_lndfw_trig_time_lands():
    plane = Plane()
    plane.cruise()
    state, landed = plane.run(5.0, vx=0.0, true_airspeed=0.0)
    # The ground-speed filter (0.97/0.03) falls from 15 m/s below LNDFW_VEL_XY_MAX 5 m/s on the 37th update
    # (15 · 0.97^37 = 4.86, 15 · 0.97^36 = 5.01; the airspeed filter is below 6 m/s from the 18th); the request
    # then holds LNDFW_TRIG_TIME 2 s, 100 updates: landed on update 137.
    assert landed == 137
    assert state.landed and state.at_rest


def test_lndfw_trig_time_sets_the_hold():
    plane = Plane(LNDFW_TRIG_TIME=0.5)
    plane.cruise()
    _, landed = plane.run(3.0, vx=0.0, true_airspeed=0.0)
    assert landed == 37 + 25


def test_an_airspeed_above_the_limit_blocks_the_landing():
    plane = Plane()
    plane.cruise()
    # Stopped on the ground in a 7 m/s wind: the airspeed filter settles on 7 m/s, above LNDFW_AIRSPD_MAX 6 m/s.
    state, landed = plane.run(60.0, vx=0.0, true_airspeed=7.0)
    assert landed is None and not state.landed
    state, landed = plane.run(10.0, true_airspeed=5.5)
    assert state.landed and landed is not None


def test_without_airspeed_the_ground_speed_limit_tightens_to_seventy_percent():
    plane = Plane()
    plane.cruise()
    # No airspeed (NaN): the limit is 0.7 · 5 = 3.5 m/s, so a 4 m/s taxi is flying ...
    state, landed = plane.run(30.0, vx=4.0, true_airspeed=math.nan)
    assert landed is None and not state.landed
    # ... while with an airspeed of 0 m/s the same 4 m/s is below the 5 m/s limit.
    state, landed = plane.run(30.0, true_airspeed=0.0)
    assert state.landed


def test_a_stale_airspeed_counts_as_none():
    plane = Plane()
    plane.cruise()
    plane.inp = dataclasses.replace(plane.inp, vx=4.0, true_airspeed=0.0)
    for _ in range(1500):  # 30 s with an airspeed 2 s old: none, so 4 m/s is above 3.5 m/s
        plane.t += DT_US
        plane.inp.local_position_timestamp_us = plane.t
        plane.inp.airspeed_timestamp_us = plane.t - 2_000_000
        assert not plane.detector.update(plane.t, plane.inp).landed


def test_a_shaking_airframe_blocks_the_landing():
    plane = Plane()
    plane.cruise()
    # Horizontal specific force of 10 m/s²: the leaking filter settles on 0.18/0.2 · 10 = 9 > LNDFW_XYACC_MAX 8.
    state, landed = plane.run(30.0, vx=0.0, true_airspeed=0.0, acceleration=(6.0, 8.0, -9.8))
    assert landed is None and not state.landed
    # 8.5 m/s² settles on 7.65 < 8: it lands.
    state, _ = plane.run(10.0, acceleration=(8.5, 0.0, -9.8))
    assert state.landed


def test_the_rotation_limit_counts_only_without_ground_speed_and_airspeed():
    plane = Plane()  # armed on the ground, every filter at zero
    blind = {"v_xy_valid": False, "true_airspeed": math.nan}
    state, changed = plane.run(2.0, **blind, angular_velocity=(0.0, 0.0, 0.1))
    # 0.1 rad/s through the 0.95/0.05 filter: 0.005, then 0.00975 > LNDFW_ROT_MAX 0.5 °/s (0.00873 rad/s).
    assert changed == 2 and not state.landed
    state, changed = plane.run(5.0, angular_velocity=(0.0, 0.0, 0.0))
    # From 0.0994 rad/s, below 0.00873 after 48 updates (0.95^48 = 0.0853), then LNDFW_TRIG_TIME: update 148.
    assert changed == 148 and state.landed
    # With an airspeed the rotation does not count: turning at 5.7 °/s it stays landed, but not at rest (> 3 °/s).
    state, changed = plane.run(5.0, true_airspeed=0.0, angular_velocity=(0.0, 0.0, 0.1))
    assert changed is None and state.landed and not state.at_rest
    state, _ = plane.run(1.1, angular_velocity=(0.0, 0.0, 0.0))
    assert state.at_rest


def test_without_a_local_position_it_is_landed():
    plane = Plane()
    plane.cruise()
    plane.inp = dataclasses.replace(plane.inp, vx=15.0, true_airspeed=15.0)
    state = plane.detector.state
    for _ in range(200):  # 4 s with a position 1.5 s old
        plane.t += DT_US
        plane.inp.local_position_timestamp_us = plane.t - 1_500_000
        state = plane.detector.update(plane.t, plane.inp)
    assert state.landed


def test_non_finite_inputs_are_ignored():
    plane = Plane()
    plane.cruise()
    plane.run(0.1, vx=math.nan, vz=math.inf, acceleration=(math.nan, 0.0, -9.8), angular_velocity=(math.nan,) * 3)
    state, landed = plane.run(5.0, vx=0.0, vz=0.0, true_airspeed=0.0, acceleration=GRAVITY, angular_velocity=(0.0,) * 3)
    assert state.landed and landed is not None


def test_a_commander_restarted_in_the_air_starts_flying():
    plane = Plane()
    plane.detector.resume_in_air()
    assert not plane.detector.state.landed
    state, _ = plane.run(1.0, vx=15.0, true_airspeed=15.0)
    assert not state.landed


def test_a_takeoff_roll_is_still_landed_but_never_at_rest():
    """The position estimate fuses zero velocity only at rest: a plane rolling down the runway is landed until
    its airspeed passes LNDFW_AIRSPD_MAX, but from the throttle-up it is moving."""
    plane = Plane()
    state, _ = plane.run(2.0, vx=0.0, true_airspeed=0.0)
    assert state.landed and state.at_rest
    state, _ = plane.run(0.02, throttle=1.0, acceleration=(3.0, 0.0, -9.80665))
    assert state.landed and not state.at_rest
    state, _ = plane.run(1.0, vx=2.0, true_airspeed=2.0)  # a steady acceleration: the engine still runs
    assert state.landed and not state.at_rest
    # Back at idle and standing: rest once the specific force's reference has come back (1.9 m/s² away after
    # the roll, within 0.5 m/s² 67 updates later at 0.98 per update) and 1 s more has passed.
    state, _ = plane.run(2.3, throttle=0.0, vx=0.0, true_airspeed=0.0, acceleration=GRAVITY)
    assert state.landed and not state.at_rest
    state, _ = plane.run(0.1)
    assert state.landed and state.at_rest


def test_a_push_or_an_unknown_throttle_is_motion():
    plane = Plane()
    state, _ = plane.run(2.0, vx=0.0, true_airspeed=0.0)
    assert state.at_rest
    state, _ = plane.run(0.02, acceleration=(0.6, 0.0, -9.80665))  # pushed with the engine off
    assert state.landed and not state.at_rest
    plane = Plane()
    state, _ = plane.run(2.0, vx=0.0, true_airspeed=0.0, throttle=math.nan)
    assert state.landed and not state.at_rest
