"""What the autonomous-flight scenarios share: getting ready, taking off, landing, and judging positions.

Positions are compared about home, which is what a pilot means by "5 m above home" and what return-to-launch
aims for: the estimator's local frame has its own origin (where GPS first fixed, at the height of the first
barometer sample), the simulator's ground truth another (the simulated home point on the ground).

- Horizontally, by where each truly is: the estimator's frame is tied to latitude and longitude by its
  reference point, so a setpoint (or home) is a place on the ground, and the truth's latitude and longitude put
  the vehicle in the same frame. The error of a hover is then the estimate's error and the control's at that
  moment, not also the estimate's error at the instant home was set (a second draw of the GPS noise that a
  position hold has nothing to do with).
- Vertically, against the heights at arming: the estimate's height is referenced to the barometer at start,
  and its absolute altitude carries the GPS altitude's metres of error.

Without a reference point (an estimate that reports none), horizontally too against the positions at arming.
"""

from __future__ import annotations

import bisect
import math
from collections.abc import Generator
from typing import Any

from stack.mathlib import quaternion as quat
from stack.mathlib.geo import MapProjection
from stack.mathlib.vector import Vec3
from stack.msg.registry import ORB_ID
from stack.msg.system import VehicleCommand, VehicleStatus
from stack.scenario.metrics import value_at
from stack.scenario.script import ScenarioError, ScriptContext, Series, Wait

NS = VehicleStatus
CMD = VehicleCommand
READY_TIMEOUT_S = 60.0
GPS_SETTLE_S = 10.0
"""Time on the ground after the position estimate turns valid, as EKF2 wants 10 s of good GPS before it
uses it: the origin is one GPS fix, and the estimate needs some fixes to average its noise out."""
# Topics every autonomous scenario records (all samples) and watches (latest value).
RECORD = (
    ORB_ID.sim_groundtruth,
    ORB_ID.vehicle_local_position,
    ORB_ID.trajectory_setpoint,
    ORB_ID.vehicle_status,
    ORB_ID.home_position,
)
WATCH = (ORB_ID.vehicle_land_detected, ORB_ID.mission_result)


def position_ready(ctx: ScriptContext) -> bool:
    lpos = ctx.latest.get(ORB_ID.vehicle_local_position)
    return (
        lpos is not None and lpos.xy_valid and lpos.z_valid and lpos.v_xy_valid and ORB_ID.home_position in ctx.latest
    )


def nav_state(ctx: ScriptContext) -> int:
    status = ctx.latest.get(ORB_ID.vehicle_status)
    return status.nav_state if status is not None else -1


def armed(ctx: ScriptContext) -> bool:
    status = ctx.latest.get(ORB_ID.vehicle_status)
    return status is not None and status.arming_state == NS.ARMING_STATE_ARMED


def wait_ready(ctx: ScriptContext) -> Generator[Wait, None, None]:
    """Until the position estimate is valid and home is known, as a pilot waits for GPS lock."""
    yield ctx.until(lambda: position_ready(ctx), READY_TIMEOUT_S, "a valid position estimate and home")
    yield ctx.wait(GPS_SETTLE_S)
    ctx.log("position estimate valid and settled, home known")


def take_off(ctx: ScriptContext, altitude: float) -> Generator[Wait, None, None]:
    """NAV_TAKEOFF to ``altitude`` above home (arms the vehicle) and wait for Hold."""
    yield from ctx.command(CMD.VEHICLE_CMD_NAV_TAKEOFF, param2=1.0, param7=altitude)
    ctx.state["armed_at"] = ctx.now
    yield ctx.until(lambda: nav_state(ctx) == NS.NAVIGATION_STATE_AUTO_LOITER, 60.0, "the takeoff to complete")
    ctx.log(f"takeoff to {altitude:g} m complete")


def settled(ctx: ScriptContext, target_z: float, tolerance: float = 0.05) -> bool:
    """The trajectory setpoint has arrived at ``target_z`` (local NED) and stopped."""
    sp = ctx.latest.get(ORB_ID.trajectory_setpoint)
    return (
        sp is not None
        and abs(sp.position[2] - target_z) < tolerance
        and all(abs(v) < 0.02 for v in sp.velocity if math.isfinite(v))
    )


def land(ctx: ScriptContext, timeout: float = 90.0) -> Generator[Wait, None, None]:
    yield from ctx.command(CMD.VEHICLE_CMD_NAV_LAND)
    yield from wait_disarmed(ctx, timeout)


def wait_disarmed(ctx: ScriptContext, timeout: float) -> Generator[Wait, None, None]:
    yield ctx.until(lambda: not armed(ctx), timeout, "landing and disarming")
    ctx.state["disarmed_at"] = ctx.now
    ctx.log("landed and disarmed")


def landed_and_disarmed(ctx: ScriptContext) -> bool:
    land = ctx.latest.get(ORB_ID.vehicle_land_detected)
    truth = ctx.latest.get(ORB_ID.sim_groundtruth)
    return not armed(ctx) and land is not None and land.landed and truth is not None and truth.on_ground


