import itertools
import math

import pytest

from stack.mathlib.scalar import CONSTANTS_ONE_G as G
from stack.mathlib.vector import NAN3
from stack.msg.setpoints import TakeoffState
from stack.posctl.position_control import PositionControl
from stack.posctl.takeoff import IDLE_ACCELERATION, Takeoff, TakeoffParams

DT = 0.01
DT_US = 10_000


def _step(takeoff, t_us, **flags):
    flags.setdefault("armed", True)
    flags.setdefault("landed", True)
    flags.setdefault("want_takeoff", False)
    state = takeoff.update_state(t_us, **flags)
    return state, takeoff.update_ramp(DT, 1.5)


def test_state_sequence_and_timings():
    takeoff = Takeoff(TakeoffParams(com_spoolup_time=1.0, mpc_tko_ramp_t=3.0, mpc_z_vel_p_acc=4.0))
    assert takeoff.update_state(0, armed=False, landed=True, want_takeoff=True) == TakeoffState.DISARMED

    t = 1_000_000
    assert _step(takeoff, t)[0] == TakeoffState.SPOOLUP
    assert _step(takeoff, t + 990_000)[0] == TakeoffState.SPOOLUP
    assert _step(takeoff, t + 1_000_000)[0] == TakeoffState.READY_FOR_TAKEOFF
    # Waits on the ground until a takeoff is requested.
    t += 5_000_000
    state, vz_limit = _step(takeoff, t)
    assert state == TakeoffState.READY_FOR_TAKEOFF
    assert vz_limit == pytest.approx(-G / 4.0)

    # Ramp: the upward velocity limit moves linearly from −g/Kp to the takeoff speed over 3 s.
    limits = []
    states = []
    for _ in range(400):
        t += DT_US
        state, vz_limit = _step(takeoff, t, want_takeoff=True, landed=False)
        states.append(state)
        limits.append(vz_limit)
    assert states[0] == TakeoffState.RAMPUP
    first_flight = states.index(TakeoffState.FLIGHT)
    assert first_flight * DT == pytest.approx(3.0, abs=1.5 * DT)
    assert limits[149] == pytest.approx(-G / 4.0 + 0.5 * (1.5 + G / 4.0), abs=0.02)
    assert all(b >= a for a, b in itertools.pairwise(limits))
    assert limits[-1] == 1.5

    # Landing returns to ready-for-takeoff; disarming to disarmed.
    assert _step(takeoff, t + DT_US, landed=True)[0] == TakeoffState.READY_FOR_TAKEOFF
    assert _step(takeoff, t + 2 * DT_US, armed=False)[0] == TakeoffState.DISARMED


def test_disarm_during_spoolup_restarts_the_timer():
    takeoff = Takeoff()
    _step(takeoff, 0)
    _step(takeoff, 500_000, armed=False)
    assert _step(takeoff, 600_000)[0] == TakeoffState.SPOOLUP
    assert _step(takeoff, 1_550_000)[0] == TakeoffState.SPOOLUP
    assert _step(takeoff, 1_600_000)[0] == TakeoffState.READY_FOR_TAKEOFF


def test_skip_takeoff_goes_straight_to_flight():
    takeoff = Takeoff()
    assert _step(takeoff, 0, skip_takeoff=True, landed=False)[0] == TakeoffState.FLIGHT
    assert takeoff.flying


def test_tilt_limit_and_minimum_thrust():
    takeoff = Takeoff()
    assert takeoff.update_tilt_limit(DT) == pytest.approx(math.radians(12.0))
    assert takeoff.minimum_thrust(0.12) == 0.0
    _step(takeoff, 0, skip_takeoff=True, landed=True)  # armed on the ground outside position control
    _step(takeoff, DT_US, skip_takeoff=True, landed=False)  # lifted off: flying
    assert takeoff.minimum_thrust(0.12) == 0.12
    # Slews up to MPC_TILTMAX_AIR at 0.2 rad/s.
    tilt = [takeoff.update_tilt_limit(DT) for _ in range(400)]
    assert tilt[0] == pytest.approx(math.radians(12.0) + 0.2 * DT)
    assert tilt[-1] == pytest.approx(math.radians(45.0))
    reached = next(i for i, x in enumerate(tilt) if x >= math.radians(45.0) - 1e-12)
    assert (reached + 1) * DT == pytest.approx(math.radians(33.0) / 0.2, abs=DT)


