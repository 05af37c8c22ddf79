"""Lockstep real-time factor of the whole multi-process stack, and CPU per module.

Run with ``python benchmarks/bench_lockstep.py`` (``--quick``: one short run of each). Every run
uses a temporary ``STACK_HOME`` (never ``~/.stack``) and the real CLI in a fresh interpreter:

- ``fly``: ``stack fly SCENARIO --profile P`` (an armed flight, ``attitude_step`` unless
  ``--scenario`` says otherwise; its report gives the scenario's own real-time factor);
- ``up``: ``stack up P --duration S`` (disarmed, plain lockstep);
- ``floor``: ``stack up`` of the test chain in ``tests/support/modules.py`` (a 250 Hz clock and three
  modules doing almost nothing): what the runtime, the bus and the lockstep cost by themselves.

While a stack runs, this script joins its bus as a client of the supervisor's router and listens to
the module heartbeats (about 1 Hz wall, each with the module's simulated time, run count and mean
time inside ``run()``). On each heartbeat of the lockstep coordinator it samples every module
process's CPU time (psutil). The measured window runs from the first sample after lockstep started
to the second-to-last sample (the last may straddle the shutdown), so start-up and shutdown are
left out. Per module it prints CPU seconds per simulated second, % of one core, and the wall time
inside ``run()`` (the algorithm and its publish calls; the runtime times it with ``perf_counter``)
relative to the module's CPU: the rest is the runtime, the bus, the lockstep and Zenoh's threads,
and above 100 % the module was preempted inside ``run()``. Then per lockstep step: the wall time,
the CPU of all processes, the wall time in ``run()``, the CPU of the same algorithms chained in
this one process (:class:`stack.sim.inprocess.InProcessAttitudeFlight`, no bus at all), hence
what everything else costs, and the floor's CPU per module and step times the module count.
"""

from __future__ import annotations

import argparse
import itertools
import json
import math
import os
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
from stack.mathlib import quaternion as quat
from stack.msg.internal import ModuleHeartbeat
from stack.sim.inprocess import InProcessAttitudeFlight
from stack.supervisor import state as run_state
from stack.supervisor.profile import Profile, load_profile

REPO = Path(__file__).resolve().parents[1]
FLOOR_VEHICLE = "floor"
FLOOR_PROFILE = f"""
[stack]
vehicle = "{FLOOR_VEHICLE}"
lockstep = true
seed = 7

[[module]]
module = "tests.support.modules:TickSource"
critical = true

[[module]]
module = "tests.support.modules:Doubler"

[[module]]
module = "tests.support.modules:Summer"

[[module]]
module = "tests.support.modules:Pacer"
"""


@dataclass
class Sample:
    wall: float
    sim_us: int
    cpu: dict[str, float]  # module → CPU seconds so far (user + system, all threads)


@dataclass
class Run:
    kind: str
    samples: list[Sample] = field(default_factory=list)
    beats: dict[str, list[ModuleHeartbeat]] = field(default_factory=dict)
    report: dict | None = None

    def window(self) -> tuple[Sample, Sample]:
        full = max((set(s.cpu) for s in self.samples), key=len, default=set())
        live = [s for s in self.samples if s.sim_us > 0 and set(s.cpu) == full]
        if len(live) < 3:
            raise SystemExit(f"{self.kind}: only {len(live)} samples while the lockstep ran; run longer (--duration)")
        return live[0], live[-2]

    def figures(self) -> dict[str, float]:
        a, b = self.window()
        sim, wall = (b.sim_us - a.sim_us) * 1e-6, b.wall - a.wall
        steps = self.steps(a, b)
        cpu = sum(b.cpu[m] - a.cpu[m] for m in b.cpu)
        in_run = sum(self.in_run(m, a, b) for m in b.cpu)
        return {"sim": sim, "wall": wall, "rtf": sim / wall, "steps": steps, "cpu": cpu, "in_run": in_run}

    def steps(self, a: Sample, b: Sample) -> int:
        clock = next(m for m, beats in self.beats.items() if beats[-1].trigger == "lockstep coordinator")
        return round(self.runs_between(clock, a.sim_us, b.sim_us)[0])

    def runs_between(self, module: str, t0_us: int, t1_us: int) -> tuple[float, float]:
        """Runs and seconds inside ``run()`` between two simulated times, from the module's heartbeats."""
        beats = [hb for hb in self.beats.get(module, []) if t0_us <= hb.sim_time_us <= t1_us]
        runs = busy = 0.0
        for prev, hb in itertools.pairwise(beats):
            runs += hb.runs - prev.runs
            busy += hb.loop_avg_us * 1e-6 * (hb.runs - prev.runs)
        span = (beats[-1].sim_time_us - beats[0].sim_time_us) if len(beats) > 1 else 0
        scale = (t1_us - t0_us) / span if span else 0.0  # a module's beats cover a slightly different span
        return runs * scale, busy * scale

    def in_run(self, module: str, a: Sample, b: Sample) -> float:
        return self.runs_between(module, a.sim_us, b.sim_us)[1]


