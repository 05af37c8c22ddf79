"""How fast a dead control module becomes a failsafe in real time, and where the vehicle ends up.

    python benchmarks/bench_control_loss.py [--rounds 1] [--modules mc_rate_control,mc_pos_control]

For each module of the control chain (and each round), a fresh ``stack up sitl_quad --realtime`` takes off to
5 m, the module is SIGKILLed, and the benchmark reads from ``vehicle_status`` when the commander named it lost
(``nav_state_timestamp``, on the same monotonic clock as the kill) and which mode it chose; then, once the
vehicle is down or 20 s have passed, how far it was from where the module died. Prints a table and the worst.
"""

from __future__ import annotations

import argparse
import math
import tempfile
import time
from pathlib import Path

from stack.cli.common import print_table
from stack.commander.control_chain import CHAIN
from stack.commander.modes import mode_name
from tests.support.hover import echo, kill, start_hovering, truth, wait

ALTITUDE_M = 5.0


def one(home: Path, module: str) -> list[object]:
    stack = start_hovering(home, ALTITUDE_M)
    try:
        north, east, _, killed_at = kill(stack, module)
        wait(stack, lambda: module in echo(stack, "vehicle_status")["control_lost_modules"], 10.0, "detection")
        status = echo(stack, "vehicle_status")
        noticed_ms = (status["nav_state_timestamp"] - killed_at) / 1000
        deadline = time.monotonic() + 20.0
        while time.monotonic() < deadline and -truth(stack)[2] > 0.3:
            time.sleep(0.5)
        end = truth(stack)
        drift = math.hypot(end[0] - north, end[1] - east)
        return [module, round(noticed_ms, 1), mode_name(status["nav_state"]), round(drift, 2), round(-end[2], 2)]
    finally:
        stack.stop()


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--rounds", type=int, default=1)
    parser.add_argument("--modules", default=",".join(link.module for link in CHAIN))
    args = parser.parse_args()
    rows = []
    with tempfile.TemporaryDirectory() as home:
        for r in range(args.rounds):
            for module in args.modules.split(","):
                rows.append(one(Path(home) / f"{module}-{r}", module))
                print(*rows[-1], flush=True)
    print_table(["module", "failsafe after [ms]", "mode", "drift [m]", "height at end [m]"], rows)
    print(f"worst: noticed after {max(float(r[1]) for r in rows):.1f} ms, drift {max(float(r[3]) for r in rows):.2f} m")


if __name__ == "__main__":
    main()
