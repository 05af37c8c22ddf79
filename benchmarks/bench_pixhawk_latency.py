"""The Pixhawk adapter's latency, link load and CPU, flying the simulated Pixhawk over UDP and over the pty.

Run with ``python benchmarks/bench_pixhawk_latency.py`` (``--profiles pixhawk_sim`` for one link; ``--seed``).
Each profile flies ``stack fly takeoff_land`` in a temporary ``STACK_HOME`` through the real CLI. During the
20 s hold it reads the ``pixhawk`` module's heartbeat (``stack status --json``) every second:

- **latency**: the age of each SET_ATTITUDE_TARGET when the adapter sends it, counted from the gyro sample
  it was computed from (the simulated Pixhawk's HIGHRES_IMU ``time_usec``, mapped onto the stack's clock by
  TIMESYNC, through the stack's attitude estimate and attitude controller), p50 and p99 over the adapter's
  last 2000 setpoints (8 s at 250 Hz), the worst of the readings;
- **link**: bytes per second in and out over the hold, against a 921600-baud UART's 92,160 B/s each way,
  and the setpoint rate (packets out per second);
- **CPU**: the adapter process's mean CPU over the hold (psutil, % of one core).

Figures are printed, not asserted; the load average the runs began with is printed with them.
"""

from __future__ import annotations

import argparse
import json
import os
import re
import statistics
import subprocess
import sys
import tempfile
import threading
import time
from pathlib import Path

from stack.pixhawk.plant import link_budget_bytes_per_s

REPO = Path(__file__).resolve().parents[1]
UART_BAUD = 921600
HOLD_SETTLE_S = 3.0
SAMPLES = 12


def _env(home: Path) -> dict[str, str]:
    env = {**os.environ, "STACK_HOME": str(home), "PYTHONUNBUFFERED": "1"}
    env["PYTHONPATH"] = str(REPO) + os.pathsep + env.get("PYTHONPATH", "")
    return env


def _status(home: Path, flight: str) -> dict | None:
    out = subprocess.run(
        [sys.executable, "-m", "stack", "status", "--json", "--vehicle", flight],
        env=_env(home),
        capture_output=True,
        text=True,
        timeout=30,
        cwd=REPO,
    )
    if out.returncode != 0:
        return None
    return next((m for m in json.loads(out.stdout)["modules"] if m["module"] == "pixhawk"), None)


def fly(profile: str, seed: int) -> dict[str, float]:
    with tempfile.TemporaryDirectory(prefix="bench-pixhawk-") as tmp:
        home = Path(tmp)
        proc = subprocess.Popen(
            [sys.executable, "-m", "stack", "fly", "takeoff_land", "--profile", profile, "--seed", str(seed), "-q"],
            env=_env(home),
            stdout=subprocess.PIPE,
            stderr=subprocess.STDOUT,
            text=True,
            cwd=REPO,
        )
        lines: list[str] = []
        holding = threading.Event()

        def read() -> None:
            assert proc.stdout is not None
            for line in proc.stdout:
                lines.append(line.rstrip())
                if "holding for" in line:
                    holding.set()

        reader = threading.Thread(target=read, daemon=True)
        reader.start()
        if not holding.wait(timeout=300):
            proc.kill()
            raise RuntimeError(f"{profile}: the flight never reached its hold:\n" + "\n".join(lines[-30:]))
        flight = next(m.group(1) for line in lines if (m := re.search(r"flight '([^']+)'", line)))
        time.sleep(HOLD_SETTLE_S)
        readings = []
        for _ in range(SAMPLES):
            row = _status(home, flight)
            if row is not None and row.get("extra"):
                readings.append((time.monotonic(), row))
            time.sleep(1.0)
        proc.wait(timeout=300)
        reader.join(timeout=5)
    if len(readings) < 2:
        raise RuntimeError(f"{profile}: no heartbeat of the pixhawk module was read")
    (t0, first), (t1, last) = readings[0], readings[-1]
    span = t1 - t0
    extras = [row["extra"] for _, row in readings]
    return {
        "p50_us": max(e.get("setpoint_age_p50_us", float("nan")) for e in extras),
        "p99_us": max(e.get("setpoint_age_p99_us", float("nan")) for e in extras),
        "bytes_in_s": (last["extra"]["bytes_in"] - first["extra"]["bytes_in"]) / span,
        "bytes_out_s": (last["extra"]["bytes_out"] - first["extra"]["bytes_out"]) / span,
        "setpoints_s": (last["extra"]["packets_out"] - first["extra"]["packets_out"]) / span,
        "cpu_percent": statistics.mean(row["cpu_percent"] for _, row in readings[1:]),
        "imu_rate_hz": float(last["extra"]["imu_rate_asked_hz"]),
        "timesync_rtt_us": float(last["extra"]["timesync_rtt_us"]),
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--profiles", nargs="+", default=["pixhawk_sim", "pixhawk_sim_pty"])
    parser.add_argument("--seed", type=int, default=1)
    args = parser.parse_args()
    load = os.getloadavg()
    budget = link_budget_bytes_per_s(UART_BAUD)
    print(f"load average at start: {load[0]:.2f} {load[1]:.2f} {load[2]:.2f}")
    print(
        f"{'PROFILE':18s} {'IMU Hz':>6s} {'p50 ms':>7s} {'p99 ms':>7s} {'IN B/s':>8s} {'OUT B/s':>8s} "
        f"{'of 921600 baud':>15s} {'SP/s':>6s} {'RTT us':>7s} {'CPU %':>6s}"
    )
    for profile in args.profiles:
        r = fly(profile, args.seed)
        share = max(r["bytes_in_s"], r["bytes_out_s"]) / budget * 100.0
        print(
            f"{profile:18s} {r['imu_rate_hz']:6.0f} {r['p50_us'] / 1e3:7.2f} {r['p99_us'] / 1e3:7.2f} "
            f"{r['bytes_in_s']:8.0f} {r['bytes_out_s']:8.0f} {share:14.1f}% {r['setpoints_s']:6.0f} "
            f"{r['timesync_rtt_us']:7.0f} {r['cpu_percent']:6.1f}"
        )


if __name__ == "__main__":
    main()
