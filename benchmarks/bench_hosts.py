"""A vehicle spread over hosts: lockstep speed, hop latency, host-loss detection and CPU per host.

Run as root with ``python benchmarks/bench_hosts.py`` (``--quick``: one seed, shorter latency runs, one trial of
each loss; ``--seeds N``: N seeds of the flights). The hosts are Linux network namespaces joined by veth links to a
bridge (tests/support/hosts.py): ``sim`` is 10.88.0.1, ``control`` 10.88.0.2; they share the machine's kernel, its
cores and its monotonic clock. Every figure is printed, none is asserted: on a shared two-core machine they move
with the other work.

1. Lockstep real-time factor of ``takeoff_land``, per seed: ``stack fly takeoff_land --seed S`` on one host (the
   machine itself, a temporary STACK_HOME) against the same flight split over the hosts ``sim`` and ``control``
   (tests/hosts/split.py ``fly_across_hosts``: the simulator, the estimators and the scenario on ``sim``, flight
   control over Zenoh on ``control``). Both record the flight (``--record``: the split flight always does), so they
   do the same work. The factor is the scenario's own (simulated over wall time from its first step to its end, the
   report's ``realtime_factor``); the worst and the median over the seeds, and whether each flight passed. The split
   flight is flown three times: over plain TCP, and with the links between the hosts on mutual TLS from a keystore
   (an identity per host) with its access rules (``[security] keystore``, stack.security), their denials counted
   (the default) and not (``count_denials = false``).
2. One-way latency of one hop of a 64-byte message, 200 Hz for a few seconds: the publisher puts its sequence number
   and ``time.monotonic_ns()`` in the payload, the subscriber takes ``time.monotonic_ns()`` in its callback (one
   kernel clock: receive minus send is the one-way time). Both are Zenoh peers as the stack's modules are
   (``BusConfig(mode="peer", connect=(router,), listen=("tcp/127.0.0.1:0",))``, the stack's low-latency transport,
   ``express`` puts with blocking congestion control as its reliable topics), each a process of its own started
   in a host's namespace. Paths: ``peer to peer`` (one host, the publisher also connects to the subscriber, as a
   module connects to those started before it), ``via the router`` (one host, both clients of the host's router,
   as the stack's tools are: a router does not route between two of its peers, which it takes for a mesh),
   ``across hosts`` (publisher on ``sim``, subscriber on ``control``, each a peer of its own host's router, the
   two routers connected to each other over the veth links: peer, router, router, peer), and ``across, mTLS`` (the
   same with the routers' link on mutual TLS, with access rules), and ``mTLS uncounted`` (their denials not counted:
   ``count_denials = false``). The routers are
   ``stack router PROFILE --host NAME``; a peer reads its router's loopback endpoint from the router's state file.
   Printed: p50, p99, max, messages received, lost (sent minus received) and duplicates (a sequence number twice).
3. Host-loss detection: routers on both hosts, a process on ``control`` holding a liveliness token, a liveliness
   subscriber on ``sim`` (each a peer of its host's router). ``ip link set eth0 down`` on ``control`` (no TCP reset
   reaches anyone: only the lease notices), T0 taken as the command returns; the time until the subscriber sees
   the token's DELETE (its own receive time), with the profile's ``[bus] lease_ms`` 1000 and the default 10000 (the
   lease of the sessions; the routers between hosts keep theirs at ROUTER_LEASE_BETWEEN_HOSTS_MS, 30 s, so a cut
   shorter than that heals on the same link, and no DELETE comes); then the link goes up again and the time until
   the token is seen again. Also a SIGKILL of the token holder (its socket closes: no lease involved). Then the
   stack's own detection (stack.bus.host_beats): a process on ``control`` beats as a supervisor does, a watcher on
   ``sim`` is a ``HostWatch`` looked at every 10 ms as the commander does; the time from the cut until it counts
   ``control`` lost, and from the link up until it is back.
4. CPU per host during the split flight of item 1. A sampler thread reads, every 0.1 s, which processes are in each
   host's namespace (``/proc/PID/ns/net`` against ``/run/netns/NS``) and each one's CPU time (user + system, all
   threads; psutil). A host's cumulative CPU at a sample is the sum over every process seen so far of its latest
   CPU time (an exited process keeps its last reading). The flight's window comes from the scenario itself: it
   ends when ``scenario_result.json`` in the run directory is written (its mtime) and started ``wall_time_s``
   earlier (the scenario's first lockstep step); the cumulative CPU is interpolated linearly at both ends, so the
   start-up (each process's imports) and the shutdown are left out. No process of the stack starts or ends within
   the window, so the 0.1 s between samples loses nothing. Printed per host: CPU seconds per simulated second and
   cores used; the one-host flight is measured the same way, its processes being this script's descendants.
"""

