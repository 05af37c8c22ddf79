"""Lockstep real-time factor of the whole multi-process stack, on each transport, against its ceiling.

Run with ``python benchmarks/bench_lockstep.py`` (``--quick``: one run of each kind). Every run uses a
temporary ``STACK_HOME`` (never ``~/.stack``) and the real CLI in a fresh interpreter; the kinds are
interleaved, ``--runs`` times:

- ``fast``: ``stack fly SCENARIO`` (takeoff_land unless ``--scenario`` says otherwise), every module its
  own process, lockstep over the same-host shared-memory fast path (the default);
- ``zenoh``: the same flight with ``--lockstep-transport zenoh``;
- ``observed``: the fast flight with the recorder (``--record``) and the plot bridge writing a Rerun
  file (``--save``; no viewer is needed);
- ``up``: ``stack up --speed max`` for ``--duration`` seconds, disarmed;
- ``paced``: ``stack up`` as a user starts it (``--speed 1``: paced to the wall clock), disarmed, for as
  long: its real-time factor (1 when it keeps up) and the CPU it costs, in cores;
- ``inner``, ``two`` and ``one``: the fast flight with modules sharing processes (a profile's
  ``process = "NAME"``): the simulator and the 250 Hz inner loop (attitude estimator, attitude and rate
  control, allocation) in one process and the rest each in its own; those two and the position chain in
  another; every lockstep module in one process. Each also runs as ``stack up --speed 1``, disarmed, for
  its resident and unique memory (all the stack's processes) and idle CPU;
- ``mixed``: the fast flight with the position chain (flight mode manager, position controller, hover thrust
  estimator) taking part over Zenoh (``transport = "zenoh"``, as modules on another host do);
- ``ceiling``: the same scenario and seed flown by :class:`stack.runtime.inprocess.InProcessStack`, the
  same modules chained in this one process with no bus (what the algorithms cost by themselves).

First it measures the round trip of a wake-up between two processes sleeping in poll() on eventfds, as lockstep
members do: what each hop of a message from one module process to another costs the machine by itself, once where
the scheduler puts them, once with both held on one CPU (the difference is what waking an idle CPU costs) and once
with idle CPUs kept awake, as the supervisor keeps them for a lockstep run at full speed where it may
(:mod:`stack.runtime.cpu_wake`).

While a stack runs, this script joins its bus as a client and listens to the module heartbeats (1 Hz
wall, each with the module's simulated time, runs and mean time inside ``run()``). On each heartbeat of
the lockstep coordinator it samples every module process's CPU time and context switches (psutil). The
window runs from the first sample after lockstep started to the second-to-last (the last may straddle
the shutdown), so start-up and shutdown are left out. It prints, per kind, the real-time factor (mean,
lowest, highest over the runs), wall and CPU µs per lockstep step and context switches per step; per
module of the fast flights, CPU µs per step, the share of it inside ``run()`` and context switches per
step; the ceiling, flown just before each flight (a shared machine's speed drifts), and each flying kind's ratio
to it; and the project's speed targets met or not, with the load
average the runs began with.
"""

from __future__ import annotations

import argparse
import itertools
import json
import os
import select
import statistics
import subprocess
import sys
import tempfile
import time
from dataclasses import dataclass, field
from pathlib import Path

import msgspec
import psutil

from stack.bus import keys
from stack.cli.common import connect
from stack.msg.internal import ModuleHeartbeat
from stack.runtime.cpu_wake import AwakeCpus
from stack.scenario.inprocess import fly_in_process
from stack.supervisor import state as run_state
from stack.supervisor.profile import load_profile

REPO = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(REPO))

from tests.support.harness import stack_env  # noqa: E402

