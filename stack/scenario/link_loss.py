"""Scenario ``link_loss``: the MAVLink link to the Pixhawk is cut for 2 s during a hold (profiles pixhawk_sim*).

After a takeoff to 5 m and a settled hold, the simulated Pixhawk's control channel (its ``--control-port``,
which the supervisor gives every module as STACK_CONTROL_PORT) cuts the link both ways for 2 s. The Pixhawk
loses the stack's setpoints: after COM_OF_LOSS_T its own failsafe (COM_OBL_RC_ACT) holds or lands, and, as
PX4's Offboard-loss failsafe clears when the signal returns, goes back to Offboard once the link is back.
The stack must see the link go (``external_autopilot_status.connected``) and come back, report the mode the
Pixhawk flies in, and nothing may fly away. Then the pilot lands: a Pixhawk still in its failsafe is handed
back to the stack by the Land command (Offboard again); one landing on its own is left to finish.

The report has: whether (and how fast) the stack reported the lost link; the mode the Pixhawk flew during
the cut (asked of the simulator, which judges as the ground truth does) and the one the stack reports once
the link is back; the largest horizontal and vertical distance from the hold point (ground truth) from the
cut until the landing began; and whether the vehicle landed and disarmed.
"""

from __future__ import annotations

import json
import math
import os
import socket
from collections.abc import Generator
from typing import Any

from stack.mavlink import px4_modes
from stack.mavlink.px4_modes import Px4Mode
from stack.msg.registry import ORB_ID
from stack.scenario import autonomy
from stack.scenario.catalogue import Check, Scenario
from stack.scenario.script import ScenarioError, ScriptContext, Wait

ALTITUDE_M = 5.0
SETTLE_S = 3.0
CUT_S = 2.0
OBSERVE_S = 4.0
"""How long the link is back before the pilot lands."""
PEEK_BEFORE_END_S = 0.4
"""When, before the cut ends (and after COM_OF_LOSS_T), the simulator is asked what the Pixhawk flies."""
CONTROL_PORT_ENV = "STACK_CONTROL_PORT"
SELF_FAILSAFE_MODES = ("AUTO.LOITER", "AUTO.LAND")
"""What PX4's Offboard-loss failsafe may fly without RC (Hold, or Land)."""


def control_simulated_pixhawk(request: dict[str, object], timeout_s: float = 1.0) -> dict[str, Any]:
    """Send one request to the simulated Pixhawk's control channel and return its answer."""
    port = os.environ.get(CONTROL_PORT_ENV)
    if not port:
        raise ScenarioError(f"no simulated Pixhawk control port ({CONTROL_PORT_ENV}): fly with --profile pixhawk_sim")
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as sock:
        sock.settimeout(timeout_s)
        sock.sendto(json.dumps(request).encode(), ("127.0.0.1", int(port)))
        try:
            answer = json.loads(sock.recv(65536))
        except (TimeoutError, ValueError) as e:
            raise ScenarioError(f"the simulated Pixhawk's control channel did not answer: {e}") from None
    if not answer.get("ok"):
        raise ScenarioError(f"the simulated Pixhawk refused {request}: {answer.get('error')}")
    return answer


def autopilot(ctx: ScriptContext) -> Any:
    status = ctx.latest.get(ORB_ID.external_autopilot_status)
    if status is None:
        raise ScenarioError("no external_autopilot_status: this scenario needs the pixhawk module")
    return status


