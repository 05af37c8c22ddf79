"""Fuzz the flight-mode manager (PX4's navigator and flight tasks in one): any estimate, home, request from the
commander and sticks, in any mode. Nothing raises, and every setpoint is finite or NaN ("not controlled")."""

from __future__ import annotations

import math

from hypothesis import given
from hypothesis import strategies as st

from stack.commander.home import HomePosition
from stack.commander.modes import MODES
from stack.msg.navigation import NavigationRequest
from stack.msg.setpoints import ManualControlSetpoint
from stack.posctl.flight_mode_manager import FlightModeManager, NavigatorInputs
from stack.posctl.flight_task import VehicleState
from stack.posctl.fmm_module import FlightModeManagerModule
from tests.fuzz.strategies import FUZZ, any_int, finite_or_nan, nasty_float, vec3

states = st.builds(
    VehicleState, st.integers(0, 2**62), vec3, vec3, nasty_float, st.booleans(), st.booleans()
)
homes = st.one_of(st.none(), st.builds(HomePosition, nasty_float, nasty_float, nasty_float, nasty_float))
requests = st.one_of(
    st.none(),
    st.builds(
        NavigationRequest,
        takeoff_altitude=nasty_float,
        takeoff_yaw=nasty_float,
        reposition=vec3,
        reposition_yaw=nasty_float,
        reposition_speed=nasty_float,
        reposition_counter=any_int,
        mission_start_index=any_int,
        mission_start_counter=any_int,
    ),
)
sticks = st.one_of(
    st.none(),
    st.builds(
        ManualControlSetpoint,
        valid=st.booleans(),
        roll=nasty_float,
        pitch=nasty_float,
        yaw=nasty_float,
        throttle=nasty_float,
    ),
)
inputs = st.builds(NavigatorInputs, states, st.sampled_from(sorted(MODES)), st.booleans(), homes, requests, sticks)


@FUZZ
@given(steps=st.lists(inputs, min_size=1, max_size=4), dt=st.floats(*FlightModeManagerModule.DT_RANGE))
def test_the_flight_mode_manager_takes_any_input(steps, dt):
    """``dt`` as the runtime gives it: clamped to the module's DT_RANGE."""
    fmm = FlightModeManager()
    for inp in steps:
        command = fmm.update(inp, dt)
        if command is None:
            continue
        for value in (*command.position, *command.velocity, *command.acceleration, command.yaw, command.yawspeed):
            assert finite_or_nan(value), command
    status = fmm.mission_status()
    assert isinstance(status.valid, bool) and not math.isinf(status.seq_total)