STEP_US = 4000
# This project's speed targets on an idle 2-core machine: real-time factor by kind, and the fast path's ratio to
# the ceiling (the same modules chained in one process).
TARGETS = {"fast": 12.0, "up": 16.0, "observed": 9.0, "zenoh": 4.0}
RATIO_TARGET = 0.7
# The modules of the simulator's 250 Hz loop: gyro to attitude estimate, attitude and rate control, allocation.
INNER_LOOP = ("simulator", "attitude_estimator_q", "mc_att_control", "mc_rate_control", "control_allocator")
GROUPINGS = ("inner", "two", "one")
# The modules the ``mixed`` kind runs over Zenoh (launch/sitl_quad_mixed.toml's).
POSITION_CHAIN = ("flight_mode_manager", "mc_pos_control", "mc_hover_thrust_estimator")


def grouped_profile(base: str, grouping: str, directory: Path) -> Path:
    """A profile that extends ``base`` and puts its lockstep modules in shared processes (see the docstring)."""
    prof = load_profile(base)
    lines = [f"extends = {json.dumps(str(prof.path))}"]
    for m in prof.modules:
        if m.cls.PASSIVE or m.cls.OUTSIDE_LOCKSTEP:
            continue
        process = "vehicle" if grouping == "one" else "inner" if m.name in INNER_LOOP else None
        if process is None and grouping == "two":
            process = "outer"
        if process is not None:
            lines += ["[[module]]", f"name = {json.dumps(m.name)}", f"module = {json.dumps(m.module)}"]
            lines.append(f'process = "{process}"')
    path = directory / f"{prof.name}_{grouping}.toml"
    path.write_text("\n".join(lines) + "\n")
    return path


def mixed_profile(base: str, directory: Path) -> Path:
    """A profile that extends ``base`` with its position chain taking part in the lockstep over Zenoh."""
    prof = load_profile(base)
    lines = [f"extends = {json.dumps(str(prof.path))}"]
    for m in prof.modules:
        if m.name in POSITION_CHAIN:
            lines += ["[[module]]", f"name = {json.dumps(m.name)}", f"module = {json.dumps(m.module)}"]
            lines.append('transport = "zenoh"')
    path = directory / f"{prof.name}_mixed.toml"
    path.write_text("\n".join(lines) + "\n")
    return path


@dataclass
class Sample:
    wall: float
    sim_us: int
    cpu: dict[str, float]  # module → CPU seconds so far (user + system, all threads)
    switches: dict[str, tuple[int, int]]  # module → (voluntary, involuntary) context switches so far


@dataclass
class Run:
    kind: str
    samples: list[Sample] = field(default_factory=list)
    beats: dict[str, list[ModuleHeartbeat]] = field(default_factory=dict)
    report: dict | None = None
    ceiling_us: float = 0.0  # CPU µs per step of the same flight in one process, flown just before (flights only)
    memory: tuple[int, int, int] = (0, 0, 0)  # processes, resident and unique bytes (the last sample)

    def window(self) -> tuple[Sample, Sample]:
        full = max((set(s.cpu) for s in self.samples), key=len, default=set())
        live = [s for s in self.samples if s.sim_us > 0 and set(s.cpu) == full]
        if len(live) < 3:
            raise SystemExit(f"{self.kind}: only {len(live)} samples while the lockstep ran; run longer (--duration)")
        return live[0], live[-2]

    def figures(self) -> dict[str, float]:
        a, b = self.window()
        sim, wall = (b.sim_us - a.sim_us) * 1e-6, b.wall - a.wall
        steps = (b.sim_us - a.sim_us) / STEP_US
        cpu = sum(b.cpu[m] - a.cpu[m] for m in b.cpu)
        switches = sum(sum(b.switches[m]) - sum(a.switches[m]) for m in b.switches)
        return {"rtf": sim / wall, "steps": steps, "wall": wall, "cpu": cpu, "switches": switches}

    def modules(self) -> dict[str, tuple[float, float, float, float]]:
        """Module → (CPU s, seconds inside run(), voluntary and involuntary switches) over the window."""
        a, b = self.window()
        out = {}
        for m in b.cpu:
            busy = sum(self.runs_between(name, a.sim_us, b.sim_us) for name in m.split("+"))
            vol = b.switches[m][0] - a.switches[m][0]
            invol = b.switches[m][1] - a.switches[m][1]
            out[m] = (b.cpu[m] - a.cpu[m], busy, vol, invol)
        return out

    def runs_between(self, module: str, t0_us: int, t1_us: int) -> float:
        """Seconds inside ``run()`` between two simulated times, from the module's heartbeats."""
        beats = [hb for hb in self.beats.get(module, []) if t0_us <= hb.sim_time_us <= t1_us]
        busy = sum(hb.loop_avg_us * 1e-6 * (hb.runs - prev.runs) for prev, hb in itertools.pairwise(beats))
        span = (beats[-1].sim_time_us - beats[0].sim_time_us) if len(beats) > 1 else 0
        return busy * (t1_us - t0_us) / span if span else 0.0  # a module's beats cover a slightly different span