class Frames:
    """Ground truth and estimate/setpoints about home (see the module docstring)."""

    def __init__(self, ctx: ScriptContext) -> None:
        home = ctx.latest.get(ORB_ID.home_position)
        truth = ctx.series.get(ORB_ID.sim_groundtruth)
        if home is None or truth is None or not truth.times:
            raise ScenarioError("no home position or no ground truth was received")
        self.truth = truth
        self.home: Vec3 = (home.x, home.y, home.z)
        armed = truth_at(truth, ctx.state.get("armed_at", truth.times[0]))
        self.projection: MapProjection | None = None
        lpos = ctx.latest.get(ORB_ID.vehicle_local_position)
        if lpos is not None and lpos.xy_global and math.isfinite(armed.lat) and math.isfinite(armed.lon):
            self.projection = MapProjection(lpos.ref_lat, lpos.ref_lon)
            north, east = self.projection.project(armed.lat, armed.lon)
            # Where home truly is, in the simulator's frame: the vehicle at arming, less its true offset from home.
            self.truth_home: Vec3 = (
                armed.position[0] - (north - home.x),
                armed.position[1] - (east - home.y),
                armed.position[2],
            )
        else:
            self.truth_home = armed.position

    def truth_about_home(self, position: Vec3) -> Vec3:
        h = self.truth_home
        return (position[0] - h[0], position[1] - h[1], position[2] - h[2])

    def local_about_home(self, position: Vec3) -> Vec3:
        h = self.home
        return (position[0] - h[0], position[1] - h[1], position[2] - h[2])

    def place_about_home(self, lat: float, lon: float, north: float, east: float) -> tuple[float, float]:
        """A place on the ground about home: by its latitude and longitude in the estimator's frame, or without a
        reference point the ``north``/``east`` it was given about home."""
        if self.projection is None:
            return north, east
        n, e = self.projection.project(lat, lon)
        return n - self.home[0], e - self.home[1]


def truth_at(series: Series, t: float) -> Any:
    """The ground-truth sample at or just before ``t``."""
    return value_at(series.times, series.values, t)


def truth_position_between(series: Series, t: float) -> Vec3 | None:
    """The true position at ``t``, interpolated between the samples around it (None outside them)."""
    i = bisect.bisect_right(series.times, t)
    if i == 0 or i == len(series.times):
        return None
    (ta, a), (tb, b) = (series.times[i - 1], series.values[i - 1]), (series.times[i], series.values[i])
    u = (t - ta) / (tb - ta) if tb > ta else 0.0
    pa, pb = a.position, b.position
    return (pa[0] + u * (pb[0] - pa[0]), pa[1] + u * (pb[1] - pa[1]), pa[2] + u * (pb[2] - pa[2]))


def estimate_error_rms(ctx: ScriptContext, frames: Frames, t0: float, t1: float) -> float:
    """RMS distance between the position estimate and the truth (both about home) over [t0, t1]."""
    errors = estimate_errors(ctx, frames, t0, t1)
    return math.sqrt(sum(e * e for e in errors) / len(errors))


def estimate_errors(ctx: ScriptContext, frames: Frames, t0: float, t1: float) -> list[float]:
    """The distance between each position estimate and the truth at its sample time (both about home), over
    [t0, t1].

    In simulation the truth has a sample at each estimate's sample time; a plant on the wall clock (a
    simulated Pixhawk) samples its truth at other times, between which it is interpolated."""
    estimates = ctx.series.get(ORB_ID.vehicle_local_position)
    if estimates is None:
        raise ScenarioError("no position estimate was received")
    by_sample = {m.timestamp_sample: m.position for m in frames.truth.values}
    errors = []
    for t, e in zip(estimates.times, estimates.values, strict=True):
        truth = by_sample.get(e.timestamp_sample)
        if truth is None:
            truth = truth_position_between(frames.truth, e.timestamp_sample * 1e-6)
        if truth is None or not (t0 <= t <= t1):
            continue
        est = frames.local_about_home((e.x, e.y, e.z))
        errors.append(math.dist(est, frames.truth_about_home(truth)))
    if not errors:
        raise ScenarioError("no position estimate matched the ground truth samples")
    return errors


def max_tilt_deg(frames: Frames, t0: float, t1: float) -> float:
    tilts = [
        math.degrees(quat.tilt(m.q))
        for t, m in zip(frames.truth.times, frames.truth.values, strict=True)
        if t0 <= t <= t1
    ]
    return max(tilts, default=math.nan)


def setpoints_between(ctx: ScriptContext, t0: float, t1: float) -> list[tuple[float, Any]]:
    series = ctx.series.get(ORB_ID.trajectory_setpoint)
    if series is None:
        raise ScenarioError("no trajectory setpoint was received")
    return [(t, m) for t, m in zip(series.times, series.values, strict=True) if t0 <= t <= t1]