def stack_env(home: Path) -> dict[str, str]:
    env = {k: v for k, v in os.environ.items() if k != "STACK_ENDPOINT"}
    env["STACK_HOME"] = str(home)
    env["PYTHONPATH"] = str(REPO) + os.pathsep + env.get("PYTHONPATH", "")
    return env


def module_processes(supervisor_pid: int) -> dict[str, psutil.Process]:
    """The supervisor and its module processes by module name (from their spec file ``<name>.spec.json``)."""
    try:
        found = {"supervisor": psutil.Process(supervisor_pid)}
        children = found["supervisor"].children()
    except psutil.Error:
        return {}
    for child in children:
        try:
            spec = next(a for a in child.cmdline() if a.endswith(".spec.json"))
        except (StopIteration, psutil.Error):
            continue
        found[Path(spec).name.removesuffix(".spec.json")] = child
    return found


def cpu_seconds(procs: dict[str, psutil.Process]) -> dict[str, float] | None:
    try:
        return {name: sum(p.cpu_times()[:2]) for name, p in procs.items()}
    except psutil.Error:
        return None  # a process has just exited


def watch(proc: subprocess.Popen, run: Run, timeout: float) -> None:
    """Follow a running stack's heartbeats until its process ends, sampling CPU on the clock's beats."""
    deadline = time.monotonic() + timeout
    while not (state := next((s for s in run_state.running_stacks() if s["pid"] == proc.pid), None)):
        if proc.poll() is not None or time.monotonic() > deadline:
            raise SystemExit(f"{run.kind}: the stack did not come up")
        time.sleep(0.05)
    decoder = msgspec.msgpack.Decoder(ModuleHeartbeat)
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
                cpu = cpu_seconds(module_processes(int(state["pid"])))
                if cpu is not None:
                    run.samples.append(Sample(time.monotonic(), hb.sim_time_us, cpu))
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


def print_runs(runs: list[Run]) -> None:
    print(
        f"\n{'run':<6} {'sim s':>6} {'wall s':>6} {'RTF':>5} {'steps':>6} {'wall/step':>10} {'CPU/step':>9}"
        f" {'in run()':>9} {'scenario RTF':>12}"
    )
    for r in runs:
        f = r.figures()
        rtf = f"{r.report['realtime_factor']:.2f}" if r.report else ""
        print(
            f"{r.kind:<6} {f['sim']:>6.1f} {f['wall']:>6.1f} {f['rtf']:>5.2f} {f['steps']:>6}"
            f" {f['wall'] / f['steps'] * 1e6:>8.0f}µs {f['cpu'] / f['steps'] * 1e6:>7.0f}µs"
            f" {f['in_run'] / f['steps'] * 1e6:>7.0f}µs {rtf:>12}"
        )


def print_modules(kind: str, runs: list[Run]) -> None:
    """CPU per module, summed over the runs of one kind."""
    totals: dict[str, list[float]] = {}
    sim = wall = 0.0
    for r in runs:
        a, b = r.window()
        sim += (b.sim_us - a.sim_us) * 1e-6
        wall += b.wall - a.wall
        for m in b.cpu:
            cpu, busy = totals.setdefault(m, [0.0, 0.0])
            totals[m] = [cpu + b.cpu[m] - a.cpu[m], busy + r.in_run(m, a, b)]
    print(f"\nCPU per module, {kind} ({len(runs)} run(s), {sim:.1f} s simulated in {wall:.1f} s)")
    print(f"{'module':<26} {'CPU s/sim s':>11} {'% of a core':>11} {'run()/CPU':>9}")
    for m, (cpu, busy) in sorted(totals.items(), key=lambda kv: -kv[1][0]):
        share = f"{busy / cpu * 100:.0f} %" if cpu > 0 and m != "supervisor" else "-"
        print(f"{m:<26} {cpu / sim:>11.3f} {cpu / wall * 100:>10.1f}% {share:>9}")
    cpu = sum(v[0] for v in totals.values())
    busy = sum(v[1] for v in totals.values())
    print(f"{'total':<26} {cpu / sim:>11.3f} {cpu / wall * 100:>10.1f}% {busy / cpu * 100:>7.0f} %")