def module_processes(supervisor_pid: int) -> dict[str, psutil.Process]:
    """The supervisor and its module processes by module name (from their spec file ``<name>.spec.json``), a process
    shared by modules by their names joined with '+'."""
    try:
        found = {"supervisor": psutil.Process(supervisor_pid)}
        children = found["supervisor"].children()
    except psutil.Error:
        return {}
    for child in children:
        try:
            specs = [Path(a).name.removesuffix(".spec.json") for a in child.cmdline() if a.endswith(".spec.json")]
        except psutil.Error:
            continue
        if specs:
            found["+".join(specs)] = child
    return found


def measure(procs: dict[str, psutil.Process], wall: float, sim_us: int) -> Sample | None:
    try:
        cpu = {name: sum(p.cpu_times()[:2]) for name, p in procs.items()}
        switches = {name: tuple(p.num_ctx_switches()) for name, p in procs.items()}
    except psutil.Error:
        return None  # a process has just exited
    return Sample(wall, sim_us, cpu, switches)  # type: ignore[arg-type]


def memory(procs: dict[str, psutil.Process]) -> tuple[int, int, int] | None:
    """How many processes, and their resident and unique memory in bytes."""
    try:
        infos = [p.memory_full_info() for p in procs.values()]
    except psutil.Error:
        return None
    return len(infos), sum(i.rss for i in infos), sum(i.uss for i in infos)


def watch(proc: subprocess.Popen, run: Run, timeout: float) -> None:
    """Follow a running stack's heartbeats until its process ends, sampling CPU on the clock's beats."""
    deadline = time.monotonic() + timeout
    while not (state := next((s for s in run_state.running_stacks() if s["pid"] == proc.pid), None)):
        if proc.poll() is not None or time.monotonic() > deadline:
            raise SystemExit(f"{run.kind}: the stack did not come up")
        time.sleep(0.05)
    decoder = msgspec.msgpack.Decoder(ModuleHeartbeat)
    procs: dict[str, psutil.Process] = {}
    with connect(run_state.stack_name(state), None, name="bench") as node:
        sub = node.session.declare_subscriber(keys.heartbeat_all(node.vehicle))
        try:
            while proc.poll() is None:
                if time.monotonic() > deadline:
                    proc.terminate()
                    raise SystemExit(f"{run.kind}: no result within {timeout:g} s")
                sample = sub.try_recv()
                if sample is None:
                    time.sleep(0.01)
                    continue
                hb = decoder.decode(sample.payload.to_bytes())
                run.beats.setdefault(hb.module, []).append(hb)
                if hb.trigger != "lockstep coordinator":
                    continue
                if len(procs) < len(run.beats) + 1:
                    procs = module_processes(int(state["pid"]))
                measured = measure(procs, time.monotonic(), hb.sim_time_us)
                if measured is not None:
                    run.samples.append(measured)
                    if run.kind.startswith("paced"):
                        run.memory = memory(procs) or run.memory
        finally:
            sub.undeclare()


