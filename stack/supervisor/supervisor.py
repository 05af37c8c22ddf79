"""The supervisor behind ``stack up``: it starts a profile's modules as processes and watches them.

Like PX4's rcS it starts the modules in order, each when the previous one reports ready. It is the
bus rendezvous (a Zenoh peer listening on 127.0.0.1), publishes the roster lockstep waits for,
answers ``stack status``, restarts crashed modules with backoff where the profile says so, and
stops everything in reverse order (in lockstep, the simulator first, freezing time) on Ctrl-C,
SIGTERM or ``--duration``, escalating to SIGKILL. No module outlives it: each asks the kernel for
SIGTERM when its parent dies. A profile's ``[[process]]`` programs (not modules: the simulated Pixhawk)
start before the modules, are watched and restarted alike, stop after them, and die with it too
(:mod:`stack.supervisor.child`).
"""

from __future__ import annotations

import contextlib
import json
import logging
import os
import secrets
import signal
import socket
import subprocess
import sys
import threading
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import IO

import msgspec
import zenoh

from stack.bus import keys
from stack.bus.alive import AliveTokens
from stack.bus.config import LOOPBACK_ANY_PORT, BusConfig, open_router, without_link_options
from stack.bus.host_beats import BEAT_PERIOD_S, STOPPING, HostWatch, beat_host, beat_key, beats_key
from stack.bus.ports import free_port, hold_again, hold_port, port_taken
from stack.bus.query import answer
from stack.bus.supervisors import SINGLE_HOST, complete_roster, rosters
from stack.bus.timebase import (
    OFFSET_FILE_ENV,
    RESYNC_PERIOD_S,
    SKEW_WARN_US,
    SYNC_SAMPLES,
    ClockSample,
    OffsetEstimate,
    SharedOffset,
    estimate_offset,
    slew,
)
from stack.fastpath.host import FastPathHost
from stack.msg.internal import ModuleHeartbeat
from stack.runtime.cpu_wake import AwakeCpus
from stack.runtime.module import LINK_SUFFIX
from stack.runtime.pacing import MAX_SPEED
from stack.runtime.spec import ModuleSpec
from stack.runtime.stop_event import StopEvent
from stack.security.denials import Denial, DenialCounts
from stack.supervisor import state as run_state
from stack.supervisor.profile import ModuleEntry, ProcessEntry, Profile, expand_placeholders

log = logging.getLogger("stack.supervisor")

START_TIMEOUT_S = 60.0
# Module processes started ahead of their turn: each loads its code while the ones before it start, and
# waits for its go (see stack.runtime.main). More would only share the two cores' start-up work thinner.
PRESTART_AHEAD = 2
STOP_GRACE_S = 5.0
BACKOFF_MAX_S = 10.0
# How often the supervisor checks its modules (and applies topic-graph changes to a fast-path run).
MONITOR_PERIOD_S = 0.05
ROUTER_PORT_ATTEMPTS = 5
# A stack whose start-up a signal interrupted exits as a shell reports a program killed by it (130: SIGINT).
INTERRUPTED_EXIT_BASE = 128


@dataclass
class UpOptions:
    duration: float | None = None
    log_level: str = "INFO"
    echo_logs: bool = True
    echo_only: tuple[str, ...] = ()
    kind: str = run_state.UP  # the command that started the stack, registered in its state
    extra_args: dict[str, dict[str, object]] = field(default_factory=dict)
    speed: float = MAX_SPEED  # the lockstep's pace (stack.runtime.pacing)
    world: str = ""  # a swarm's world clock (stack.runtime.world_clock): its file, this vehicle's slot, the vehicles
    world_slot: int = -1
    world_vehicles: tuple[str, ...] = ()


@dataclass
class ModuleProcess:
    entry: ModuleEntry
    spec_path: Path
    log_path: Path
    process: str
    """The OS process it runs in: its own name, or the group it shares a process with (``process = "NAME"``)."""
    proc: subprocess.Popen | None = None
    state: str = "stopped"
    restarts: int = 0
    failures: int = 0
    exit_code: int | None = None
    restart_at: float | None = None
    reader: threading.Thread | None = None

    @property
    def pid(self) -> int:
        return self.proc.pid if self.proc is not None else 0


@dataclass
class ProgramProcess:
    """A running ``[[process]]`` (see :class:`ModuleProcess`)."""

    entry: ProcessEntry
    log_path: Path
    proc: subprocess.Popen | None = None
    state: str = "stopped"
    restarts: int = 0
    failures: int = 0
    exit_code: int | None = None
    restart_at: float | None = None
    reader: threading.Thread | None = None

    @property
    def pid(self) -> int:
        return self.proc.pid if self.proc is not None else 0


