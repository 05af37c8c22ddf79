"""Scenario ``attitude_step``: arm, climb, hold near hover thrust, then 10° steps in roll, pitch and yaw.

The vehicle flies in offboard attitude mode: the script publishes ``vehicle_attitude_setpoint`` and
keeps the collective thrust near hover with a small vertical-speed loop on the simulator's ground
truth (the steps tilt the thrust vector). Each axis steps by 10° and back; the metrics come from the
ground truth, the estimate error from ``vehicle_attitude`` against it.
"""

from __future__ import annotations

import math
from collections.abc import Generator
from typing import Any

from stack.commander.modes import MAV_MODE_FLAG_CUSTOM_MODE_ENABLED
from stack.mathlib import quaternion as quat
from stack.mathlib.scalar import constrain
from stack.mavlink.px4_modes import MainMode
from stack.msg.registry import ORB_ID
from stack.msg.setpoints import VehicleAttitudeSetpoint
from stack.msg.system import OffboardControlMode, TelemetryStatus, VehicleCommand
from stack.scenario.catalogue import Check, Scenario
from stack.scenario.metrics import rms, step_response, unwrap_degrees, value_at
from stack.scenario.script import ScenarioError, ScriptContext, Wait

STEP_DEG = 10.0
HOLD_S = 1.5
CLIMB_TO_M = 3.0


class AttitudeStep:
    """The script's state: the attitude it asks for, and the thrust loop."""

    def __init__(self, ctx: ScriptContext) -> None:
        self.ctx = ctx
        self.euler = [0.0, 0.0, 0.0]
        self.yaw0 = 0.0
        self.climb = True
        self.thrust_integral = 0.0
        self.steps: dict[str, list[float]] = {"roll": [], "pitch": [], "yaw": []}
        self.ticks = 0

    def setpoint(self) -> None:
        """Publish the attitude setpoint with a collective thrust that holds the climb or the altitude.

        Like an offboard companion, it also streams offboard_control_mode (proof of life, attitude
        control) and a ground-station heartbeat, at 10 Hz.
        """
        if self.ticks % 10 == 0:
            self.ctx.publish(ORB_ID.offboard_control_mode, OffboardControlMode(attitude=True))
            self.ctx.publish(ORB_ID.telemetry_status, TelemetryStatus(heartbeat_type_gcs=True))
        self.ticks += 1
        truth = self.ctx.latest.get(ORB_ID.sim_groundtruth)
        thrust = 0.5
        if truth is not None:
            z, vz = truth.position[2], truth.velocity[2]
            vz_sp = constrain(-0.8 * (z + CLIMB_TO_M), -1.0, 1.0)
            error = vz - vz_sp
            self.thrust_integral = constrain(self.thrust_integral + 0.4 * error * 0.01, -0.3, 0.3)
            tilt = math.cos(self.euler[0]) * math.cos(self.euler[1])
            thrust = constrain((0.5 + self.thrust_integral + 0.3 * error) / tilt, 0.1, 0.9)
        q = quat.from_euler(self.euler[0], self.euler[1], self.yaw0 + self.euler[2])
        self.ctx.publish(
            ORB_ID.vehicle_attitude_setpoint, VehicleAttitudeSetpoint(q_d=q, thrust_body=(0.0, 0.0, -thrust))
        )

    def run(self) -> Generator[Wait, None, None]:
        ctx = self.ctx
        yield ctx.until(lambda: ORB_ID.vehicle_attitude in ctx.latest, 10.0, "an attitude estimate")
        yield ctx.wait(1.0)
        self.yaw0 = quat.yaw(ctx.latest[ORB_ID.vehicle_attitude].q)
        yield from ctx.command(
            VehicleCommand.VEHICLE_CMD_DO_SET_MODE,
            param1=MAV_MODE_FLAG_CUSTOM_MODE_ENABLED,
            param2=MainMode.OFFBOARD,
        )
        yield from ctx.command(VehicleCommand.VEHICLE_CMD_COMPONENT_ARM_DISARM, param1=1.0)
        ctx.log("armed: climbing")
        yield ctx.until(
            lambda: ctx.latest[ORB_ID.sim_groundtruth].position[2] < -CLIMB_TO_M + 0.3,
            20.0,
            f"a climb to {CLIMB_TO_M} m",
        )
        yield ctx.wait(2.0)
        for axis, name in enumerate(("roll", "pitch", "yaw")):
            for target in (STEP_DEG, 0.0):
                ctx.log(f"{name} step to {target:g} deg")
                self.steps[name].append(ctx.now)
                self.euler[axis] = math.radians(target)
                yield ctx.wait(HOLD_S)
        ctx.log("steps done")