def algorithms_cpu_per_step(profile: Profile, seed: int, steps: int = 2500) -> float:
    """CPU µs per step of the flight's algorithms alone, chained in this process (InProcessAttitudeFlight)."""
    params = {k: v for entry in profile.modules for k, v in entry.params.items()}
    flight = InProcessAttitudeFlight(profile.airframe, params, seed=seed)
    model = flight.sim.model
    flight.sim.reset_pose((0.0, 0.0, -5.0), motor_states=(model.hover_command,) * model.rotor_count)
    flight.armed, flight.thrust = True, model.hover_thrust_fraction
    start = time.process_time()
    for i in range(steps):
        if i % 250 == 0:  # 10° roll steps and back, once a second
            flight.q_sp = quat.from_euler(math.radians(10.0 * (i // 250 % 2)), 0.0, 0.0)
        flight.step()
    return (time.process_time() - start) / steps * 1e6


def where_the_time_goes(flights: list[Run], floors: list[Run], module_count: int, algorithms: float) -> None:
    fly = [r.figures() for r in flights]
    steps = sum(f["steps"] for f in fly)
    wall = sum(f["wall"] for f in fly) / steps * 1e6
    cpu = sum(f["cpu"] for f in fly) / steps * 1e6
    in_run = sum(f["in_run"] for f in fly) / steps * 1e6
    print(f"\nwhere the time goes, per lockstep step of the flight ({module_count} modules + the supervisor)")
    print(f"  wall time                          {wall:7.0f} µs  (2 cores: at most {2 * wall:.0f} µs of CPU)")
    print(f"  CPU, all processes                 {cpu:7.0f} µs")
    print(f"  wall time inside run()             {in_run:7.0f} µs  (the modules' code and its publish calls;")
    print("                                                 preemption on a loaded machine inflates it)")
    print(
        f"  the algorithms alone, one process  {algorithms:7.0f} µs  (InProcessAttitudeFlight: simulator, estimator,"
        " attitude and rate loops, allocator)"
    )
    print(
        f"  everything else                    {cpu - algorithms:7.0f} µs  ({(cpu - algorithms) / cpu * 100:.0f} %:"
        " messages, bus, lockstep, runtime, Zenoh threads, commander, scenario)"
    )
    if floors:
        fl = [r.figures() for r in floors]
        n_floor = len(floors[0].window()[1].cpu) - 1
        per_module = sum(f["cpu"] for f in fl) / sum(f["steps"] for f in fl) / n_floor * 1e6
        floor_wall = sum(f["wall"] for f in fl) / sum(f["steps"] for f in fl) * 1e6
        machinery = per_module * module_count
        print(f"  floor: {n_floor} trivial modules      {floor_wall:7.0f} µs wall, {per_module:.0f} µs CPU per module")
        print(
            f"  floor CPU per module x {module_count}          {machinery:7.0f} µs  ({machinery / cpu * 100:.0f} % of"
            " the flight's CPU: what modules cost doing nothing)"
        )


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--profile", default="sitl_quad", help="launch profile (a name in launch/ or a path)")
    parser.add_argument("--runs", type=int, default=3, help="runs of each kind")
    parser.add_argument("--duration", type=float, default=15.0, help="wall seconds of each `stack up` run")
    parser.add_argument("--seed", type=int, default=1, help="seed of the flights")
    parser.add_argument("--scenario", default="attitude_step", help="scenario of the `stack fly` runs")
    parser.add_argument("--no-floor", action="store_true", help="skip the trivial-module floor runs")
    parser.add_argument("--quick", action="store_true", help="one run of each kind, 6 s `stack up` runs")
    args = parser.parse_args()
    if args.quick:
        args.runs, args.duration = 1, 6.0
    profile = load_profile(args.profile)
    load = os.getloadavg()
    print(f"load average {load[0]:.2f} {load[1]:.2f} {load[2]:.2f} on {os.cpu_count()} CPUs; profile {args.profile}")
    timeout = 300.0
    with tempfile.TemporaryDirectory(prefix="bench_lockstep") as tmp:
        home = Path(tmp)
        os.environ["STACK_HOME"] = str(home)  # connect() finds the stack through it
        floor_profile = home / "floor.toml"
        floor_profile.write_text(FLOOR_PROFILE)
        flights, ups, floors = [], [], []
        for i in range(args.runs):
            report = home / f"report{i}.json"
            fly_args = ["fly", args.scenario, "--profile", args.profile, "--seed", str(args.seed), "-q"]
            flight = run_stack("fly", [*fly_args, "--report", str(report)], home, timeout)
            flight.report = json.loads(report.read_text())
            flights.append(flight)
            up_args = ["up", args.profile, "--duration", str(args.duration), "-q"]
            ups.append(run_stack("up", up_args, home, timeout))
            if not args.no_floor:
                floor_args = ["up", str(floor_profile), "--duration", str(args.duration), "-q"]
                floors.append(run_stack("floor", floor_args, home, timeout))
            print(f"run {i + 1}/{args.runs} done", flush=True)
    print_runs([*flights, *ups, *floors])
    print_modules("fly", flights)
    print_modules("up (disarmed)", ups)
    module_count = len(flights[0].window()[1].cpu) - 1
    where_the_time_goes(flights, floors, module_count, algorithms_cpu_per_step(profile, args.seed))


if __name__ == "__main__":
    main()