from __future__ import annotations

import argparse
import json
import os
import queue
import shutil
import signal
import statistics
import subprocess
import sys
import tempfile
import threading
import time
from collections.abc import Callable
from pathlib import Path

import psutil

REPO = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(REPO))

from stack.bus.config import ROUTER_LEASE_BETWEEN_HOSTS_MS  # noqa: E402
from stack.bus.host_beats import DEFAULT_LEASE_MS  # noqa: E402
from stack.security.keystore import init_keystore, issue_identity  # noqa: E402
from tests.hosts.split import fly_across_hosts, split_profile  # noqa: E402
from tests.support.harness import run_cli, stack_env  # noqa: E402
from tests.support.hosts import Host, Network  # noqa: E402

SCENARIO = "takeoff_land"
FLY_TIMEOUT_S = 600.0
SAMPLE_S = 0.1
LEASES_MS = (1000, 10000)
HOP_RATE_HZ = 200.0
HOP_SIZE = 64
PEER_PORT = 7460  # the subscriber's own listening port inside a host's namespace (nothing else there)

# --- processes run on the hosts (python -c SCRIPT CONFIG_JSON) -------------------------------------------------------

COMMON = """
import json, os, struct, sys, time
import zenoh
from stack.bus.config import BusConfig
cfg = json.loads(sys.argv[1])
bus = BusConfig(mode=cfg["mode"], connect=tuple(cfg["connect"]), listen=tuple(cfg["listen"]), lease_ms=cfg["lease_ms"])
session = zenoh.open(bus.zenoh_config(cfg["name"]))
"""

PUBLISHER = COMMON + """
pub = session.declare_publisher(cfg["key"], express=True, congestion_control=zenoh.CongestionControl.BLOCK)
deadline = time.monotonic() + 30
while not pub.matching_status.matching:
    if time.monotonic() > deadline:
        sys.exit("no subscriber matched")
    time.sleep(0.02)
time.sleep(0.5)  # every route settled
period_ns, pad = 1e9 / cfg["rate"], bytes(cfg["size"] - 16)
start = time.monotonic_ns()
for seq in range(cfg["count"]):
    due = start + int(seq * period_ns)
    while (now := time.monotonic_ns()) < due:
        time.sleep((due - now) * 1e-9)
    pub.put(struct.pack("<qq", seq, time.monotonic_ns()) + pad)
time.sleep(0.5)
session.close()
"""

SUBSCRIBER = COMMON + """
got = []
def on_sample(sample):
    now = time.monotonic_ns()
    seq, sent = struct.unpack_from("<qq", sample.payload.to_bytes())
    got.append((seq, now - sent))
sub = session.declare_subscriber(cfg["key"], on_sample)
print("ready", flush=True)
while not os.path.exists(cfg["done"]):
    time.sleep(0.05)
sub.undeclare()
with open(cfg["out"], "w") as f:
    json.dump(got, f)
session.close()
"""

TOKEN = COMMON + """
token = session.liveliness().declare_token(cfg["key"])
print("ready", flush=True)
while True:
    time.sleep(1)
"""

BEATER = COMMON + """
from stack.bus.host_beats import BEAT_PERIOD_S, beat_key
pub = session.declare_publisher(beat_key("v1", "control"))
print("ready", flush=True)
while True:
    pub.put(b"")
    time.sleep(BEAT_PERIOD_S)
"""

BEAT_WATCHER = COMMON + """
from stack.bus.host_beats import DEFAULT_LEASE_MS, HostWatch, beat_host, beats_key
watch = HostWatch({"sim": [], "control": ["mc_rate_control"]}, "sim", DEFAULT_LEASE_MS)
def on_sample(sample):
    host = beat_host(str(sample.key_expr), "v1")
    if host is not None:
        watch.beat(host, time.monotonic_ns() // 1000)
sub = session.declare_subscriber(beats_key("v1"), on_sample)
while True:
    time.sleep(0.01)  # as often as the commander looks (100 Hz)
    for change in watch.update(time.monotonic_ns() // 1000):
        print("DELETE" if change.lost else "PUT", time.monotonic_ns(), flush=True)
"""

