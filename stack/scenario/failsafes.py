"""Scenario ``failsafes``: command-link loss, a geofence breach and a draining battery, in one flight.

The script is the ground station: it sends a heartbeat (``telemetry_status``) twice a second. After a
takeoff to 10 m and a go-to 10 m north:

1. **Link loss**: the heartbeats stop. After COM_DL_LOSS_T (5 s here) and the COM_FAIL_ACT_T grace in
   Hold, NAV_DLL_ACT (2, the default profile's) returns the vehicle home. The heartbeats resume and the
   pilot takes over with Hold.
2. **Geofence**: an offboard companion flies north at 3 m/s (``trajectory_setpoint`` velocity) until the
   vehicle leaves the GF_MAX_HOR_DIST (25 m here) cylinder; GF_ACTION (3) returns it. Back inside,
   the pilot takes over with Hold.
3. **Battery**: the simulated battery drains from full to empty in SIM_BAT_DRAIN (100 s) of armed time,
   without PX4's 50 % floor. At the critical level (BAT_CRIT_THR 10 % here) COM_LOW_BAT_ACT (3)
   returns, at the emergency level (BAT_EMERGEN_THR 3 %) it lands, and the vehicle disarms on the
   ground. The levels are 7 s apart, more than the COM_FAIL_ACT_T grace in Hold before an action.

The report has, for each, the mode the commander chose with its failsafe flag up.
"""

from __future__ import annotations

import math
from collections.abc import Generator
from typing import Any

from stack.commander.modes import MAV_MODE_FLAG_CUSTOM_MODE_ENABLED, mode_name
from stack.mavlink.px4_modes import MainMode
from stack.msg.registry import ORB_ID
from stack.msg.setpoints import TrajectorySetpoint
from stack.msg.system import OffboardControlMode, TelemetryStatus
from stack.scenario import autonomy
from stack.scenario.catalogue import Check, Scenario
from stack.scenario.script import ScriptContext, Wait

NS = autonomy.NS
CMD = autonomy.CMD
ALTITUDE_M = 10.0
AWAY_M = 10.0
FENCE_M = 25.0
BREACH_SPEED = 3.0
PARAMS: dict[str, object] = {
    "COM_DL_LOSS_T": 5,
    "GF_MAX_HOR_DIST": FENCE_M,
    "SIM_BAT_DRAIN": 100.0,
    "SIM_BAT_MIN_PCT": 0.0,
    "BAT_CRIT_THR": 0.10,
    "BAT_EMERGEN_THR": 0.03,
}


class GroundStation:
    """Heartbeats while the link is up; the offboard stream while the companion flies."""

    def __init__(self, ctx: ScriptContext) -> None:
        self.ctx = ctx
        self.link_up = True
        self.offboard_velocity: tuple[float, float, float] | None = None
        self.ticks = 0

    def tick(self) -> None:
        ctx = self.ctx
        if self.link_up and self.ticks % 50 == 0:
            ctx.publish(ORB_ID.telemetry_status, TelemetryStatus(heartbeat_type_gcs=True))
        if self.offboard_velocity is not None:
            if self.ticks % 10 == 0:
                ctx.publish(ORB_ID.offboard_control_mode, OffboardControlMode(velocity=True))
            if autonomy.nav_state(ctx) == NS.NAVIGATION_STATE_OFFBOARD:
                ctx.publish(ORB_ID.trajectory_setpoint, TrajectorySetpoint(velocity=self.offboard_velocity))
        self.ticks += 1


def failsafe_mode(ctx: ScriptContext) -> str | None:
    """The mode the commander switched to by failsafe, once it has (None while no failsafe acts)."""
    status = ctx.latest.get(ORB_ID.vehicle_status)
    if status is None or not status.failsafe or status.nav_state == NS.NAVIGATION_STATE_AUTO_LOITER:
        return None  # Hold is the grace period before the action
    return mode_name(status.nav_state)


def take_over(ctx: ScriptContext) -> Generator[Wait, None, None]:
    yield from ctx.command(CMD.VEHICLE_CMD_NAV_LOITER_UNLIM)
    yield ctx.until(lambda: autonomy.nav_state(ctx) == NS.NAVIGATION_STATE_AUTO_LOITER, 5.0, "Hold")
    ctx.log("pilot took over with Hold")


