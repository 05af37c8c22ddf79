"""A real-time hover against a starved machine and stalled modules: outcome and how far the vehicle strayed.

    python benchmarks/bench_stall.py [--burners 4,8,16,32] [--burn-s 30] [--stops 1,3,10] [--modules ...]

On ``stack up sitl_quad --realtime`` hovering at 5 m (its MAVLink links on free ports, its own STACK_HOME):

1. for each count of ``--burners`` CPU-burning processes (a Python busy loop each, normal priority), keeps
   them running ``--burn-s`` seconds;
2. for each module of the control chain and each duration of ``--stops``, sends the module SIGSTOP, then
   SIGCONT that many seconds later, and watches as long again plus 5 s.

Each trial prints the outcome (still holding, the failsafe the vehicle took and where it ended), the worst
horizontal and vertical distance of the true (simulated) position from where the trial began, and the
vehicle's warnings. A trial that leaves the vehicle on the ground or terminated is followed by disarming it,
and the next trial starts from a new takeoff (a vehicle terminated on the ground must be able to disarm and fly
again: a trial where it cannot is counted). Exit code 0 when every trial of the starved machine held the hover.
"""

from __future__ import annotations

import argparse
import json
import os
import signal
import subprocess
import sys
import tempfile
import time
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(REPO))

from tests.support.harness import RunningStack, launch_profile, stack_env, takeoff_when_ready  # noqa: E402

CHAIN = (
    "attitude_estimator_q",
    "local_position_estimator",
    "mc_att_control",
    "mc_rate_control",
    "control_allocator",
    "flight_mode_manager",
    "mc_pos_control",
    "commander",
)
HOLD = 4
ALTITUDE_M = 5.0


def watch(stack: RunningStack, seconds: float) -> subprocess.Popen:
    return subprocess.Popen(
        [sys.executable, "-m", "tests.support.attack", "none", "0", "--watch", str(seconds)],
        cwd=REPO,
        env=stack_env(stack.home),
        stdout=subprocess.PIPE,
        text=True,
    )


def result(watcher: subprocess.Popen) -> dict:
    out, _ = watcher.communicate(timeout=300)
    return json.loads(out)


def outcome(seen: dict) -> str:
    if seen["nav_state"] == HOLD and not seen["failsafe"] and seen["armed"]:
        return "held"
    mode = {4: "Hold", 5: "Return", 12: "Descend", 13: "Termination", 18: "Land"}.get(seen["nav_state"], "?")
    return f"{'failsafe, ' if seen['failsafe'] else ''}{mode}{'' if seen['armed'] else ', disarmed'}"


def print_trial(name: str, seen: dict) -> None:
    said = "; ".join(dict.fromkeys(seen["said"]))[:300]
    print(
        f"{name:44s} {outcome(seen):28s} horizontal {seen['horizontal_m']:7.2f} m  vertical {seen['vertical_m']:6.2f} m"
        + (f"  [{said}]" if said else ""),
        flush=True,
    )


def fly_again(stack: RunningStack) -> bool:
    """From wherever the last trial left it: on the ground disarmed, then up to the hover; False if refused."""
    status = json.loads(stack.cli("topic", "echo", "vehicle_status", "-n", "1", "--json").stdout)
    if status["arming_state"] == 2 and status["nav_state"] == HOLD and not status["failsafe"]:
        return True
    if status["arming_state"] == 2:
        stack.cli("cmd", "land", "--wait", timeout=120)
        stack.cli("cmd", "disarm")
    status = json.loads(stack.cli("topic", "echo", "vehicle_status", "-n", "1", "--json").stdout)
    if status["arming_state"] == 2:
        disarm = stack.cli("cmd", "disarm", "--force")
        if disarm.returncode != 0:
            print(f"  cannot disarm: {disarm.stderr.strip()}", flush=True)
            return False
    try:
        return takeoff_when_ready(stack, "--alt", str(ALTITUDE_M)).returncode == 0
    except AssertionError as refused:  # refused for good, not just until the estimates converge
        print(f"  cannot take off: {refused}", flush=True)
        return False


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--burners", default="4,8,16,32")
    parser.add_argument("--burn-s", type=float, default=30.0)
    parser.add_argument("--stops", default="1,3,10")
    parser.add_argument("--modules", default=",".join(CHAIN))
    args = parser.parse_args()
    starved_ok = True
    stuck = 0
    with tempfile.TemporaryDirectory(prefix="bench-stall-") as work:
        home = Path(work) / "home"
        stack = RunningStack(home, launch_profile(Path(work) / "profile"), "--realtime", "--quiet")
        try:
            stack.wait_up()
            assert takeoff_when_ready(stack, "--alt", str(ALTITUDE_M)).returncode == 0, stack.output
            for count in (int(n) for n in args.burners.split(",") if n):
                watcher = watch(stack, args.burn_s + 5.0)
                burners = [subprocess.Popen([sys.executable, "-c", "while True: pass"]) for _ in range(count)]
                time.sleep(args.burn_s)
                load = os.getloadavg()[0]
                for b in burners:
                    b.kill()
                seen = result(watcher)
                print_trial(f"{count} CPU burners for {args.burn_s:g} s (load {load:.1f})", seen)
                starved_ok &= outcome(seen) == "held"
                if not fly_again(stack):
                    stuck += 1
            for module in (m for m in args.modules.split(",") if m):
                for stop_s in (float(s) for s in args.stops.split(",") if s):
                    pid = stack.module_pids()[module]
                    watcher = watch(stack, 2 * stop_s + 5.0)
                    os.kill(pid, signal.SIGSTOP)
                    time.sleep(stop_s)
                    os.kill(pid, signal.SIGCONT)
                    print_trial(f"SIGSTOP {module} for {stop_s:g} s", result(watcher))
                    if not fly_again(stack):
                        stuck += 1
        finally:
            stack.stop()
    print(
        f"\nstarved machine: {'every hover held' if starved_ok else 'a hover was lost'}; "
        f"trials after which the vehicle could not fly again: {stuck}"
    )
    return 0 if starved_ok and stuck == 0 else 1


if __name__ == "__main__":
    sys.exit(main())