WATCHER = COMMON + """
def on_sample(sample):
    kind = "DELETE" if sample.kind == zenoh.SampleKind.DELETE else "PUT"
    print(kind, time.monotonic_ns(), sample.key_expr, flush=True)
sub = session.liveliness().declare_subscriber(cfg["key"], on_sample, history=True)
while True:
    time.sleep(1)
"""


def script_on(host: Host, script: str, cfg: dict, **kw: object) -> subprocess.Popen[str]:
    return host.popen(sys.executable, "-c", script, json.dumps(cfg), env=stack_env(host.home), cwd=REPO, **kw)


def peer(name: str, router: str, lease_ms: int = 10000, listen: str = "tcp/127.0.0.1:0", *more: str) -> dict:
    """A session as a module's: a peer of its host's router (and of ``more``), listening on ``listen``."""
    return {"mode": "peer", "name": name, "connect": [router, *more], "listen": [listen], "lease_ms": lease_ms}


def client(name: str, router: str) -> dict:
    """A session as a tool's: a client of its host's router."""
    return {"mode": "client", "name": name, "connect": [router], "listen": [], "lease_ms": 10000}


def stop(proc: subprocess.Popen[str], timeout: float = 10.0) -> None:
    if proc.poll() is None:
        proc.terminate()
        try:
            proc.wait(timeout)
        except subprocess.TimeoutExpired:
            proc.kill()
            proc.wait()


# --- routers -------------------------------------------------------------------------------------------------------


class Routers:
    """``stack router PROFILE --host NAME`` on each host of ``net``, the profile's ``[bus] lease_ms`` given; with
    ``keystore``, linked over mutual TLS with its access rules (else plain TCP, ``--insecure``)."""

    def __init__(
        self, net: Network, work: Path, lease_ms: int, keystore: Path | None = None, count_denials: bool = True
    ) -> None:
        counting = f"count_denials = {str(count_denials).lower()}\n"
        secure = f'[security]\nkeystore = "{keystore}"\n{counting}' if keystore is not None else ""
        tag = f"{lease_ms}{'-tls' if keystore else ''}{'' if count_denials else '-uncounted'}"
        profile = split_profile(work / f"routers-{tag}.toml", net, f"\n[bus]\nlease_ms = {lease_ms}\n{secure}")
        self.procs: dict[str, subprocess.Popen[str]] = {}
        self.endpoints: dict[str, str] = {}
        plain = () if keystore else ("--insecure",)
        for name, host in net.hosts.items():
            log = (work / f"router-{name}-{tag}.log").open("w")
            self.procs[name] = host.popen(
                sys.executable, "-m", "stack", "router", str(profile), "--host", name, *plain,
                env=stack_env(host.home), cwd=REPO, stdout=log, stderr=subprocess.STDOUT,
            )  # fmt: skip
        for name, host in net.hosts.items():
            self.endpoints[name] = self._endpoint(host, self.procs[name])

    @staticmethod
    def _endpoint(host: Host, proc: subprocess.Popen[str], timeout: float = 60.0) -> str:
        """The loopback endpoint the router listens on, from its state file (STACK_HOME/state/*.json)."""
        deadline = time.monotonic() + timeout
        while time.monotonic() < deadline:
            if proc.poll() is not None:
                raise SystemExit(f"the router of host {host.name} exited ({proc.returncode})")
            for path in (host.home / "state").glob("*.json"):
                try:
                    state = json.loads(path.read_text())
                except (OSError, ValueError):
                    continue  # being written
                if state.get("pid") == proc.pid and state.get("endpoint"):
                    return state["endpoint"]
            time.sleep(0.05)
        raise SystemExit(f"the router of host {host.name} wrote no state within {timeout:g} s")

    def close(self) -> None:
        for proc in self.procs.values():
            stop(proc)


# --- CPU per host --------------------------------------------------------------------------------------------------