def run_stack(kind: str, args: list[str], home: Path, timeout: float) -> Run:
    run = Run(kind)
    log = home / f"{kind}.out"
    with log.open("w") as out:
        proc = subprocess.Popen(
            [sys.executable, "-m", "stack", *args], env=stack_env(home), stdout=out, stderr=subprocess.STDOUT, cwd=REPO
        )
        try:
            watch(proc, run, timeout)
            proc.wait(timeout=60.0)
        finally:
            if proc.poll() is None:
                proc.kill()
                proc.wait()
    if proc.returncode != 0:
        tail = "\n".join(log.read_text().splitlines()[-15:])
        raise SystemExit(f"{kind}: `stack {' '.join(args)}` exited with {proc.returncode}:\n{tail}")
    return run


def fly(kind: str, args: argparse.Namespace, home: Path, extra: list[str], profile: str = "") -> Run:
    """A ``stack fly`` of the scenario, after the same flight in one process (the ceiling, measured beside each
    flight: a shared machine's speed drifts within minutes)."""
    ceiling_us = fly_in_process(args.scenario, args.profile, args.seed).cpu_us_per_step
    report = home / f"{kind}-report.json"
    fly_args = ["fly", args.scenario, "--profile", profile or args.profile, "--seed", str(args.seed), "-q"]
    run = run_stack(kind, [*fly_args, "--report", str(report), *extra], home, timeout=600.0)
    run.report = json.loads(report.read_text())
    run.ceiling_us = ceiling_us
    if not run.report["passed"]:
        raise SystemExit(f"{kind}: the {args.scenario} flight failed: {run.report['checks']}")
    return run


def print_kinds(runs: dict[str, list[Run]]) -> tuple[dict[str, float], dict[str, float]]:
    """The table of kinds; returns each kind's mean real-time factor and each flying kind's mean ratio to the
    ceiling measured beside its flights."""
    print(
        f"\n{'kind':<12} {'runs':>4} {'RTF':>6} {'lowest':>6} {'highest':>7} {'wall/step':>10} {'CPU/step':>9}"
        f" {'switches/step':>13} {'scenario RTF':>12} {'to ceiling':>10}"
    )
    means, ratios = {}, {}
    for kind, kind_runs in runs.items():
        figs = [r.figures() for r in kind_runs]
        rtfs = [f["rtf"] for f in figs]
        steps = sum(f["steps"] for f in figs)
        scenario = [r.report["realtime_factor"] for r in kind_runs if r.report]
        means[kind] = statistics.fmean(rtfs)
        if all(r.ceiling_us for r in kind_runs):
            pairs = zip(figs, kind_runs, strict=True)
            ratios[kind] = statistics.fmean(f["rtf"] * r.ceiling_us / STEP_US for f, r in pairs)
        print(
            f"{kind:<12} {len(figs):>4} {means[kind]:>6.2f} {min(rtfs):>6.2f} {max(rtfs):>7.2f}"
            f" {sum(f['wall'] for f in figs) / steps * 1e6:>8.0f}µs {sum(f['cpu'] for f in figs) / steps * 1e6:>7.0f}µs"
            f" {sum(f['switches'] for f in figs) / steps:>13.1f}"
            f" {(f'{statistics.fmean(scenario):.2f}' if scenario else ''):>12}"
            f" {(f'{ratios[kind]:.2f}' if kind in ratios else ''):>10}"
        )
    ceilings = [r.ceiling_us for kind_runs in runs.values() for r in kind_runs if r.ceiling_us]
    print(
        f"{'ceiling':<12} {len(ceilings):>4} {STEP_US / statistics.fmean(ceilings):>6.2f}"
        f" {STEP_US / max(ceilings):>6.2f} {STEP_US / min(ceilings):>7.2f}"
        f"  (the same flight in one process, CPU = wall: {statistics.fmean(ceilings):.0f} µs per step)"
    )
    return means, ratios