class Supervisor:
    """The supervisor of one host's share of the vehicle (``host``; the whole vehicle in a profile without hosts).

    In a shared-memory lockstep run the shared memory is on the coordinator's host: the members on other hosts
    take part over Zenoh (:mod:`stack.fastpath.bridge`), and that host's supervisor gives the run its id, which
    the others ask for before they start anything.
    """

    def __init__(self, profile: Profile, options: UpOptions, run_dir: Path, host: str | None = None) -> None:
        self.profile = profile
        self.options = options
        self.run_dir = run_dir
        self.vehicle = profile.vehicle
        self.host = host or SINGLE_HOST
        here = [e for e in profile.modules if not profile.hosts or e.host == host]
        self._set_port(profile.port or free_port())
        coordinator = next((e for e in profile.modules if e.cls.LOCKSTEP_COORDINATOR), None)
        self.leads = coordinator is None or any(e is coordinator for e in here)
        # Whose clock is the vehicle's time base across hosts (stack.bus.timebase): the coordinator's host.
        self.leader = coordinator.host if coordinator is not None and profile.hosts else self.host
        # A shared-memory lockstep run, in which a member may take part over Zenoh (stack.fastpath.bridge), as every
        # member on another host does. Modules share a process in real time, or on this shared memory (see
        # stack.supervisor.profile).
        self.shm_run = profile.lockstep and profile.lockstep_transport == "shm"
        self.grouping = not profile.lockstep or (self.shm_run and self.leads)
        self.bridged = []
        if self.shm_run and coordinator is not None:
            over_zenoh = [e for e in profile.modules if e.transport == "zenoh" or e.host != coordinator.host]
            self.bridged = [e.name for e in over_zenoh if _is_member(e)]
        self.coordinator = coordinator.name if self.bridged and coordinator is not None else None
        self.modules = []
        for e in here:
            process = e.process if e.process and self.grouping else e.name
            self.modules.append(ModuleProcess(e, run_dir / f"{e.name}.spec.json", run_dir / f"{process}.log", process))
        self.groups: dict[str, list[ModuleProcess]] = {}
        for m in self.modules:
            self.groups.setdefault(m.process, []).append(m)
            if m.process != m.entry.name:
                # Where a module's log is looked for (<module>.log), its process's.
                (run_dir / f"{m.entry.name}.log").symlink_to(m.log_path.name)
        local_mesh = profile.bus.mode == "peer" and profile.bus.listen == (LOOPBACK_ANY_PORT,)
        # Held until each process is let go (_go): a stack starting meanwhile cannot take a later module's port.
        self._port_holds = {process: hold_port() for process in self.groups} if local_mesh else {}
        self._process_ports = {process: int(held.getsockname()[1]) for process, held in self._port_holds.items()}
        ports = self._process_ports
        self.module_endpoints = {m.entry.name: f"tcp/127.0.0.1:{ports[m.process]}" for m in self.modules if ports}
        self.programs = [
            ProgramProcess(e, run_dir / f"{e.name}.log")
            for e in profile.processes
            if not profile.hosts or e.host == host
        ]
        self.placeholders = {
            "python": sys.executable,
            "run_dir": str(run_dir),
            "seed": str(profile.seed),
            "udp_port": str(free_port(kind=socket.SOCK_DGRAM)),
            "control_port": str(free_port(kind=socket.SOCK_DGRAM)),
        }
        self.roster_complete = False
        self.failed = False
        # The vehicle's modules, on every host, with the topics each publishes, whose messages its modules accept
        # (stack.bus.access): the profile's, and those the coordinator's host added (a flight's scenario, observers).
        self.vehicle_modules = profile.publishers()
        # The lockstep run's id, and its same-host shared-memory fast path (stack.fastpath) unless the
        # profile sends lockstep traffic over Zenoh.
        self.run_id = secrets.randbits(63) | 1
        self.fast: FastPathHost | None = None
        self._stop = StopEvent()  # set by the signal handler
        self._signal: int | None = None  # the signal that stopped the stack, if one did
        self._alive: dict[str, int] = {}
        self._alive_changed = threading.Condition()
        self._alive_tokens = AliveTokens(self.vehicle, self._say)
        self._heartbeats: dict[str, ModuleHeartbeat] = {}
        self._print_lock = threading.Lock()
        self.denied = DenialCounts()  # what this host's router's access rules refused (stack.security.denials)
        self._hb_decoder = msgspec.msgpack.Decoder(ModuleHeartbeat)
        # A vehicle over several hosts: this host's beat, and the other hosts' (stack.bus.host_beats).
        self.hosts = HostWatch(profile.placement(), self.host, profile.host_lease_ms) if profile.hosts else None
        # In real time on several hosts, the vehicle's time base is the leading host's (stack.bus.timebase).
        self.clock = SharedOffset(run_dir / "clock_offset", writable=True) if profile.hosts else None
        self._offset_at: tuple[int, float] | None = None
        """(offset µs, when it was set: time.monotonic()) once measured."""

    def _set_port(self, port: int) -> None:
        self.port = port
        self.endpoint = f"tcp/127.0.0.1:{port}"
        bus = self.profile.bus
        listen, self.router_connect = self.profile.router_links(self.host) if self.profile.hosts else ((), bus.connect)
        self.router_listen = (self.endpoint, *listen)
        # Modules reach the rest of the bus through this router only: also connected to [bus] connect, a module had a
        # second route to every subscriber there, which then got each of its messages twice.
        self.module_bus = BusConfig(
            mode=bus.mode,
            connect=(self.endpoint,),
            listen=bus.listen,
            low_latency=bus.low_latency,
            lease_ms=bus.lease_ms,
        )

    @staticmethod
    def _on_fast_path(m: ModuleProcess) -> bool:
        """Whether the module takes part in the same-host fast path (a module outside the lockstep does not)."""
        return not m.entry.cls.OUTSIDE_LOCKSTEP

    def _open_router(self) -> zenoh.Session:
        """The rendezvous router; a port taken since it was picked (another stack starting at the same
        moment) is picked again, unless the profile fixed it."""
        for attempt in range(ROUTER_PORT_ATTEMPTS):
            bus = BusConfig(
                mode="router",
                connect=self.router_connect,
                listen=self.router_listen,
                low_latency=self.profile.bus.low_latency,
                lease_ms=self.profile.router_lease_ms,
                tls=self.profile.host_tls(self.host) if self.profile.hosts else {},
                access=self.profile.host_access(),
            )
            try:
                counting = self._on_denial if self.profile.count_denials else None
                return open_router(bus, "supervisor", self.profile.router_link_count, counting)
            except zenoh.ZError as e:
                if self.profile.port or attempt + 1 == ROUTER_PORT_ATTEMPTS or not port_taken(e):
                    raise
                self._set_port(free_port())
        raise AssertionError("unreachable")

    # -- entry -------------------------------------------------------------------------------------

    def run(self) -> int:
        signal.signal(signal.SIGINT, self._on_signal)
        signal.signal(signal.SIGTERM, self._on_signal)
        session = self._open_router()
        awake = self._keep_cpus_awake()
        entities = []
        beating: threading.Thread | None = None
        if self.shm_run and self.leads:
            remote = [name for name in self.bridged if name not in {m.entry.name for m in self.modules}]
            fast = [m.entry.name for m in self.modules if self._on_fast_path(m)]
            self.fast = FastPathHost([*fast, *remote], self.run_id, bridged=self.bridged)
            self.fast.watch_graph(session, self.vehicle)
        try:
            entities = [
                session.declare_queryable(self._key("roster"), self._on_roster_query),
                session.declare_queryable(self._key("status"), self._on_status_query),
                session.liveliness().declare_subscriber(keys.alive_query(self.vehicle), self._on_alive, history=True),
                session.declare_subscriber(keys.heartbeat_all(self.vehicle), self._on_heartbeat),
                session.declare_queryable(self._key("outside"), self._on_outside_query),
                session.declare_queryable(self._key("stop"), self._on_stop_query),
            ]
            if self.hosts is not None:
                entities.append(session.declare_subscriber(beats_key(self.vehicle), self._on_beat))
                if self.leader == self.host:
                    entities.append(session.declare_queryable(self._key("clock"), self._on_clock_query))
                beating = threading.Thread(target=self._beat, args=(session,), name="beat", daemon=True)
                beating.start()
            run_state.write_state(self.vehicle, self.state_record())
            self._say(f"run directory {self.run_dir}")
            self._say_groups()
            self._say(f"bus rendezvous {self.endpoint}, vehicle '{self.vehicle}'")
            if self.profile.hosts:
                self._say(f"host {self.host}: router on {', '.join(map(without_link_options, self.router_listen))}")
            if (self.leads or self._await_lead(session)) and self._sync_clock(session) and self._start_all():
                self.roster_complete = True
                if self.fast is not None and self._await_vehicle_roster(session):
                    self.fast.roster_complete()
                self._say(f"all {len(self.modules)} modules up" + (" (lockstep)" if self.profile.lockstep else ""))
                self._say_links()
                self._monitor()
            elif self._signal is not None:
                self._say_interrupted(self._signal)
            else:
                self.failed = True
        finally:
            if self._signal is not None and self.roster_complete:
                self._say(f"{signal.Signals(self._signal).name}: stopping")
            self._stop_all()
            self._stop.set()
            if beating is not None:
                beating.join()
            for entity in entities:
                entity.undeclare()
            if self.fast is not None:
                self.fast.close()
            if self.clock is not None:
                self.clock.close()
            for held in self._port_holds.values():
                held.close()
            if awake is not None:
                awake.close()
            session.close()
            run_state.remove_state(self.vehicle, os.getpid())
        if self._signal is not None and not self.roster_complete:
            self._say("stopped: start-up interrupted")
            return INTERRUPTED_EXIT_BASE + self._signal
        code = 1 if self.failed or any(r.failures for r in (*self.modules, *self.programs)) else 0
        self._say("stopped" + (" with failures" if code else ""))
        return code

    def _keep_cpus_awake(self) -> AwakeCpus | None:
        """For a lockstep run as fast as it can go, idle CPUs kept from sleeping (stack.runtime.cpu_wake) until it
        ends; None for any other run."""
        if not (self.profile.lockstep and self.options.speed == MAX_SPEED):
            return None
        awake = AwakeCpus()
        if awake.held:
            self._say("idle CPUs kept awake for the run (PM QoS CPU latency 0 µs): no wake-up delay between steps")
        else:
            self._say(f"idle CPUs may sleep between steps ({awake.refusal}): a lockstep step waits for them to wake")
        return awake

    def _key(self, what: str) -> str:
        return keys.supervisor_key(self.vehicle, self.host, what)

    def _await_lead(self, session: zenoh.Session) -> bool:
        """The run's id, seed and parameters, from the supervisor of the coordinator's host (it may start after this
        one): a flight there sets its scenario's, which are the vehicle's wherever its modules run. False if stopped
        meanwhile."""
        said = False
        while not self._stop.is_set():
            answers = [a for a in rosters(session, self.vehicle) if a["host"] != self.host and a["run_id"]]
            leader = next((a for a in answers if a["leads"]), None)
            if leader is not None:
                self.run_id = leader["run_id"]
                self.profile.seed = leader["seed"]
                for m in self.modules:
                    m.entry.params = leader["params"].get(m.entry.name, m.entry.params)
                self.vehicle_modules.update(leader["publishes"])
                self._say(f"the run of host {leader['host']}: its seed {self.profile.seed} and parameters")
                return True
            if not said:
                self._say("waiting for the host of the lockstep's coordinator to come up")
                said = True
            self._stop.wait(0.2)
        return False

    def _await_vehicle_roster(self, session: zenoh.Session) -> bool:
        """Until every host's supervisor has started its modules for this run (the lockstep starts with all of
        them); False if stopped meanwhile."""
        hosts = self.profile.hosts_with_modules()
        said = False
        while not self._stop.is_set():
            answers = rosters(session, self.vehicle) if len(hosts) > 1 else []
            if len(hosts) == 1 or complete_roster(answers, hosts, self.run_id) is not None:
                return True
            if not said:
                ready = {a["host"] for a in answers if a["run_id"] == self.run_id and a["complete"]}
                self._say(f"waiting for hosts {', '.join(h for h in hosts if h not in ready)} to start their modules")
                said = True
            self._stop.wait(0.2)
        return False

    def _say_interrupted(self, signum: int) -> None:
        """What a Ctrl-C or SIGTERM during start-up leaves: which modules had started, which was starting."""
        started = [r.entry.name for r in (*self.programs, *self.modules) if r.state == "running"]
        starting = [r.entry.name for r in (*self.programs, *self.modules) if r.state == "starting"]
        total = len(self.programs) + len(self.modules)
        done = f"{len(started)} of {total} started" + (f" ({', '.join(started)})" if started else "")
        doing = f", {starting[0]} starting" if starting else ""
        self._say(f"start-up interrupted by {signal.Signals(signum).name}: {done}{doing}; stopping them")

    def _say_groups(self) -> None:
        for process, members in self.groups.items():
            if len(members) > 1:
                self._say(f"process {process}: {', '.join(m.entry.name for m in members)}")
        if not self.grouping and any(m.entry.process for m in self.modules):
            how = "lockstep over Zenoh" if not self.shm_run else f"host {self.host} in the lockstep over Zenoh"
            shared = "modules share one in real time, or in the lockstep's shared memory"
            self._say(f"{how}: each module in its own process ({shared})")
        if self.bridged:
            self._say(f"over Zenoh in the shared-memory lockstep: {', '.join(self.bridged)}")

    def _say_links(self) -> None:
        """The links modules gave the user (Module.show_link), last, where they are seen: even with --quiet."""
        for m in self.modules:
            link = self.run_dir / f"{m.entry.name}{LINK_SUFFIX}"
            if link.is_file():
                self._say(f"{m.entry.name} {link.read_text().strip()}  <- open it in a browser")

    def state_record(self) -> dict[str, object]:
        return {
            **run_state.process_identity(),
            "kind": self.options.kind,
            "vehicle": self.vehicle,
            "profile": str(self.profile.path),
            "endpoint": self.endpoint,
            "host": self.host,
            "bus": json.loads(self.module_bus.to_json()),
            "run_dir": str(self.run_dir),
            "lockstep": self.profile.lockstep,
            "lockstep_transport": self.profile.lockstep_transport if self.profile.lockstep else None,
            "started": time.time(),
        }

    def _on_signal(self, signum: int, frame: object) -> None:
        # No printing or lock here: the handler may interrupt this thread inside _say, which holds the print lock.
        if not self._stop.is_set():
            self._signal = signum
        self._stop.set()

    # -- starting ----------------------------------------------------------------------------------

    def _start_all(self) -> bool:
        for p in self.programs:
            if self._stop.is_set():
                return False
            self._spawn_program(p)
            if not self._wait_program_ready(p):
                return False
        for i, m in enumerate(self.modules):
            if self._stop.is_set():
                return False
            for ahead in self.modules[i : i + 1 + PRESTART_AHEAD]:
                if ahead.proc is None:
                    self._spawn(ahead, go=False)
            self._go(m)
            if not self._wait_ready(m):
                return False
        return True

    def _module_bus(self, name: str, restarted: bool) -> BusConfig:
        """Each module listens on its own endpoint and connects to the router and the modules before it; a
        restarted one connects to all the others, so its messages go straight to every subscriber from its
        first lockstep step rather than by whatever route exists until the later modules reconnect to it."""
        if not self.module_endpoints:
            return self.module_bus
        names = [m.entry.name for m in self.modules]
        peers = [n for n in names if n != name] if restarted else names[: names.index(name)]
        own = self.module_endpoints[name]
        connect = dict.fromkeys(self.module_endpoints[n] for n in peers if self.module_endpoints[n] != own)
        bus = self.module_bus
        return BusConfig(
            mode=bus.mode,
            connect=(*bus.connect, *connect),
            listen=(own,),
            low_latency=bus.low_latency,
            lease_ms=bus.lease_ms,
            mesh=tuple(dict.fromkeys(self.module_endpoints.values())),
        )

    def _spec(self, m: ModuleProcess) -> ModuleSpec:
        e = m.entry
        bridged = e.name in self.bridged
        args = {**e.args, **self.options.extra_args.get(e.name, {})}
        args = {k: expand_placeholders(v, self.placeholders) if isinstance(v, str) else v for k, v in args.items()}
        return ModuleSpec(
            name=e.name,
            module=e.module,
            vehicle=self.vehicle,
            bus=self._module_bus(e.name, restarted=m.restarts > 0),
            params=e.params,
            args=args,
            lockstep=self.profile.lockstep,
            speed=self.options.speed,
            seed=self.profile.seed,
            log_level=self.options.log_level,
            supervisor_pid=os.getpid(),
            stall_timeout_s=self.profile.stall_timeout_s,
            run_dir=str(self.run_dir),
            late_join=m.restarts > 0,
            run_id=self.run_id,
            fastpath_fd=self.fast.region.fd if self.fast is not None and not bridged else -1,
            peers=self.vehicle_modules,
            hosts=self.profile.hosts_with_modules(),
            shm_run=self.shm_run,
            outside=[e.name for e in self.profile.modules if e.cls.OUTSIDE_LOCKSTEP or e.cls.PASSIVE],
            host=self.host,
            placement=self.profile.placement(),
            host_lease_ms=self.profile.host_lease_ms,
            open_topics=list(self.profile.open_topics),
            bridged=self.bridged if e.name == self.coordinator else [],
            world=self.options.world if e.cls.LOCKSTEP_COORDINATOR and self.profile.lockstep else "",
            world_slot=self.options.world_slot,
            world_vehicles=list(self.options.world_vehicles),
            sync_with=[*self.bridged, self.coordinator] if bridged and self.coordinator else None,
        )

    def _environment(self) -> dict[str, str]:
        """A child's environment: the profile placeholders as STACK_RUN_DIR, STACK_UDP_PORT..."""
        return {
            **os.environ,
            "PYTHONUNBUFFERED": "1",
            **{f"STACK_{k.upper()}": v for k, v in self.placeholders.items()},
            **({OFFSET_FILE_ENV: str(self.clock.path)} if self._offset_at is not None and self.clock else {}),
        }

    def _spawn(self, m: ModuleProcess, go: bool = True) -> None:
        """Start the process of the module (and of the modules sharing it); it loads their code, then waits for
        ``_go`` (given now unless ``go`` is False)."""
        members = self.groups[m.process]
        for each in members:
            each.spec_path.write_text(self._spec(each).to_json())
        env = self._environment()
        # fork+exec via posix_spawn/vfork (no Python code runs in the child before exec); own process
        # group so a terminal Ctrl-C reaches the supervisor only and it can stop modules in order.
        proc = subprocess.Popen(
            [sys.executable, "-m", "stack.runtime.main", *(str(each.spec_path) for each in members)],
            stdin=subprocess.PIPE,
            stdout=subprocess.PIPE,
            stderr=subprocess.STDOUT,
            env=env,
            process_group=0,
            pass_fds=self.fast.pass_fds() if self.fast is not None and m.entry.name not in self.bridged else (),
        )
        log_file = m.log_path.open("a")
        reader = threading.Thread(target=self._pump, args=(m.process, proc.stdout, log_file), daemon=True)
        for each in members:
            each.proc, each.reader = proc, reader
            each.exit_code = None
            each.restart_at = None
        reader.start()
        if go:
            self._go(m)

    def _go(self, m: ModuleProcess) -> None:
        """Let the module's process open its session and start (if it already died, _wait_ready says so)."""
        assert m.proc is not None and m.proc.stdin is not None
        m.state = "starting"
        held = self._port_holds.pop(m.process, None)
        if held is not None:
            held.close()
        self._say(f"starting {m.entry.name} (pid {m.proc.pid})")
        if m.proc.stdin.closed:
            return  # a process shared with a module started before
        try:
            m.proc.stdin.write(b"go\n")
            m.proc.stdin.close()
        except OSError:
            pass

    def _spawn_program(self, p: ProgramProcess) -> None:
        command = [expand_placeholders(part, self.placeholders) for part in p.entry.command]
        env = self._environment()
        p.proc = subprocess.Popen(
            [sys.executable, "-m", "stack.supervisor.child", str(os.getpid()), *command],
            stdin=subprocess.DEVNULL,
            stdout=subprocess.PIPE,
            stderr=subprocess.STDOUT,
            env=env,
            process_group=0,
        )
        p.state = "starting"
        p.exit_code = None
        p.restart_at = None
        self._say(f"starting process {p.entry.name} (pid {p.proc.pid}): {' '.join(command)}")
        log_file = p.log_path.open("a")
        p.reader = threading.Thread(target=self._pump, args=(p.entry.name, p.proc.stdout, log_file), daemon=True)
        p.reader.start()

    def _wait_program_ready(self, p: ProgramProcess) -> bool:
        """Ready once it has run ``ready_after_s`` without exiting (it has no bus to say so)."""
        assert p.proc is not None
        try:
            p.proc.wait(timeout=p.entry.ready_after_s)
        except subprocess.TimeoutExpired:
            p.state = "running"
            self._say(f"process {p.entry.name} running")
            return True
        p.exit_code = p.proc.returncode
        p.state = "failed"
        p.failures += 1
        self._say(f"process {p.entry.name} exited with code {p.exit_code} while starting (see {p.log_path})")
        return False

    def _watch_programs(self, now: float) -> None:
        for p in self.programs:
            if p.state == "running" and p.proc is not None and p.proc.poll() is not None:
                p.exit_code = p.proc.returncode
                failed = p.exit_code != 0
                p.failures += failed
                self._say(
                    f"process {p.entry.name} {'failed with exit code ' + str(p.exit_code) if failed else 'exited'}"
                )
                policy = p.entry.restart
                if (policy == "always" or (policy == "on-failure" and failed)) and p.restarts < p.entry.max_restarts:
                    p.state = "restarting"
                    p.restart_at = now + min(0.5 * 2**p.restarts, BACKOFF_MAX_S)
                else:
                    p.state = "failed" if failed else "exited"
            elif p.state == "restarting" and p.restart_at is not None and now >= p.restart_at:
                p.restarts += 1
                self._spawn_program(p)
                p.state = "running"

    def _wait_ready(self, m: ModuleProcess) -> bool:
        deadline = time.monotonic() + START_TIMEOUT_S
        with self._alive_changed:
            while self._alive.get(m.entry.name) != m.pid:
                if m.proc is not None and m.proc.poll() is not None:
                    m.exit_code = m.proc.returncode
                    m.state = "failed"
                    m.failures += 1
                    self._say(f"{m.entry.name} exited with code {m.exit_code} while starting (see {m.log_path})")
                    return False
                if time.monotonic() > deadline:
                    m.state = "failed"
                    m.failures += 1
                    self._say(f"{m.entry.name} did not report ready within {START_TIMEOUT_S:.0f} s")
                    return False
                if self._stop.is_set():
                    return False
                self._alive_changed.wait(0.05)
        m.state = "running"
        self._say(f"{m.entry.name} ready")
        return True

    def _on_alive(self, sample: zenoh.Sample) -> None:
        parsed = self._alive_tokens.parse(str(sample.key_expr))
        if parsed is None:
            return
        name, pid = parsed
        with self._alive_changed:
            if sample.kind == zenoh.SampleKind.PUT:
                self._alive[name] = pid
            elif self._alive.get(name) == pid:
                del self._alive[name]
            self._alive_changed.notify_all()

    def _on_clock_query(self, query: zenoh.Query) -> None:
        answer(query, self._key("clock"), str(time.clock_gettime_ns(time.CLOCK_MONOTONIC) // 1000))

    def _measure_offset(self, session: zenoh.Session) -> OffsetEstimate | None:
        """The leading host's clock minus this one's (stack.bus.timebase), None when it does not answer."""
        samples = []
        key = keys.supervisor_key(self.vehicle, self.leader, "clock")
        for _ in range(SYNC_SAMPLES):
            sent = time.clock_gettime_ns(time.CLOCK_MONOTONIC) // 1000
            for reply in session.get(key, timeout=1.0):
                if reply.ok is not None:
                    received = time.clock_gettime_ns(time.CLOCK_MONOTONIC) // 1000
                    with contextlib.suppress(ValueError):
                        samples.append(ClockSample(sent, int(reply.ok.payload.to_string()), received))
        return estimate_offset(samples)

    def _sync_clock(self, session: zenoh.Session) -> bool:
        """Before this host's modules start, in real time: put them on the leading host's clock (and keep them there,
        :meth:`_keep_clock`). False if stopped meanwhile."""
        if self.clock is None or self.profile.lockstep or self.leader == self.host:
            return True
        said = False
        while not self._stop.is_set():
            estimate = self._measure_offset(session)
            if estimate is not None:
                self.clock.write(estimate.offset_us)
                self._offset_at = (estimate.offset_us, time.monotonic())
                self._say(
                    f"clock: on host {self.leader}'s, {estimate.offset_us / 1e6:+.6f} s from this host's"
                    f" (round trip {estimate.round_trip_us / 1000:.1f} ms)"
                )
                threading.Thread(target=self._keep_clock, args=(session,), name="clock", daemon=True).start()
                return True
            if not said:
                self._say(f"waiting for host {self.leader}'s clock")
                said = True
            self._stop.wait(0.2)
        return False

    def _keep_clock(self, session: zenoh.Session) -> None:
        """Measure again every RESYNC_PERIOD_S and slew towards it; a large error is said (a clock stepped, or
        drifting fast)."""
        assert self.clock is not None and self._offset_at is not None
        while not self._stop.wait(RESYNC_PERIOD_S):
            estimate = self._measure_offset(session)
            if estimate is None:
                continue
            offset, since = self._offset_at
            now = time.monotonic()
            error = estimate.offset_us - offset
            if abs(error) > SKEW_WARN_US:
                self._say(f"clock: {error / 1000:+.1f} ms off host {self.leader}'s; slewing to it")
            offset = slew(offset, estimate.offset_us, round((now - since) * 1e6))
            self.clock.write(offset)
            self._offset_at = (offset, now)

    def _beat(self, session: zenoh.Session) -> None:
        """This host's beat, every BEAT_PERIOD_S until the supervisor stops."""
        # Ahead of the vehicle's messages in Zenoh's queues: behind a link full of telemetry a beat still gets through.
        publisher = session.declare_publisher(beat_key(self.vehicle, self.host), priority=zenoh.Priority.REAL_TIME)
        try:
            while not self._stop.wait(BEAT_PERIOD_S):
                publisher.put(b"")
            publisher.put(STOPPING)
        finally:
            publisher.undeclare()

    def _on_beat(self, sample: zenoh.Sample) -> None:
        host = beat_host(str(sample.key_expr), self.vehicle)
        if host is not None and self.hosts is not None:
            self.hosts.beat(host, time.monotonic_ns() // 1000, sample.payload.to_bytes())

    def _on_heartbeat(self, sample: zenoh.Sample) -> None:
        try:
            hb = self._hb_decoder.decode(sample.payload.to_bytes())
        except msgspec.DecodeError:
            return
        self._heartbeats[hb.module] = hb

    # -- watching ----------------------------------------------------------------------------------

    def _monitor(self) -> None:
        deadline = None if self.options.duration is None else time.monotonic() + self.options.duration
        while not self._stop.wait(MONITOR_PERIOD_S):
            now = time.monotonic()
            if self.fast is not None:
                self.fast.update_outside()
            if deadline is not None and now >= deadline:
                self._say(f"duration of {self.options.duration:g} s reached")
                return
            if self.hosts is not None:
                for change in self.hosts.update(time.monotonic_ns() // 1000):
                    self._say(change.describe())
                    if self.fast is not None:
                        self.fast.host_away(change.modules, change.lost)
            for members in self.groups.values():
                proc = members[0].proc
                if proc is not None and proc.poll() is not None and any(m.state == "running" for m in members):
                    self._on_exit(members)
                elif all(m.state == "restarting" for m in members):
                    restart_at = members[0].restart_at
                    if restart_at is not None and now >= restart_at:
                        self._restart(members)
            self._watch_programs(now)
            for m in self.modules:
                if m.entry.critical and m.state == "exited":
                    self._say(f"{m.entry.name} has finished: stopping the stack")
                    return
                if m.entry.critical and m.state == "failed":
                    self._say(f"critical module {m.entry.name} failed: stopping the stack")
                    return
            for p in self.programs:
                if p.entry.critical and p.state in ("failed", "exited"):
                    self._say(f"critical process {p.entry.name} {p.state}: stopping the stack")
                    return
            if self.modules and all(m.state in ("exited", "failed") for m in self.modules):
                self._say("all modules have exited")
                return

    @staticmethod
    def _label(members: list[ModuleProcess]) -> str:
        """How the supervisor names a process: its module, or the group and the modules in it."""
        if len(members) == 1:
            return members[0].entry.name
        return f"process {members[0].process} ({', '.join(m.entry.name for m in members)})"

    def _on_exit(self, members: list[ModuleProcess]) -> None:
        """The process of ``members`` exited: restart it if every one of their policies asks (a module that may not
        restart, such as the simulator, keeps its process down), else they are over."""
        proc = members[0].proc
        assert proc is not None
        code = proc.returncode
        for m in members:
            m.exit_code = code
            m.failures += code != 0
        label = self._label(members)
        if code == 0:
            self._say(f"{label} exited")
        else:
            self._say(f"{label} failed with exit code {code} (see {members[0].log_path})")
        if all(m.entry.restart == "always" or (m.entry.restart == "on-failure" and code != 0) for m in members):
            self._plan_restart_or_give_up(members)
        else:
            for m in members:
                m.state = "exited" if code == 0 else "failed"
        if self.fast is not None:
            for m in members:
                if self._on_fast_path(m):
                    self.fast.exit_handled(m.entry.name, m.state == "restarting")

    def _restart(self, members: list[ModuleProcess]) -> None:
        for m in members:
            m.restarts += 1
        self._say(f"restarting {self._label(members)} (restart {members[0].restarts})")
        self._spawn(members[0])
        for m in members[1:]:
            self._go(m)
        if all(self._wait_ready(m) for m in members):
            if self.fast is not None:
                for m in members:
                    if self._on_fast_path(m):
                        self.fast.restart_over(m.entry.name)
            return
        proc = members[0].proc
        if proc is not None and proc.poll() is None:
            proc.kill()  # a module of it never came up: the next attempt starts the process anew
            proc.wait()
        self._plan_restart_or_give_up(members)

    def _plan_restart_or_give_up(self, members: list[ModuleProcess]) -> None:
        label = self._label(members)
        restarts = members[0].restarts
        if restarts >= max(m.entry.max_restarts for m in members):
            self._say(f"{label}: giving up after {restarts} restarts")
            for m in members:
                m.state = "failed"
                if self.fast is not None and self._on_fast_path(m):
                    self.fast.restart_over(m.entry.name)
            return
        delay = min(0.5 * 2**restarts, BACKOFF_MAX_S)
        restart_at = time.monotonic() + delay
        process = members[0].process
        if process in self._process_ports and process not in self._port_holds:
            held = hold_again(self._process_ports[process])
            if held is not None:
                self._port_holds[process] = held
        for m in members:
            m.state = "restarting"
            m.restart_at = restart_at
        self._say(f"{label}: restart in {delay:.1f} s")

    # -- stopping ----------------------------------------------------------------------------------

    def _stop_all(self) -> None:
        for m in self._stop_order():
            proc = m.proc
            if proc is None:
                continue
            if proc.poll() is not None:
                if m.state in ("starting", "running", "stopping"):
                    m.exit_code, m.state = proc.returncode, "exited"  # its process was stopped with another module
                continue
            m.state = "stopping"
            try:
                proc.send_signal(signal.SIGTERM)
                proc.wait(timeout=STOP_GRACE_S)
            except subprocess.TimeoutExpired:
                self._say(f"{m.entry.name} did not stop within {STOP_GRACE_S:.0f} s: killing it")
                proc.kill()
                proc.wait()
            m.exit_code = proc.returncode
            if m.exit_code not in (0, -signal.SIGTERM, -signal.SIGKILL):
                m.failures += 1
                self._say(f"{m.entry.name} stopped with exit code {m.exit_code}")
            m.state = "exited"
        for p in reversed(self.programs):
            self._stop_program(p)
        for reader in {r.reader for r in (*self.modules, *self.programs) if r.reader is not None}:
            reader.join(timeout=2.0)

    def _stop_program(self, p: ProgramProcess) -> None:
        proc = p.proc
        if proc is None or proc.poll() is not None:
            return
        p.state = "stopping"
        try:
            proc.send_signal(signal.SIGTERM)
            proc.wait(timeout=STOP_GRACE_S)
        except subprocess.TimeoutExpired:
            self._say(f"process {p.entry.name} did not stop within {STOP_GRACE_S:.0f} s: killing it")
            proc.kill()
            proc.wait()
        p.exit_code = proc.returncode
        if p.exit_code not in (0, -signal.SIGTERM, -signal.SIGKILL):
            p.failures += 1
            self._say(f"process {p.entry.name} stopped with exit code {p.exit_code}")
        p.state = "exited"

    def _stop_order(self) -> list[ModuleProcess]:
        """Reverse start order; in lockstep the clock's driver goes first, so simulated time stops at once
        and no module sees the world go on without the ones already stopped (a vehicle falling)."""
        order = list(reversed(self.modules))
        if self.profile.lockstep:
            order.sort(key=lambda m: not m.entry.cls.LOCKSTEP_COORDINATOR)
        return order

    # -- services ----------------------------------------------------------------------------------

    def _on_roster_query(self, query: zenoh.Query) -> None:
        modules = {m.entry.name: m.pid for m in self.modules if m.state == "running"}
        reply = {
            "host": self.host,
            "leads": self.leads,
            "run_id": self.run_id,
            "seed": self.profile.seed,
            "params": {e.name: e.params for e in self.profile.modules},  # every module of the vehicle it knows
            "publishes": self.profile.publishers(),
            "complete": self.roster_complete,
            "modules": modules,
        }
        answer(query, self._key("roster"), json.dumps(reply))

    def _on_outside_query(self, query: zenoh.Query) -> None:
        """Which topics the stack puts on Zenoh for subscribers outside it: a tool that has just subscribed
        waits until its topics are among them (with no fast path, every topic always is)."""
        reply = {"fast_path": self.fast is not None, "topics": self.fast.outside_topics() if self.fast else []}
        answer(query, self._key("outside"), json.dumps(reply))

    def _on_stop_query(self, query: zenoh.Query) -> None:
        """``stack down`` from another host of the vehicle: stop as on SIGTERM."""
        answer(query, self._key("stop"), json.dumps({"host": self.host, "pid": os.getpid()}))
        if not self._stop.is_set():
            self._signal = signal.SIGTERM
        self._stop.set()

    def _on_denial(self, denial: Denial) -> None:
        with self._print_lock:
            first = self.denied.add(denial, time.time())
        if first:
            self._say(f"router of host {self.host}: {denial.describe()} (counted in `stack status`)")

    def _on_status_query(self, query: zenoh.Query) -> None:
        answer(query, self._key("status"), json.dumps(self.status()))

    def status(self) -> dict[str, object]:
        rows = []
        for m in self.modules:
            hb = self._heartbeats.get(m.entry.name)
            row: dict[str, object] = {
                "module": m.entry.name,
                "host": self.host,
                "type": m.entry.module,
                "process": m.process,
                "state": m.state,
                "pid": m.pid,
                "restarts": m.restarts,
                "exit_code": m.exit_code,
            }
            if hb is not None:
                row.update(msgspec.structs.asdict(hb))
                row["module"], row["host"], row["hostname"] = m.entry.name, self.host, hb.host
                row["state"] = m.state if m.state != "running" else hb.state
            rows.append(row)
        for p in self.programs:
            rows.append(
                {
                    "module": p.entry.name,
                    "host": self.host,
                    "type": "process",
                    "state": p.state,
                    "pid": p.pid,
                    "restarts": p.restarts,
                    "exit_code": p.exit_code,
                }
            )
        return {
            "vehicle": self.vehicle,
            "host": self.host,
            "host_order": list(self.profile.hosts).index(self.host) if self.profile.hosts else 0,
            "placement": self.profile.placement(),
            "lost_hosts": self.hosts.lost if self.hosts is not None else [],
            "profile": self.profile.name,
            "lockstep": self.profile.lockstep,
            "speed": self.options.speed,
            "open_topics": list(self.profile.open_topics),
            "denied": self.denied.rows(),
            "modules": rows,
        }

    # -- output ------------------------------------------------------------------------------------

    def _pump(self, name: str, stream: IO[bytes], log_file: IO[str]) -> None:
        prefix = f"[{name}] "
        with log_file:
            for raw in iter(stream.readline, b""):
                line = raw.decode(errors="replace").rstrip()
                log_file.write(f"{time.strftime('%H:%M:%S')} {line}\n")
                log_file.flush()
                echo = self.options.echo_logs or name in self.options.echo_only
                if echo:
                    with self._print_lock:
                        print(prefix + line, flush=True)

    def _say(self, text: str) -> None:
        with self._print_lock:
            print(f"[stack] {text}", flush=True)
        with (self.run_dir / "supervisor.log").open("a") as f:
            f.write(f"{time.strftime('%H:%M:%S')} {text}\n")


def _is_member(entry: ModuleEntry) -> bool:
    """Whether the module is a lockstep member: neither the coordinator nor outside the lockstep nor a passive
    observer."""
    cls = entry.cls
    return not (cls.LOCKSTEP_COORDINATOR or cls.OUTSIDE_LOCKSTEP or cls.PASSIVE)