def namespace_members(netns: str) -> Callable[[], list[int]]:
    """The processes in the network namespace ``netns``, found through /proc (cheaper than ``ip netns pids``)."""
    inode = os.stat(f"/run/netns/{netns}").st_ino

    def members() -> list[int]:
        pids = []
        for entry in os.listdir("/proc"):
            if entry.isdigit():
                try:
                    if os.stat(f"/proc/{entry}/ns/net").st_ino == inode:
                        pids.append(int(entry))
                except OSError:
                    pass
        return pids

    return members


def descendants() -> list[int]:
    return [p.pid for p in psutil.Process().children(recursive=True)]


class CpuSampler(threading.Thread):
    """Every SAMPLE_S, each group's cumulative CPU seconds: every process seen so far at its latest reading."""

    def __init__(self, groups: dict[str, Callable[[], list[int]]]) -> None:
        super().__init__(daemon=True)
        self.groups = groups
        self.latest: dict[str, dict[tuple[int, float], float]] = {g: {} for g in groups}
        self.samples: list[tuple[float, dict[str, float]]] = []  # (time.time(), group → cumulative CPU s)
        self.procs: dict[int, psutil.Process] = {}
        self._halt = threading.Event()

    def run(self) -> None:
        while not self._halt.wait(SAMPLE_S):
            now = time.time()
            for group, members in self.groups.items():
                for pid in members():
                    try:
                        proc = self.procs.get(pid) or self.procs.setdefault(pid, psutil.Process(pid))
                        times = proc.cpu_times()
                        key = (pid, proc.create_time())  # a pid used again is another process
                    except psutil.Error:
                        continue
                    self.latest[group][key] = times.user + times.system
            self.samples.append((now, {g: sum(v.values()) for g, v in self.latest.items()}))

    def stop(self) -> None:
        self._halt.set()
        self.join()

    def at(self, group: str, t: float) -> float:
        """The group's cumulative CPU seconds at the wall time ``t``, interpolated between samples."""
        before = [(s, c[group]) for s, c in self.samples if s <= t]
        after = [(s, c[group]) for s, c in self.samples if s > t]
        if not before or not after:
            raise SystemExit(f"no CPU samples around the flight's {'start' if not before else 'end'}")
        (t0, c0), (t1, c1) = before[-1], after[0]
        return c0 + (c1 - c0) * (t - t0) / (t1 - t0)


def flight_window(report: dict) -> tuple[float, float]:
    """The scenario's first and last step in wall time (its result file is written at the last)."""
    end = (Path(report["run_dir"]) / "scenario_result.json").stat().st_mtime
    return end - report["wall_time_s"], end


def cpu_in_flight(sampler: CpuSampler, report: dict) -> dict[str, tuple[float, float]]:
    """Group → (CPU seconds per simulated second, cores) over the flight."""
    start, end = flight_window(report)
    out = {}
    for group in sampler.groups:
        cpu = sampler.at(group, end) - sampler.at(group, start)
        out[group] = (cpu / report["sim_time_s"], cpu / (end - start))
    return out


# --- 1 and 4: flights ----------------------------------------------------------------------------------------------


def fly_one_host(seed: int, work: Path) -> tuple[dict, dict[str, tuple[float, float]]]:
    home = work / f"one-{seed}"
    home.mkdir()
    report = home / "report.json"
    sampler = CpuSampler({"machine": descendants})
    sampler.start()
    try:
        out = run_cli(
            home, "fly", SCENARIO, "--seed", str(seed), "-q", "--report", str(report),
            "--record", str(home / "flight.mcap"), timeout=FLY_TIMEOUT_S,
        )  # fmt: skip
    finally:
        sampler.stop()
    if not report.exists():
        raise SystemExit(f"one host, seed {seed}: no report (exit {out.returncode}):\n{out.stdout}{out.stderr}")
    result = json.loads(report.read_text())
    return result, cpu_in_flight(sampler, result)


def fly_split(
    net: Network, seed: int, work: Path, keystore: Path | None = None, count_denials: bool = True
) -> tuple[dict, dict[str, tuple[float, float]]]:
    where = work / f"split-{seed}{'-tls' if keystore else ''}{'' if count_denials else '-uncounted'}"
    where.mkdir()
    sampler = CpuSampler({name: namespace_members(h.netns) for name, h in net.hosts.items()})
    sampler.start()
    try:
        flight = fly_across_hosts(net, SCENARIO, seed, where, keystore, count_denials)
    finally:
        sampler.stop()
    return flight.report, cpu_in_flight(sampler, flight.report)