def print_modules(kind: str, runs: list[Run]) -> None:
    totals: dict[str, list[float]] = {}
    steps = 0.0
    for r in runs:
        steps += r.figures()["steps"]
        for m, values in r.modules().items():
            totals[m] = [t + v for t, v in zip(totals.get(m, [0.0] * 4), values, strict=True)]
    print(f"\nper lockstep step, {kind} ({len(runs)} run(s), {steps:.0f} steps)")
    print(f"{'module':<26} {'CPU µs':>7} {'in run()':>8} {'voluntary':>9} {'involuntary':>11}")
    for m, (cpu, busy, vol, invol) in sorted(totals.items(), key=lambda kv: -kv[1][0]):
        share = f"{busy / cpu * 100:.0f} %" if cpu > 0 and m != "supervisor" else "-"
        names = m.split("+")
        label = names[0] + (f" +{len(names) - 1}" if len(names) > 1 else "")
        print(f"{label:<26} {cpu / steps * 1e6:>7.0f} {share:>8} {vol / steps:>9.2f} {invol / steps:>11.2f}")
    cpu, busy, vol, invol = (sum(v[i] for v in totals.values()) for i in range(4))
    share = f"{busy / cpu * 100:.0f} %"
    print(f"{'total':<26} {cpu / steps * 1e6:>7.0f} {share:>8} {vol / steps:>9.2f} {invol / steps:>11.2f}")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--profile", default="sitl_quad", help="launch profile (a name in launch/ or a path)")
    parser.add_argument("--scenario", default="takeoff_land", help="scenario of the flights")
    parser.add_argument("--seed", type=int, default=1, help="seed of the flights")
    parser.add_argument("--runs", type=int, default=3, help="runs of each kind")
    parser.add_argument("--duration", type=float, default=12.0, help="wall seconds of each `stack up` run")
    parser.add_argument("--quick", action="store_true", help="one run of each kind, 8 s `stack up` runs")
    args = parser.parse_args()
    if args.quick:
        args.runs, args.duration = 1, 8.0
    load_profile(args.profile)  # refused here, in one line, if broken
    load = os.getloadavg()
    print(f"load average {load[0]:.2f} {load[1]:.2f} {load[2]:.2f} on {os.cpu_count()} CPUs; profile {args.profile}")
    across, one_cpu = wake_round_trip_us(), wake_round_trip_us(cpu=min(os.sched_getaffinity(0)))
    awake = AwakeCpus()
    kept_awake = wake_round_trip_us() if awake.held else 0.0
    awake.close()
    print(
        f"wake-up round trip between two processes (eventfd, poll): {across:.1f} µs, {one_cpu:.1f} µs on one CPU, "
        + (
            f"{kept_awake:.1f} µs with idle CPUs kept awake (as full-speed lockstep runs keep them)"
            if kept_awake
            else f"idle CPUs cannot be kept awake here ({awake.refusal}): full-speed lockstep runs wait on them"
        )
    )
    kinds = ["fast", "zenoh", "mixed", "observed", "up", "paced", *GROUPINGS, *(f"paced {g}" for g in GROUPINGS)]
    runs: dict[str, list[Run]] = {kind: [] for kind in kinds}
    with tempfile.TemporaryDirectory(prefix="bench_lockstep") as tmp:
        home = Path(tmp)
        os.environ["STACK_HOME"] = str(home)  # connect() finds the stack through it
        grouped = {g: str(grouped_profile(args.profile, g, home)) for g in GROUPINGS}
        mixed = str(mixed_profile(args.profile, home))
        for i in range(args.runs):
            runs["fast"].append(fly("fast", args, home, []))
            runs["zenoh"].append(fly("zenoh", args, home, ["--lockstep-transport", "zenoh"]))
            runs["mixed"].append(fly("mixed", args, home, [], mixed))
            observers = ["--record", str(home / "flight.mcap"), "--save", str(home / "flight.rrd")]
            runs["observed"].append(fly("observed", args, home, observers))
            up_args = ["--duration", str(args.duration), "-q"]
            runs["up"].append(run_stack("up", ["up", args.profile, *up_args, "--speed", "max"], home, timeout=600.0))
            runs["paced"].append(run_stack("paced", ["up", args.profile, *up_args, "--speed", "1"], home, 600.0))
            for g, profile in grouped.items():
                runs[g].append(fly(g, args, home, [], profile))
                paced = f"paced {g}"
                runs[paced].append(run_stack(paced, ["up", profile, *up_args, "--speed", "1"], home, 600.0))
            print(f"run {i + 1}/{args.runs} done", flush=True)
    means, ratios = print_kinds(runs)
    print("\nidle `stack up` at --speed 1, by grouping: real-time factor, CPU, processes, memory (all the stack's)")
    for g in ("", *GROUPINGS):
        kind = f"paced {g}".strip()
        figs = [r.figures() for r in runs[kind]]
        cores = sum(f["cpu"] for f in figs) / sum(f["wall"] for f in figs)
        n, rss, uss = runs[kind][-1].memory
        print(
            f"  {g or 'per module':<10} RTF {means[kind]:.2f}, {cores:.2f} cores, {n} processes,"
            f" {rss / 2**20:.0f} MB resident, {uss / 2**20:.0f} MB unique"
        )
    print_modules("fast path, flying", runs["fast"])
    print_modules("Zenoh, flying", runs["zenoh"])
    print_modules("fast path with the position chain over Zenoh, flying", runs["mixed"])
    for g in GROUPINGS:
        print_modules(f"fast path, flying, grouped {g}", runs[g])
    print("\ntargets (idle 2-core machine):")
    for kind, target in TARGETS.items():
        print(f"  {kind:<9} real-time factor {means[kind]:5.2f} >= {target:g}: {verdict(means[kind], target)}")
    ratio = ratios["fast"]
    print(f"  ratio to the ceiling     {ratio:5.3f} >= {RATIO_TARGET:g}: {verdict(ratio, RATIO_TARGET)}")