def script(ctx: ScriptContext) -> Generator[Wait, None, None]:
    yield from autonomy.wait_ready(ctx)
    yield from autonomy.take_off(ctx, ALTITUDE_M)
    home = ctx.latest[ORB_ID.home_position]
    yield ctx.until(lambda: autonomy.settled(ctx, home.z - ALTITUDE_M), 30.0, "the climb to settle")
    yield ctx.wait(SETTLE_S)
    ctx.state["hold_point"] = ctx.latest[ORB_ID.sim_groundtruth].position
    cut_at = ctx.state["cut_at"] = ctx.now
    control_simulated_pixhawk({"cut_s": CUT_S})
    ctx.log(f"link to the Pixhawk cut for {CUT_S:g} s")
    yield ctx.until(lambda: not autopilot(ctx).connected, CUT_S, "the stack to report the lost link")
    ctx.state["link_lost_reported_after_s"] = ctx.now - cut_at
    ctx.log("the stack reports the link lost")
    yield ctx.wait(cut_at + CUT_S - PEEK_BEFORE_END_S - ctx.now)
    # What the Pixhawk flies while the stack cannot hear it, from the simulator (as the judge, like the truth).
    answer = control_simulated_pixhawk({"status": True})
    ctx.state["pixhawk_failsafe_mode"] = px4_modes.name(Px4Mode[str(answer["mode"])])
    ctx.log(
        f"during the cut the Pixhawk flies in {ctx.state['pixhawk_failsafe_mode']} (failsafe: {answer['failsafe']})"
    )
    yield ctx.until(lambda: autopilot(ctx).connected, CUT_S + 10.0, "the link to come back")
    ctx.log("the link is back")
    yield ctx.wait(OBSERVE_S)
    status = autopilot(ctx)
    ctx.state["pixhawk_mode_after"] = status.mode
    ctx.state["in_control_after"] = status.in_control
    ctx.log(f"the stack reports the Pixhawk in {status.mode}; the stack's setpoints fly it: {status.in_control}")
    ctx.state["landing_at"] = ctx.now
    if status.mode == "AUTO.LAND":
        ctx.log("the Pixhawk lands on its own")
        yield from autonomy.wait_disarmed(ctx, 90.0)
    else:
        yield from autonomy.land(ctx)
    yield ctx.wait(1.0)


def evaluate(ctx: ScriptContext) -> dict[str, Any]:
    truth = ctx.series.get(ORB_ID.sim_groundtruth)
    if truth is None:
        raise ScenarioError("no ground truth was received")
    t0, t1 = ctx.state["cut_at"], ctx.state["landing_at"]
    hold = ctx.state["hold_point"]
    horizontal = vertical = 0.0
    for t, m in zip(truth.times, truth.values, strict=True):
        if t0 <= t <= t1:
            horizontal = max(horizontal, math.hypot(m.position[0] - hold[0], m.position[1] - hold[1]))
            vertical = max(vertical, abs(m.position[2] - hold[2]))
    failsafe_mode = ctx.state.get("pixhawk_failsafe_mode", "none")
    return {
        "link_loss_reported": "link_lost_reported_after_s" in ctx.state,
        "link_loss_reported_after_s": ctx.state.get("link_lost_reported_after_s", math.nan),
        "pixhawk_failsafe_mode": failsafe_mode,
        "pixhawk_failsafe_held_or_landed": failsafe_mode in SELF_FAILSAFE_MODES,
        "pixhawk_mode_after_link": ctx.state.get("pixhawk_mode_after", "none"),
        "in_control_after_link": ctx.state.get("in_control_after", False),
        "drift_horizontal_max_m": horizontal,
        "drift_vertical_max_m": vertical,
        "landed_and_disarmed": autonomy.landed_and_disarmed(ctx),
    }


SCENARIO = Scenario(
    name="link_loss",
    description="Pixhawk profiles: the MAVLink link cut for 2 s in a hold; the Pixhawk's failsafe flies, then land",
    script=script,
    evaluate=evaluate,
    checks=(
        Check("link_loss_reported", True),
        Check("pixhawk_failsafe_held_or_landed", True),
        Check("drift_horizontal_max_m", 2.0),
        Check("drift_vertical_max_m", 1.0),
        Check("landed_and_disarmed", True),
    ),
    record=(*autonomy.RECORD, ORB_ID.external_autopilot_status),
    watch=autonomy.WATCH,
    timeout_s=180.0,
    profile="pixhawk_sim",
)