def distance_from_home(ctx: ScriptContext) -> float:
    lpos, home = ctx.latest[ORB_ID.vehicle_local_position], ctx.latest[ORB_ID.home_position]
    return math.hypot(lpos.x - home.x, lpos.y - home.y)


def script(ctx: ScriptContext) -> Generator[Wait, None, None]:
    gcs = GroundStation(ctx)
    ctx.tick_hooks.append(gcs.tick)
    yield from autonomy.wait_ready(ctx)
    yield from autonomy.take_off(ctx, ALTITUDE_M)
    home = ctx.latest[ORB_ID.home_position]
    yield from ctx.command(CMD.VEHICLE_CMD_DO_REPOSITION_LOCAL, param5=home.x + AWAY_M, param6=home.y)
    yield ctx.until(lambda: distance_from_home(ctx) > AWAY_M - 0.5, 20.0, f"the go-to {AWAY_M:g} m north")
    yield ctx.wait(2.0)

    ctx.log("ground station link cut")
    gcs.link_up = False
    yield ctx.until(lambda: failsafe_mode(ctx) is not None, 20.0, "the link-loss failsafe")
    ctx.state["link_loss_action"] = failsafe_mode(ctx)
    ctx.log(f"link-loss failsafe: {ctx.state['link_loss_action']}")
    gcs.link_up = True
    yield ctx.wait(1.0)
    yield from take_over(ctx)

    ctx.log("offboard: flying north out of the geofence")
    gcs.offboard_velocity = (BREACH_SPEED, 0.0, 0.0)
    yield ctx.wait(1.0)
    yield from ctx.command(
        CMD.VEHICLE_CMD_DO_SET_MODE,
        param1=float(MAV_MODE_FLAG_CUSTOM_MODE_ENABLED),
        param2=float(MainMode.OFFBOARD),
    )
    yield ctx.until(lambda: failsafe_mode(ctx) is not None, 30.0, "the geofence failsafe")
    ctx.state["geofence_action"] = failsafe_mode(ctx)
    ctx.log(f"geofence failsafe: {ctx.state['geofence_action']}")
    gcs.offboard_velocity = None
    yield ctx.until(lambda: distance_from_home(ctx) < FENCE_M - 5.0, 30.0, "the return inside the geofence")
    yield from take_over(ctx)

    ctx.log("holding until the battery runs low")
    yield ctx.until(lambda: failsafe_mode(ctx) is not None, 120.0, "the critical-battery failsafe")
    ctx.state["battery_critical_action"] = failsafe_mode(ctx)
    ctx.log(f"critical battery failsafe: {ctx.state['battery_critical_action']}")
    yield ctx.until(
        lambda: failsafe_mode(ctx) not in (None, ctx.state["battery_critical_action"]),
        30.0,
        "the emergency-battery failsafe",
    )
    ctx.state["battery_emergency_action"] = failsafe_mode(ctx)
    ctx.log(f"emergency battery failsafe: {ctx.state['battery_emergency_action']}")
    yield from autonomy.wait_disarmed(ctx, 120.0)
    yield ctx.wait(1.0)


def evaluate(ctx: ScriptContext) -> dict[str, Any]:
    return {
        "link_loss_action": ctx.state.get("link_loss_action", "none"),
        "geofence_action": ctx.state.get("geofence_action", "none"),
        "battery_critical_action": ctx.state.get("battery_critical_action", "none"),
        "battery_emergency_action": ctx.state.get("battery_emergency_action", "none"),
        "landed_and_disarmed": autonomy.landed_and_disarmed(ctx),
    }


SCENARIO = Scenario(
    name="failsafes",
    description="Link loss → return, geofence breach → return, low battery → return then land",
    script=script,
    evaluate=evaluate,
    checks=(
        Check("link_loss_action", "Return"),
        Check("geofence_action", "Return"),
        Check("battery_critical_action", "Return"),
        Check("battery_emergency_action", "Land"),
        Check("landed_and_disarmed", True),
    ),
    record=(ORB_ID.vehicle_status, ORB_ID.home_position),
    watch=(ORB_ID.vehicle_local_position, ORB_ID.vehicle_land_detected, ORB_ID.sim_groundtruth),
    publish=(ORB_ID.telemetry_status, ORB_ID.offboard_control_mode, ORB_ID.trajectory_setpoint),
    timeout_s=300.0,
    params=PARAMS,
)