WAKE_ECHO = """
import os, select, sys
ping, pong, n = int(sys.argv[1]), int(sys.argv[2]), int(sys.argv[3])
poll = select.poll()
poll.register(ping, select.POLLIN)
for _ in range(n):
    poll.poll()
    os.eventfd_read(ping)
    os.eventfd_write(pong, 1)
"""


def wake_round_trip_us(rounds: int = 20_000, cpu: int | None = None) -> float:
    """Mean round trip of a wake-up between two processes that sleep in poll() on eventfds, as lockstep members do:
    what each hop of a message between module processes costs the machine by itself. With ``cpu``, both processes
    are held on that one CPU: the wakee then runs where its waker is about to sleep, and no idle CPU has to be woken
    (on a virtual machine whose idle CPUs halt, that wake-up is most of the cost of a hop)."""
    ping, pong = os.eventfd(0), os.eventfd(0)
    allowed = os.sched_getaffinity(0)
    if cpu is not None:
        os.sched_setaffinity(0, {cpu})  # the echo process inherits it
    echo = subprocess.Popen([sys.executable, "-c", WAKE_ECHO, str(ping), str(pong), str(rounds)], pass_fds=(ping, pong))
    poll = select.poll()
    poll.register(pong, select.POLLIN)
    try:
        start = time.perf_counter()
        for _ in range(rounds):
            os.eventfd_write(ping, 1)
            poll.poll()
            os.eventfd_read(pong)
        elapsed = time.perf_counter() - start
    finally:
        os.sched_setaffinity(0, allowed)
        echo.wait()
        os.close(ping)
        os.close(pong)
    return elapsed / rounds * 1e6


def verdict(value: float, target: float) -> str:
    return "met" if value >= target else "MISSED"


if __name__ == "__main__":
    main()