def flights(net: Network, seeds: list[int], work: Path, keystore: Path) -> None:
    print(f"\n1. lockstep real-time factor of {SCENARIO} (the scenario's; the recorder on in all)")
    print(
        f"{'seed':>4} {'one host':>9} {'passed':>6} {'2 hosts':>8} {'passed':>6} {'mTLS':>6} {'passed':>6}"
        f" {'uncounted':>9} {'passed':>6}"
    )
    ones, splits, tls, uncounted, cpu_one, cpu_split = [], [], [], [], [], []
    for seed in seeds:
        one, cpu = fly_one_host(seed, work)
        ones.append(one["realtime_factor"])
        cpu_one.append(cpu)
        split, cpu = fly_split(net, seed, work)
        splits.append(split["realtime_factor"])
        cpu_split.append(cpu)
        secure, _ = fly_split(net, seed, work, keystore)
        tls.append(secure["realtime_factor"])
        quiet, _ = fly_split(net, seed, work, keystore, count_denials=False)
        uncounted.append(quiet["realtime_factor"])
        print(
            f"{seed:>4} {ones[-1]:>9.2f} {one['passed']!s:>6} {splits[-1]:>8.2f} {split['passed']!s:>6}"
            f" {tls[-1]:>6.2f} {secure['passed']!s:>6} {uncounted[-1]:>9.2f} {quiet['passed']!s:>6}",
            flush=True,
        )
    print(
        f"{'worst':>4} {min(ones):>9.2f} {'':>6} {min(splits):>8.2f} {'':>6} {min(tls):>6.2f} {'':>6}"
        f" {min(uncounted):>9.2f}"
    )
    print(
        f"{'med.':>4} {statistics.median(ones):>9.2f} {'':>6} {statistics.median(splits):>8.2f} {'':>6}"
        f" {statistics.median(tls):>6.2f} {'':>6} {statistics.median(uncounted):>9.2f}"
    )
    print("\n4. CPU during the flights (first to last step), CPU s per simulated s and cores; mean of seeds")
    rows = [("one host", "machine", cpu_one)] + [(f"2 hosts: {h}", h, cpu_split) for h in net.hosts]
    for label, group, per_seed in rows:
        per_sim = statistics.fmean(c[group][0] for c in per_seed)
        cores = statistics.fmean(c[group][1] for c in per_seed)
        print(f"  {label:<17} {per_sim:6.3f} CPU s per sim s, {cores:5.2f} cores")
    total = statistics.fmean(sum(c[h][0] for h in net.hosts) for c in cpu_split)
    print(f"  {'2 hosts: both':<17} {total:6.3f} CPU s per sim s")


# --- 2: hop latency ------------------------------------------------------------------------------------------------


def hop(pub_host: Host, pub_cfg: dict, sub_host: Host, sub_cfg: dict, count: int, work: Path, label: str) -> None:
    tag = label.replace(" ", "-")
    out, done = work / f"hop-{tag}.json", work / f"hop-{tag}.done"
    key = f"stack/bench/sensor_gyro/{tag}"  # a topic of the simulator's host, which its access rules let it publish
    sub = script_on(sub_host, SUBSCRIBER, {**sub_cfg, "key": key, "out": str(out), "done": str(done)},
                    stdout=subprocess.PIPE)  # fmt: skip
    try:
        assert sub.stdout is not None
        if sub.stdout.readline().strip() != "ready":
            raise SystemExit(f"{label}: the subscriber did not start ({sub.wait()})")
        pub_cfg = {**pub_cfg, "key": key, "rate": HOP_RATE_HZ, "size": HOP_SIZE, "count": count}
        pub = script_on(pub_host, PUBLISHER, pub_cfg)
        if pub.wait(timeout=count / HOP_RATE_HZ + 60) != 0:
            raise SystemExit(f"{label}: the publisher failed ({pub.returncode})")
        done.touch()
        sub.wait(timeout=30)
    finally:
        stop(sub)
    got = json.loads(out.read_text())
    seqs = [s for s, _ in got]
    lat = sorted(d * 1e-3 for _, d in got)  # µs
    dup = len(seqs) - len(set(seqs))
    lost = count - len(set(seqs))
    if not lat:
        print(f"  {label:<16} nothing received of {count}")
        return
    p = statistics.quantiles(lat, n=100, method="inclusive") if len(lat) > 1 else [lat[0]] * 99
    print(
        f"  {label:<16} {p[49]:>8.0f} {p[98]:>8.0f} {lat[-1]:>8.0f} {len(got):>6} {lost:>5} {dup:>5}"
        f"{'' if seqs == sorted(seqs) else '  (out of order)'}",
        flush=True,
    )