def script(ctx: ScriptContext) -> Generator[Wait, None, None]:
    flight = AttitudeStep(ctx)
    ctx.tick_hooks.append(flight.setpoint)
    ctx.state["steps"] = flight.steps
    yield from flight.run()


def evaluate(ctx: ScriptContext) -> dict[str, Any]:
    truth = ctx.series.get(ORB_ID.sim_groundtruth)
    if truth is None or not truth.times:
        raise ScenarioError("no ground truth was received")
    steps: dict[str, list[float]] = ctx.state["steps"]
    euler = [quat.to_euler(m.q) for m in truth.values]
    times = truth.times
    metrics: dict[str, Any] = {}
    for axis, name in enumerate(("roll", "pitch", "yaw")):
        series = unwrap_degrees([math.degrees(e[axis]) for e in euler])
        worst_rise, worst_overshoot = 0.0, 0.0
        for t_step, direction in zip(steps[name], (1.0, -1.0), strict=True):
            start = value_at(times, series, t_step)
            rise, overshoot = step_response(times, series, t_step, start, start + direction * STEP_DEG)
            worst_rise = max(worst_rise, rise) if rise == rise else math.nan
            worst_overshoot = max(worst_overshoot, overshoot)
        metrics[f"{name}_rise_time_s"] = worst_rise
        metrics[f"{name}_overshoot_pct"] = worst_overshoot
    metrics["attitude_est_error_rms_deg"] = _estimate_error(ctx, steps["roll"][0] - 2.0)
    rates = ctx.series.get(ORB_ID.vehicle_rates_setpoint)
    metrics["max_rate_sp_dps"] = (
        max((max(abs(m.roll), abs(m.pitch), abs(m.yaw)) for m in rates.values), default=0.0) * 180.0 / math.pi
        if rates
        else math.nan
    )
    return metrics


def _estimate_error(ctx: ScriptContext, since: float) -> float:
    truth = ctx.series[ORB_ID.sim_groundtruth]
    estimates = ctx.series.get(ORB_ID.vehicle_attitude)
    if estimates is None:
        return math.nan
    by_sample = {m.timestamp_sample: m.q for m in truth.values}
    errors = [
        math.degrees(quat.angle_between(e.q, by_sample[e.timestamp_sample]))
        for t, e in zip(estimates.times, estimates.values, strict=True)
        if t >= since and e.timestamp_sample in by_sample
    ]
    if not errors:
        raise ScenarioError("no attitude estimate matched the ground truth samples")
    return rms(errors)


SCENARIO = Scenario(
    name="attitude_step",
    description="Arm, hold near hover thrust, then 10° steps in roll, pitch and yaw, each and back",
    script=script,
    evaluate=evaluate,
    checks=(
        Check("roll_rise_time_s", 0.08),
        Check("roll_overshoot_pct", 10.0),
        Check("pitch_rise_time_s", 0.08),
        Check("pitch_overshoot_pct", 10.0),
        Check("yaw_rise_time_s", 0.20),
        Check("yaw_overshoot_pct", 10.0),
        Check("attitude_est_error_rms_deg", 1.0),
    ),
    record=(ORB_ID.sim_groundtruth, ORB_ID.vehicle_attitude, ORB_ID.vehicle_rates_setpoint),
    publish=(ORB_ID.vehicle_attitude_setpoint, ORB_ID.offboard_control_mode, ORB_ID.telemetry_status),
    timeout_s=60.0,
)