def test_started_in_the_air_the_tilt_limit_is_the_flight_one_at_once():
    """A position controller restarted in flight must not tip a vehicle leaning into the wind upright."""
    takeoff = Takeoff()
    _step(takeoff, 0, skip_takeoff=True, landed=False)
    assert takeoff.update_tilt_limit(DT) == pytest.approx(math.radians(45.0))


def test_setpoint_shaping_per_state():
    takeoff = Takeoff()
    pos, vel, acc = (0.0, 0.0, -2.0), (0.0, 0.0, -1.0), (0.1, 0.2, -0.5)
    idle = takeoff.shape_setpoint(pos, vel, acc)
    assert idle.acceleration == IDLE_ACCELERATION and idle.reset_integral
    assert all(math.isnan(c) for c in idle.position + idle.velocity)
    _step(takeoff, 0)
    _step(takeoff, 1_000_000, want_takeoff=True)
    assert takeoff.state == TakeoffState.RAMPUP
    ramp = takeoff.shape_setpoint(pos, vel, acc)
    assert ramp.position == pos and ramp.velocity == vel and not ramp.reset_integral
    assert ramp.acceleration[:2] == (0.1, 0.2) and math.isnan(ramp.acceleration[2])
    _step(takeoff, 1_000_000, skip_takeoff=True, landed=False)
    assert takeoff.shape_setpoint(pos, vel, acc) == (pos, vel, acc, False)


def test_controller_thrust_is_zero_before_and_at_the_start_of_the_ramp():
    takeoff = Takeoff()
    pc = PositionControl()
    t = 0

    def cycle(want_takeoff):
        nonlocal t
        t += DT_US
        takeoff.update_state(t, armed=True, landed=not want_takeoff, want_takeoff=want_takeoff)
        pc.set_limits(
            vel_up=takeoff.update_ramp(DT),
            thrust_min=takeoff.minimum_thrust(0.12),
            tilt_max=takeoff.update_tilt_limit(DT),
        )
        sp = takeoff.shape_setpoint((0.0, 0.0, -2.5), NAN3, NAN3)
        if sp.reset_integral:
            pc.reset_integral()
        pc.set_state((0.0, 0.0, 0.0), (0.0, 0.0, 0.0), (0.0, 0.0, 0.0), 0.0)
        pc.set_setpoint(sp.position, sp.velocity, sp.acceleration, 0.0, 0.0)
        assert pc.update(DT)
        return -pc.thrust_setpoint[2]

    idle = [cycle(False) for _ in range(150)]
    assert max(idle) <= 1e-3
    ramp = [cycle(True) for _ in range(320)]
    assert takeoff.state == TakeoffState.FLIGHT
    # The ramp starts from (almost) zero thrust and grows smoothly.
    assert ramp[0] < 0.02
    assert max(b - a for a, b in itertools.pairwise(ramp)) < 0.01
    assert ramp[-1] > 0.5


def test_still_landed_at_the_end_of_the_ramp_goes_back_to_ready():
    # PX4 falls through rampup → flight → (landed) ready_for_takeoff in one update.
    takeoff = Takeoff(TakeoffParams(mpc_tko_ramp_t=0.5))
    _step(takeoff, 0)
    _step(takeoff, 1_000_000, want_takeoff=True)
    for _ in range(60):
        takeoff.update_ramp(DT)
    assert takeoff.update_state(1_600_000, armed=True, landed=True, want_takeoff=False) == (
        TakeoffState.READY_FOR_TAKEOFF
    )
