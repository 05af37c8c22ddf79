"""The flight of a swarm scenario, vehicle by vehicle: the leader's (vehicle 1) and a follower's.

Every vehicle takes off to ALTITUDE_M above its home at the same simulated time (they share one clock). The
leader waits ASSEMBLE_S for the others to take their places, then flies the box (stack.scenario.formation) in
Offboard, hovers HOVER_S where it started and lands. A follower flies in Offboard at its place about the leader,
from the leader's position as it hears it (``ctx.leader``, LEADER_DELAY_S late); when the leader comes down below
LAND_BELOW_M it lands where it is; when the leader is lost it takes the profile's choice (``on_leader_loss``:
Hold, then lands after HOLD_AFTER_LOSS_S, or Land).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Generator
from typing import Any

from stack.commander.modes import MAV_MODE_FLAG_CUSTOM_MODE_ENABLED, mode_name
from stack.mavlink.px4_modes import MainMode
from stack.msg.registry import ORB_ID
from stack.msg.setpoints import TrajectorySetpoint
from stack.msg.system import OffboardControlMode
from stack.scenario import autonomy, formation
from stack.scenario.catalogue import Check, Scenario, Swarm
from stack.scenario.script import ScenarioError, Script, ScriptContext, Wait

EvaluateSwarm = Callable[[list[dict[str, Any] | None], float], dict[str, Any]]

ALTITUDE_M = 5.0
ASSEMBLE_S = 4.0
HOVER_S = 3.0
LAND_BELOW_M = 2.0
"""A follower lands once the leader, coming down, is lower than this above its ground."""
DESCENDING_M_S = 0.3
HOLD_AFTER_LOSS_S = 6.0
SETTLE_S = 3.0
"""After a follower switches to Hold, the time it takes to stop; its drift is measured from then."""
LOSS_ACTIONS = ("hold", "land")
NS = autonomy.NS
CMD = autonomy.CMD


class Offboard:
    """Streams ``offboard_control_mode`` and, in Offboard, the setpoint ``target`` gives at each tick (None: none)."""

    def __init__(self, ctx: ScriptContext) -> None:
        self.ctx = ctx
        self.target: Callable[[], TrajectorySetpoint | None] | None = None
        ctx.tick_hooks.append(self.tick)

    def tick(self) -> None:
        if self.target is None:
            return
        setpoint = self.target()
        if setpoint is None:
            return
        self.ctx.publish(ORB_ID.offboard_control_mode, OffboardControlMode(position=True, velocity=True))
        if autonomy.nav_state(self.ctx) == NS.NAVIGATION_STATE_OFFBOARD:
            self.ctx.publish(ORB_ID.trajectory_setpoint, setpoint)

    def start(self) -> Generator[Wait, None, None]:
        yield self.ctx.wait(0.2)  # the offboard signal first, as PX4 wants before the switch
        custom = float(MAV_MODE_FLAG_CUSTOM_MODE_ENABLED)
        yield from self.ctx.command(CMD.VEHICLE_CMD_DO_SET_MODE, param1=custom, param2=float(MainMode.OFFBOARD))
        yield self.ctx.until(lambda: autonomy.nav_state(self.ctx) == NS.NAVIGATION_STATE_OFFBOARD, 2.0, "Offboard")


def take_off(ctx: ScriptContext) -> Generator[Wait, None, None]:
    yield from autonomy.wait_ready(ctx)
    yield from autonomy.take_off(ctx, ALTITUDE_M)
    home = ctx.latest[ORB_ID.home_position]
    yield ctx.until(lambda: autonomy.settled(ctx, home.z - ALTITUDE_M), 30.0, "the climb to settle")


def leader_script(ctx: ScriptContext, killed_after_s: float | None = None) -> Generator[Wait, None, None]:
    """The leader's flight; ``killed_after_s``: its processes are all killed that long into the box."""
    offboard = Offboard(ctx)
    yield from take_off(ctx)
    held = ctx.latest[ORB_ID.trajectory_setpoint].position
    start = (held[0], held[1], held[2])
    offboard.target = lambda: TrajectorySetpoint(position=start, velocity=(0.0, 0.0, 0.0))
    yield ctx.wait(ASSEMBLE_S)
    yield from offboard.start()
    began = ctx.state["box_start_at"] = ctx.now
    box: dict[str, Any] = {"done": False}

    def along_box() -> TrajectorySetpoint:
        position, velocity, box["done"] = formation.box_setpoint(start, ctx.now - began)
        return TrajectorySetpoint(position=position, velocity=velocity)

    offboard.target = along_box
    ctx.log("flying the box")
    if killed_after_s is not None:
        yield ctx.wait(killed_after_s)
        ctx.state["killed_at"] = ctx.now
        ctx.kill_stack()
    yield ctx.until(lambda: box["done"], 120.0, "the box")
    ctx.state["box_end_at"] = ctx.now
    yield ctx.wait(HOVER_S)
    yield from autonomy.land(ctx)
    yield ctx.wait(1.0)