def latencies(net: Network, seconds: float, work: Path, keystore: Path) -> None:
    sim, control = net.hosts["sim"], net.hosts["control"]
    count = round(seconds * HOP_RATE_HZ)
    print(f"\n2. one-way hop latency, {HOP_SIZE}-byte messages at {HOP_RATE_HZ:g} Hz, {count} sent per path (µs)")
    print(f"  {'path':<16} {'p50':>8} {'p99':>8} {'max':>8} {'recv':>6} {'lost':>5} {'dup':>5}")
    routers = Routers(net, work, 10000)
    try:
        r = routers.endpoints
        direct = f"tcp/127.0.0.1:{PEER_PORT}"
        hop(sim, peer("bench-pub", r["sim"], 10000, "tcp/127.0.0.1:0", direct), sim,
            peer("bench-sub", r["sim"], 10000, direct), count, work, "peer to peer")  # fmt: skip
        hop(sim, client("bench-pub", r["sim"]), sim, client("bench-sub", r["sim"]), count, work, "via the router")
        hop(sim, peer("bench-pub", r["sim"]), control, peer("bench-sub", r["control"]), count, work, "across hosts")
    finally:
        routers.close()
    for count_denials, label in ((True, "across, mTLS"), (False, "mTLS uncounted")):
        routers = Routers(net, work, 10000, keystore, count_denials)
        try:
            r = routers.endpoints
            hop(sim, peer("bench-pub", r["sim"]), control, peer("bench-sub", r["control"]), count, work, label)
        finally:
            routers.close()


# --- 3: host-loss detection ----------------------------------------------------------------------------------------


class Watcher:
    """The liveliness subscriber's lines: (kind, its receive time in ns)."""

    def __init__(self, proc: subprocess.Popen[str]) -> None:
        self.proc = proc
        self.events: queue.Queue[tuple[str, int]] = queue.Queue()
        threading.Thread(target=self._read, daemon=True).start()

    def _read(self) -> None:
        assert self.proc.stdout is not None
        for line in self.proc.stdout:
            fields = line.split()
            if len(fields) >= 2 and fields[1].isdigit():  # anything else it prints (a warning) is no event
                self.events.put((fields[0], int(fields[1])))

    def wait_for(self, kind: str, timeout: float) -> int | None:
        deadline = time.monotonic() + timeout
        while (left := deadline - time.monotonic()) > 0:
            try:
                got, ns = self.events.get(timeout=left)
            except queue.Empty:
                break
            if got == kind:
                return ns
        return None


def fmt_s(since_ns: int, at_ns: int | None) -> str:
    return "not seen" if at_ns is None else f"{(at_ns - since_ns) * 1e-9:6.3f} s"


def host_loss(net: Network, trials: int, work: Path) -> None:
    sim, control = net.hosts["sim"], net.hosts["control"]
    print("\n3. host-loss detection: a liveliness token on host control, watched from host sim")
    for lease in LEASES_MS:
        routers = Routers(net, work, lease)
        token = watcher = None
        try:
            key = "bench/alive/control"
            watcher_proc = script_on(sim, WATCHER, {**peer("bench-watch", routers.endpoints["sim"], lease), "key": key},
                                     stdout=subprocess.PIPE)  # fmt: skip
            watcher = Watcher(watcher_proc)
            holder = {**peer("bench-token", routers.endpoints["control"], lease), "key": key}
            token = script_on(control, TOKEN, holder, stdout=subprocess.DEVNULL)
            if watcher.wait_for("PUT", 60) is None:
                raise SystemExit(f"lease {lease} ms: the token was never seen from host sim")
            for _ in range(trials):
                control.link_down()
                t0 = time.monotonic_ns()
                gone = watcher.wait_for("DELETE", lease * 3e-3 + 10)
                control.link_up()
                t1 = time.monotonic_ns()
                if gone is None:  # the routers' link outlived the cut: the token never left
                    print(
                        f"  lease {lease:>5} ms, link down {(t1 - t0) / 1e9:.1f} s: no DELETE (the routers between"
                        f" hosts keep their link {ROUTER_LEASE_BETWEEN_HOSTS_MS / 1000:.0f} s); link up: carried on",
                        flush=True,
                    )
                    continue
                back = watcher.wait_for("PUT", 60)
                print(
                    f"  lease {lease:>5} ms, link down: DELETE after {fmt_s(t0, gone)};"
                    f" after link up, seen again after {fmt_s(t1, back)}",
                    flush=True,
                )
                if back is None:
                    raise SystemExit("the hosts did not reconnect")
            for _ in range(trials):
                token.kill()
                t0 = time.monotonic_ns()
                token.wait()
                gone = watcher.wait_for("DELETE", 30)
                print(f"  lease {lease:>5} ms, holder SIGKILLed: DELETE after {fmt_s(t0, gone)}", flush=True)
                token = script_on(control, TOKEN, holder, stdout=subprocess.DEVNULL)
                if watcher.wait_for("PUT", 60) is None:
                    raise SystemExit("the restarted token was never seen")
        finally:
            control.link_up()
            for proc in (token, watcher.proc if watcher else None):
                if proc is not None:
                    stop(proc)
            routers.close()
    beats(net, trials, work)