class Follower:
    """A follower's side of the formation, from what it heard of the leader at each tick."""

    def __init__(self, ctx: ScriptContext, home_z: float) -> None:
        assert ctx.swarm is not None
        self.ctx = ctx
        self.offset = formation.slot_offset(ctx.swarm.slot, ctx.swarm.spacing_m)
        self.home_z = home_z
        self.following = False
        self.lost_at: float | None = None
        self.last_heard_us = 0
        self.oldest_followed_s = 0.0

    def heard(self) -> Any:
        return self.ctx.leader.get(ORB_ID.vehicle_local_position)

    def now_us(self) -> int:
        return round(self.ctx.now * 1e6)

    def ready(self) -> bool:
        """The leader is heard, hovering at its height."""
        leader = self.heard()
        return (
            not formation.leader_lost(leader, self.now_us())
            and formation.leader_height_m(leader) > ALTITUDE_M - 0.5
            and self.setpoint() is not None
        )

    def setpoint(self) -> TrajectorySetpoint | None:
        """Where to fly now; None once the leader is lost (then never again)."""
        leader, own = self.heard(), self.ctx.latest.get(ORB_ID.vehicle_local_position)
        if self.lost_at is not None or own is None:
            return None
        now = self.now_us()
        if formation.leader_lost(leader, now):
            if self.following:
                self.lost_at = self.ctx.now
                self.last_heard_us = leader.timestamp_sample if leader is not None else 0
                self.ctx.log(f"leader lost: last heard at t={self.last_heard_us / 1e6:.2f} s")
            return None
        setpoint = formation.formation_setpoint(leader, own, self.home_z, self.offset, now)
        if setpoint is not None and self.following:
            self.oldest_followed_s = max(self.oldest_followed_s, formation.heard_age_s(leader, now))
        return setpoint

    def leader_landing(self) -> bool:
        leader = self.heard()
        return (
            leader is not None
            and formation.leader_height_m(leader) < LAND_BELOW_M
            and leader.vz > DESCENDING_M_S
        )


def follower_script(ctx: ScriptContext) -> Generator[Wait, None, None]:
    action = ctx.options.get("on_leader_loss", "hold")
    if action not in LOSS_ACTIONS:
        raise ScenarioError(f"on_leader_loss: {action!r} is not one of {', '.join(LOSS_ACTIONS)}")
    offboard = Offboard(ctx)
    yield from take_off(ctx)
    follower = Follower(ctx, ctx.latest[ORB_ID.home_position].z)
    yield ctx.until(follower.ready, 60.0, "the leader at its height")
    offboard.target = follower.setpoint
    yield from offboard.start()
    follower.following = True
    ctx.state["following_at"] = ctx.now
    ctx.state["follower"] = follower
    ctx.log("in formation")
    yield ctx.until(lambda: follower.lost_at is not None or follower.leader_landing(), 300.0, "the leader to land")
    offboard.target = None
    if follower.lost_at is None:
        ctx.log("the leader is landing: landing")
        yield from autonomy.land(ctx)
    elif action == "land":
        yield from autonomy.land(ctx)
    else:
        yield from ctx.command(CMD.VEHICLE_CMD_NAV_LOITER_UNLIM)
        yield ctx.wait(HOLD_AFTER_LOSS_S)
        ctx.state["hold_end_at"] = ctx.now
        yield from autonomy.land(ctx)
    yield ctx.wait(1.0)


def script(ctx: ScriptContext, killed_after_s: float | None = None) -> Generator[Wait, None, None]:
    if ctx.swarm is None:
        raise ScenarioError("a swarm scenario flies with --vehicles N")
    if ctx.swarm.leads:
        yield from leader_script(ctx, killed_after_s)
    else:
        yield from follower_script(ctx)


def evaluate(ctx: ScriptContext) -> dict[str, Any]:
    """A vehicle's own figures; the swarm's checks are made from every vehicle's (swarm_track)."""
    metrics: dict[str, Any] = {"landed_and_disarmed": autonomy.landed_and_disarmed(ctx)}
    for name in ("box_start_at", "box_end_at", "killed_at", "following_at"):
        if name in ctx.state:
            metrics[name] = ctx.state[name]
    follower: Follower | None = ctx.state.get("follower")
    if follower is None:
        return metrics
    metrics["oldest_followed_s"] = follower.oldest_followed_s
    metrics["leader_lost_at"] = follower.lost_at
    metrics["on_leader_loss"] = ctx.options.get("on_leader_loss", "hold")
    if follower.lost_at is not None:
        metrics["leader_last_heard_at"] = follower.last_heard_us * 1e-6
        metrics["mode_after_loss"] = _mode_after(ctx, follower.lost_at)
        if "hold_end_at" in ctx.state:
            metrics["hold_drift_m"] = _drift(ctx, follower.lost_at + SETTLE_S, ctx.state["hold_end_at"])
    return metrics


def _mode_after(ctx: ScriptContext, t: float) -> str:
    """The first mode the vehicle was in after Offboard, from ``t`` on."""
    status = ctx.series.get(ORB_ID.vehicle_status)
    if status is None:
        return ""
    for when, s in zip(status.times, status.values, strict=True):
        if when >= t and s.nav_state != NS.NAVIGATION_STATE_OFFBOARD:
            return mode_name(s.nav_state)
    return ""


def _drift(ctx: ScriptContext, t0: float, t1: float) -> float:
    """How far the vehicle truly moved from where it was at ``t0``, over [t0, t1]."""
    truth = ctx.series[ORB_ID.sim_groundtruth]
    start = autonomy.truth_at(truth, t0).position
    moved = [math.dist(m.position, start) for t, m in zip(truth.times, truth.values, strict=True) if t0 <= t <= t1]
    return max(moved, default=math.nan)


def swarm_scenario(
    name: str, description: str, script: Script, evaluate_swarm: EvaluateSwarm, checks: tuple[Check, ...]
) -> Scenario:
    """A scenario flown by these scripts: each vehicle's own figures from :func:`evaluate`, the swarm judged by
    ``evaluate_swarm`` against ``checks``; the followers hear the leader's position LEADER_DELAY_S late."""
    return Scenario(
        name=name,
        description=description,
        script=script,
        evaluate=evaluate,
        checks=(),
        record=autonomy.RECORD,
        watch=autonomy.WATCH,
        publish=(ORB_ID.offboard_control_mode, ORB_ID.trajectory_setpoint),
        timeout_s=240.0,
        options={"on_leader_loss": "hold"},
        choices={"on_leader_loss": LOSS_ACTIONS},
        swarm=Swarm(
            peers=(ORB_ID.vehicle_local_position,),
            peer_delay_s=formation.LEADER_DELAY_S,
            evaluate=evaluate_swarm,
            checks=checks,
        ),
    )