def beats(net: Network, trials: int, work: Path) -> None:
    """The stack's own host-loss detection (stack.bus.host_beats): beats every 0.1 s through the routers, lost after
    the profile's host lease (the default, with the routers' default Zenoh lease)."""
    sim, control = net.hosts["sim"], net.hosts["control"]
    routers = Routers(net, work, 10000)
    beater = watcher = None
    try:
        watcher = Watcher(
            script_on(sim, BEAT_WATCHER, peer("bench-beat-watch", routers.endpoints["sim"]), stdout=subprocess.PIPE)
        )
        beater = script_on(control, BEATER, peer("bench-beat", routers.endpoints["control"]), stdout=subprocess.DEVNULL)
        time.sleep(2.0)  # the beats flowing (a host never heard is not lost)
        for _ in range(trials):
            control.link_down()
            t0 = time.monotonic_ns()
            lost = watcher.wait_for("DELETE", 10)
            control.link_up()
            t1 = time.monotonic_ns()
            back = watcher.wait_for("PUT", 60)
            print(
                f"  host beats, lease {DEFAULT_LEASE_MS} ms, link down: lost after {fmt_s(t0, lost)};"
                f" after link up, back after {fmt_s(t1, back)}",
                flush=True,
            )
            time.sleep(1.0)
    finally:
        control.link_up()
        for proc in (beater, watcher.proc if watcher else None):
            if proc is not None:
                stop(proc)
        routers.close()


def host_keystore(net: Network, root: Path) -> Path:
    """A keystore with an identity for each host of ``net``, valid at its address."""
    init_keystore(root)
    for host in net.hosts.values():
        issue_identity(root, host.name, "host", (host.address,))
    return root


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="one seed, 2 s latency runs, one trial of each loss")
    parser.add_argument("--seeds", type=int, default=None, help="seeds of the flights (default 3, --quick 1)")
    args = parser.parse_args()
    if not hasattr(os, "geteuid") or os.geteuid() != 0 or shutil.which("ip") is None:
        print("bench_hosts needs root and iproute2's `ip` (its hosts are network namespaces)", file=sys.stderr)
        sys.exit(2)
    seeds = list(range(1, (args.seeds or (1 if args.quick else 3)) + 1))
    seconds, trials = (2.0, 1) if args.quick else (5.0, 2)
    load = os.getloadavg()
    print(f"load average {load[0]:.2f} {load[1]:.2f} {load[2]:.2f} on {os.cpu_count()} CPUs; seeds {seeds}")
    started = time.monotonic()
    with tempfile.TemporaryDirectory(prefix="bench_hosts") as tmp:
        work = Path(tmp)
        net = Network(["sim", "control"], work / "hosts")
        previous = signal.signal(signal.SIGTERM, lambda *_: sys.exit(143))
        try:
            net.start()
            keystore = host_keystore(net, work / "keys")
            flights(net, seeds, work, keystore)
            latencies(net, seconds, work, keystore)
            host_loss(net, trials, work)
        finally:
            net.close()
            signal.signal(signal.SIGTERM, previous)
    print(f"\n({time.monotonic() - started:.0f} s)")


if __name__ == "__main__":
    main()
