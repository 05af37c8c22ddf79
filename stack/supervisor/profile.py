"""Launch profiles: TOML files that read like PX4's ``rc.mc_apps``.

A profile lists the modules in start order, each with its parameters, arguments, start condition
and restart policy, plus the vehicle namespace and bus settings. Everything is checked before any
process starts; a problem is reported in one line naming the file, the key and what is wrong::

    launch/sitl_quad.toml: module[3].params.MC_ROLLRATE_P: 0.9 is above the maximum 0.5 (range 0.01 to 0.5)

A profile may start from another (``extends = "sitl_quad"``, looked up beside it, then by name) and
give only what differs: its tables are merged into the base's key by key, and each ``[[module]]`` it
lists changes the base's module of the same name (its ``params`` and ``args`` merged likewise) or, if
the base has none, is started after the base's modules.

Modules given the same ``process = "NAME"`` share one OS process (as ROS 2 component containers do; PX4 runs
all its modules in one): each stays a module with its topics, parameters, heartbeat and status row, and a
crash restarts the process if every one of its modules' policies asks (a module that may not restart, such as
the simulator, keeps the process down: a crash of any module of it is then that module's crash). Only
lockstep modules can share a process: in real time (``--realtime``) each in a thread of its own
(:mod:`stack.runtime.realtime_group`), and in a shared-memory lockstep run on the shared memory; a lockstep
over Zenoh runs each module in its own process, as a host without the lockstep's shared memory does. Over
``[hosts]``, the modules of a process are on one host.

A lockstep member given ``transport = "zenoh"`` takes part in a shared-memory lockstep run over Zenoh, as a
module on another host must: it keeps its place in the run, which the simulator's process serves for it
(:mod:`stack.fastpath.bridge`), and the flight is the same, message for message.

A ``[[process]]`` is a supervised program that is not a module (no bus, no heartbeat), such as the
simulated Pixhawk ``stack pixhawk-sim``: the processes start first, in order, each ready once it has run
``ready_after_s`` without exiting; they stop last; their death is noticed and handled as a module's
(``restart``, ``critical``). In a process's ``command`` and in a module's string arguments these
placeholders are replaced when the stack starts, so both ends of a link can name it: ``{python}`` (this
Python), ``{run_dir}`` (the run directory), ``{seed}`` (the run's seed), ``{udp_port}`` and
``{control_port}`` (two free 127.0.0.1 UDP ports, chosen per run). Every module and process also finds
them in its environment as ``STACK_<NAME>`` (``STACK_CONTROL_PORT``...).

One vehicle may be spread over several machines: ``[hosts.NAME] endpoint = "tcp/ADDR:PORT"`` declares a host
and where its Zenoh router listens (the other hosts' routers connect there), and every ``[[module]]`` and
``[[process]]`` then names the host that runs it (``host = "NAME"``). ``stack up PROFILE --host NAME`` on each
machine starts that host's share; a host may run no module at all (a ground laptop: its router and the tools).
The ``[params]`` are the vehicle's, wherever its modules run. A profile without ``[hosts]`` is one machine's.
"""

from __future__ import annotations

import ast
import dataclasses
import math
import re
import string
import tomllib
from dataclasses import dataclass, field
from pathlib import Path

from stack.bus import keys
from stack.bus.config import ROUTER_LEASE_BETWEEN_HOSTS_MS, BusConfig, between_hosts
from stack.bus.host_beats import BEAT_PERIOD_S, DEFAULT_LEASE_MS, MIN_LEASE_MS
from stack.bus.supervisors import SINGLE_HOST
from stack.launch_files import find_mission, launch_dirs
from stack.msg.registry import TOPICS
from stack.names import suggestion
from stack.params.param import ParamError, ParamValue
from stack.runtime.module import Module
from stack.runtime.spec import load_module_class, resolve_args

DEFAULT_PROFILE = "sitl_quad"


RESTART_POLICIES = ("no", "on-failure", "always")
# How lockstep messages travel: shared memory between the processes of one supervisor (stack.fastpath),
# or Zenoh, for a lockstep run whose modules are not all started by this supervisor on this host.
LOCKSTEP_TRANSPORTS = ("shm", "zenoh")
DEFAULT_SWARM_SPACING_M = 5.0
FLAGS = ("lockstep", "realtime", "plot", "record")
PLACEHOLDERS = ("python", "run_dir", "seed", "udp_port", "control_port")
"""What ``{name}`` in a process command or a module's string argument stands for (see the module docstring)."""
MAX_DEPTH = 32
"""Tables and arrays nested deeper are refused: a profile needs a few levels (the launch profiles 3), and every
walk of a document (merging an extended profile, checking a module's arguments) recurses once per level."""


class ProfileError(ValueError):
    """A launch profile was refused; the message names the file, the key and the problem."""


@dataclass
class ModuleEntry:
    name: str
    module: str
    cls: type[Module]
    params: dict[str, ParamValue]
    args: dict[str, ParamValue]
    condition: str
    restart: str
    max_restarts: int
    critical: bool
    process: str = ""
    """The process it shares with the other modules of the same ``process`` name; empty: a process of its own."""
    transport: str = "shm"
    """How it takes part in a shared-memory lockstep run: through the shared memory, or over Zenoh."""
    host: str = ""
    """The machine that runs it (``[hosts.NAME]``); empty in a profile of one machine."""


@dataclass
class ProcessEntry:
    """A supervised program that is not a module (``[[process]]``)."""

    name: str
    command: list[str]
    condition: str
    restart: str
    max_restarts: int
    critical: bool
    ready_after_s: float
    host: str = ""


@dataclass(frozen=True)
class HostEntry:
    """A machine the vehicle is spread over (``[hosts.NAME]``): its router listens on ``endpoint``, where the other
    hosts' routers connect."""

    name: str
    endpoint: str


_ENDPOINT = re.compile(r"^(tcp|tls|quic)/(\[[0-9A-Fa-f:.]+\]|[A-Za-z0-9.\-]+):(\d{1,5})$")


def endpoint_problem(endpoint: str) -> str:
    """Why ``endpoint`` cannot be where a host's router listens for the others, or '' if it can."""
    m = _ENDPOINT.match(endpoint)
    if m is None:
        return f"{endpoint!r} is not a Zenoh endpoint like tcp/10.0.0.2:7447"
    if not 0 < int(m[3]) <= 65535:
        return f"{endpoint}: the port must be between 1 and 65535 (the other hosts connect to it)"
    return ""


def expand_placeholders(text: str, values: dict[str, str]) -> str:
    """``text`` with each ``{name}`` of PLACEHOLDERS replaced (other braces, e.g. JSON, left alone)."""
    for name, value in values.items():
        text = text.replace("{" + name + "}", value)
    return text


@dataclass
class Profile:
    path: Path
    vehicle: str
    description: str
    lockstep: bool
    seed: int
    airframe: str
    bus: BusConfig
    port: int
    stall_timeout_s: float = 10.0
    lockstep_transport: str = "shm"
    open_topics: tuple[str, ...] = ()
    """Topics any program on the bus may publish, beyond those open to tools (stack.bus.access)."""
    modules: list[ModuleEntry] = field(default_factory=list)
    processes: list[ProcessEntry] = field(default_factory=list)
    scenario_limits: dict[str, dict[str, float | bool]] = field(default_factory=dict)
    scenario_options: dict[str, dict[str, str]] = field(default_factory=dict)
    hosts: dict[str, HostEntry] = field(default_factory=dict)
    host_lease_ms: int = DEFAULT_LEASE_MS
    """How long a host of the vehicle may go without a beat before the others count it lost (stack.bus.host_beats)."""
    swarm_names: tuple[str, ...] = ()
    """The vehicles of a swarm of this profile (``[swarm] names``); empty: v1, v2... (stack.supervisor.swarm)."""
    swarm_spacing_m: float = DEFAULT_SWARM_SPACING_M
    """How far east of the one before it each vehicle of a swarm has its home (``[swarm] spacing_m``)."""
    keystore: Path | None = None
    """``[security] keystore``: the links between hosts on mutual TLS, each host presenting its identity there
    (stack.security.tls); None: plain TCP."""
    count_denials: bool = True
    """``[security] count_denials``: each host's router counts what its access rules drop (stack.security.denials),
    at a cost per message it passes; false: dropped uncounted."""

    @property
    def name(self) -> str:
        return self.path.stem

    def hosts_with_modules(self) -> list[str]:
        """The hosts whose supervisors start modules (their rosters make the vehicle's), in profile order."""
        if not self.hosts:
            return [SINGLE_HOST]
        return [h for h in self.hosts if any(m.host == h for m in self.modules)]

    def publishers(self) -> dict[str, list[str]]:
        """Each module by name, with the topics it publishes (its class's declaration, for its arguments)."""
        return {e.name: sorted(e.cls.publishes(e.args)) for e in self.modules}

    def placement(self) -> dict[str, list[str]]:
        """Host → the names of its modules, for every host of the profile (empty without hosts)."""
        return {h: [e.name for e in self.modules if e.host == h] for h in self.hosts}

    def router_links(self, host: str) -> tuple[tuple[str, ...], tuple[str, ...]]:
        """Where ``host``'s router listens for the other hosts, and what it connects to: ``bus.connect`` and the hosts
        listed before it, each with the socket buffers of a link between hosts. One TCP link joins two hosts, the
        later one connecting: when both connected at once, Zenoh put both links in one transport, and after a link
        cut the two routers could disagree on it for good, one dropping the other's messages as unknown."""
        names = list(self.hosts)
        earlier = (between_hosts(self.host_endpoint(h)) for h in names[: names.index(host)])
        return (between_hosts(self.host_endpoint(host)),), (*self.bus.connect, *earlier)

    def listen_endpoints(self, host: str | None) -> tuple[str, ...]:
        """Where the stack of ``host`` (None: of a profile of one machine) listens beyond its modules' own router."""
        beyond = self.router_links(host)[0] if host is not None and self.hosts else ()
        return (*beyond, *self.bus.listen)

    def host_endpoint(self, host: str) -> str:
        """Where ``host``'s router listens for the other hosts: over TLS with a keystore."""
        endpoint = self.hosts[host].endpoint
        if self.keystore is None:
            return endpoint
        from stack.security.tls import tls_endpoint  # cryptography, only for a profile with a keystore

        return tls_endpoint(endpoint)

    def host_access(self) -> dict[str, object]:
        """The access rules of a host's router, from the keystore's identities and what each host's modules publish
        (stack.security.acl); empty without a keystore."""
        if self.keystore is None or not self.hosts:
            return {}
        from stack.security.acl import access_rules

        publishers = self.publishers()
        publishes = {host: {t for m in names for t in publishers[m]} for host, names in self.placement().items()}
        return access_rules(self.keystore, publishes)

    def host_tls(self, host: str) -> dict[str, str]:
        """What ``host``'s router presents and trusts on the links between hosts (stack.bus.config.BusConfig.tls):
        empty without a keystore; a ProfileError naming the file when its identity is not in the keystore."""
        if self.keystore is None or not self.hosts:
            return {}
        from stack.security.keystore import KeystoreError
        from stack.security.tls import tls_files

        try:
            return tls_files(self.keystore, host, role="host")
        except KeystoreError as e:
            raise ProfileError(f"{self.path}: security.keystore: {e}") from None

    @property
    def router_lease_ms(self) -> int:
        """Zenoh's lease on a host's router: between hosts ROUTER_LEASE_BETWEEN_HOSTS_MS, else ``[bus] lease_ms``."""
        return ROUTER_LEASE_BETWEEN_HOSTS_MS if self.hosts else self.bus.lease_ms

    @property
    def router_link_count(self) -> int:
        """How many links a host's router may hold to other routers: one to each other host, one to each endpoint of
        ``bus.connect``."""
        return max(len(self.hosts) - 1, 0) + len(self.bus.connect)

    def check_host(self, host: str | None) -> None:
        """``--host``: required, and one of the profile's hosts, when the profile spreads the vehicle over hosts;
        refused when it does not. Raises ProfileError naming the file."""
        known = ", ".join(self.hosts)
        if host is None and self.hosts:
            raise ProfileError(f"{self.path}: hosts: the vehicle is spread over hosts {known}; give --host NAME")
        if host is not None and not self.hosts:
            raise ProfileError(f"{self.path}: --host {host}: this profile runs on one machine (it has no [hosts])")
        if host is not None and host not in self.hosts:
            hint = suggestion(host, self.hosts)
            raise ProfileError(f"{self.path}: --host {host}: no such host{hint}; hosts: {known}")
        if host is not None:
            self.host_tls(host)


def resolve_path(profile: str | Path) -> Path:
    """A profile by name (``sitl_quad`` → launch/sitl_quad.toml) or by path."""
    p = Path(profile)
    if p.suffix == ".toml" or p.exists():
        return p
    for d in launch_dirs():
        if (d / f"{profile}.toml").exists():
            return d / f"{profile}.toml"
    return Path("launch") / f"{profile}.toml"


def available_profiles() -> list[str]:
    return sorted({p.stem for d in launch_dirs() for p in d.glob("*.toml")})


def load_profile(profile: str | Path, *, flags: dict[str, bool] | None = None) -> Profile:
    """Read and check a profile. ``flags`` (realtime, plot, record) feed start conditions."""
    path = resolve_path(profile)
    return _Loader(path).load(flags or {})


def merge_documents(base: dict, child: dict) -> dict:
    """``child`` over ``base``: tables merged key by key, ``[[module]]`` entries matched by name."""
    merged = dict(base)
    for key, value in child.items():
        if key in ("module", "process") and isinstance(value, list) and isinstance(base.get(key), list):
            merged[key] = _merge_modules(base[key], value)
        elif isinstance(value, dict) and isinstance(base.get(key), dict):
            merged[key] = merge_documents(base[key], value)
        else:
            merged[key] = value
    return merged


def _merge_modules(base: list, child: list) -> list:
    merged = list(base)
    index = {_entry_name(e): i for i, e in enumerate(base)}
    for entry in child:
        i = index.get(_entry_name(entry))
        if i is None or not isinstance(entry, dict) or not isinstance(merged[i], dict):
            merged.append(entry)
        else:
            merged[i] = merge_documents(merged[i], entry)
    return merged


def _entry_name(entry: object) -> object:
    """The name a ``[[module]]`` entry will run under (its ``name``, else its module's NAME)."""
    if not isinstance(entry, dict):
        return None
    if "name" in entry:
        return entry["name"]
    ref = entry.get("module")
    if not isinstance(ref, str):
        return None
    try:
        return load_module_class(ref).NAME or ref
    except ValueError:
        return ref  # refused with its reason when the entry itself is checked


def _too_deep(doc: dict) -> str | None:
    """The key of a value of ``doc`` nested more than :data:`MAX_DEPTH` levels deep, or None (walked
    without recursion: the document may be nested deeper than Python's recursion limit)."""
    todo: list[tuple[object, str, int]] = [(doc, "", 0)]
    while todo:
        value, where, depth = todo.pop()
        if depth > MAX_DEPTH:
            return where
        if isinstance(value, dict):
            todo.extend((v, f"{where}.{k}" if where else str(k), depth + 1) for k, v in value.items())
        elif isinstance(value, list):
            todo.extend((v, f"{where}[{i}]", depth + 1) for i, v in enumerate(value))
    return None


class _Loader:
    def __init__(self, path: Path) -> None:
        self.path = path
        self.bases: list[Path] = []  # the profiles it extends, nearest first

    def fail(self, key: str, problem: str) -> ProfileError:
        source = f"{self.path} (extends {' < '.join(str(b) for b in self.bases)})" if self.bases else str(self.path)
        return ProfileError(f"{source}: {key}: {problem}" if key else f"{source}: {problem}")

    def _document(self, path: Path, extended_by: tuple[Path, ...]) -> dict:
        """The TOML document of ``path`` merged onto the profile it extends, recursively."""
        try:
            doc = tomllib.loads(path.read_text())
        except tomllib.TOMLDecodeError as e:
            raise ProfileError(f"{path}: TOML syntax error: {e}") from None
        except RecursionError:
            # tomllib reads nested arrays and inline tables by recursion, and gives up at Python's recursion limit.
            raise ProfileError(
                f"{path}: arrays or inline tables nested too deeply to read (more than {MAX_DEPTH} levels are refused)"
            ) from None
        deep = _too_deep(doc)
        if deep is not None:
            raise ProfileError(f"{path}: {deep}: nested more than {MAX_DEPTH} levels deep")
        base_name = doc.pop("extends", None)
        if base_name is None:
            return doc
        if not isinstance(base_name, str):
            raise ProfileError(f"{path}: extends: expected a profile name or path, got {base_name!r}")
        beside = path.parent / (base_name if base_name.endswith(".toml") else f"{base_name}.toml")
        base = beside if beside.exists() else resolve_path(base_name)
        if not base.exists():
            hint = suggestion(Path(base_name).stem, available_profiles())
            known = ", ".join(available_profiles())
            raise ProfileError(f"{path}: extends: no such profile '{base_name}'{hint} (available: {known})")
        chain = (*extended_by, path.resolve())
        if base.resolve() in chain:
            raise ProfileError(f"{path}: extends: '{base_name}' leads back to this profile")
        self.bases.append(base)
        return merge_documents(self._document(base, chain), doc)

    def load(self, flags: dict[str, bool]) -> Profile:
        if not self.path.exists():
            hint = suggestion(self.path.stem, available_profiles())
            known = ", ".join(available_profiles())
            raise ProfileError(f"{self.path}: no such profile{hint} (available: {known})")
        doc = self._document(self.path, ())
        self._only(doc, "", {"stack", "bus", "params", "module", "process", "scenario", "hosts", "swarm", "security"})
        stack = self._table(doc, "stack")
        self._only(
            stack,
            "stack",
            {
                "vehicle",
                "description",
                "lockstep",
                "lockstep_transport",
                "seed",
                "airframe",
                "stall_timeout_s",
                "open_topics",
            },
        )
        vehicle = self._get(stack, "stack", "vehicle", str, "v1")
        try:
            keys.check_name("vehicle", vehicle)
        except ValueError as e:
            raise self.fail("stack.vehicle", str(e)) from None
        lockstep = self._get(stack, "stack", "lockstep", bool, True) and not flags.get("realtime", False)
        airframe = self._get(stack, "stack", "airframe", str, "")
        transport = self._get(stack, "stack", "lockstep_transport", str, "shm")
        if transport not in LOCKSTEP_TRANSPORTS:
            raise self.fail("stack.lockstep_transport", f"'{transport}' is not one of {', '.join(LOCKSTEP_TRANSPORTS)}")
        bus_table = self._table(doc, "bus")
        bus, port = self._bus(bus_table)
        profile = Profile(
            path=self.path,
            vehicle=vehicle,
            description=self._get(stack, "stack", "description", str, ""),
            lockstep=lockstep,
            seed=self._get(stack, "stack", "seed", int, 1),
            airframe=airframe,
            bus=bus,
            port=port,
            stall_timeout_s=float(self._get(stack, "stack", "stall_timeout_s", float, 10.0)),
            lockstep_transport=transport,
            open_topics=self._open_topics(stack),
            hosts=self._hosts(self._table(doc, "hosts")),
            host_lease_ms=self._host_lease(bus_table),
        )
        shared = self._airframe_params(airframe)
        given_shared = self._table(doc, "params")
        shared.update(given_shared)
        entries = doc.get("module", [])
        if not isinstance(entries, list) or not entries:
            raise self.fail("module", "expected at least one [[module]] entry")
        variables: dict[str, object] = {**flags, "lockstep": lockstep, "realtime": not lockstep}
        names: set[str] = set()
        declared: set[str] = set()
        for i, entry in enumerate(entries):
            module = self._module(i, entry, shared, variables)
            declared.update(p.name for p in module.cls.PARAMS)
            if module.name in names:
                raise self.fail(f"module[{i}].name", f"'{module.name}' is used twice")
            names.add(module.name)
            if module.condition and not self._condition(f"module[{i}].condition", module.condition, variables, shared):
                continue
            profile.modules.append(module)
        for name in given_shared:
            if name not in declared:
                raise self.fail(f"params.{name}", "no module of this profile has this parameter")
        processes = doc.get("process", [])
        if not isinstance(processes, list):
            raise self.fail("process", "expected [[process]] entries")
        for i, entry in enumerate(processes):
            process = self._process(i, entry, shared, variables)
            if process.name in names:
                raise self.fail(f"process[{i}].name", f"'{process.name}' is used twice")
            names.add(process.name)
            if process.condition and not self._condition(
                f"process[{i}].condition", process.condition, variables, shared
            ):
                continue
            profile.processes.append(process)
        if profile.hosts and "low_latency" not in bus_table:
            # Zenoh's low-latency transport writes straight to the socket: behind a slow link between hosts a router
            # would wait for room, holding up everything else it forwards. With queues, a full one drops instead.
            profile.bus = dataclasses.replace(profile.bus, low_latency=False)
        self._check_placement(profile)
        self._check_process_groups(profile)
        for module in profile.modules:
            for aname, value in module.args.items():
                if isinstance(value, str):
                    self._check_placeholders(f"module ({module.name}).args.{aname}", value, allow_json=True)
        profile.scenario_limits, profile.scenario_options = self._scenario_settings(self._table(doc, "scenario"))
        profile.swarm_names, profile.swarm_spacing_m = self._swarm(self._table(doc, "swarm"))
        security = self._table(doc, "security")
        profile.keystore = self._keystore(security)
        profile.count_denials = bool(self._get(security, "security", "count_denials", bool, True))
        return profile

    def _keystore(self, table: dict) -> Path | None:
        self._only(table, "security", {"keystore", "count_denials"})
        given = self._get(table, "security", "keystore", str, "")
        if not given:
            return None
        path = Path(given).expanduser()
        path = path if path.is_absolute() else self.path.parent / path
        if not (path / "ca.pem").exists():
            raise self.fail("security.keystore", f"no keystore at {path} (make one with `stack keys init {path}`)")
        return path

    def _swarm(self, table: dict) -> tuple[tuple[str, ...], float]:
        self._only(table, "swarm", {"names", "spacing_m"})
        names = self._get(table, "swarm", "names", list, [])
        for i, name in enumerate(names):
            if not isinstance(name, str) or not keys.valid_name(name):
                raise self.fail(f"swarm.names[{i}]", f"{name!r} is not a vehicle name (letters, digits, '_' and '-')")
        if len(set(names)) != len(names):
            raise self.fail("swarm.names", "a vehicle is named twice")
        spacing = float(self._get(table, "swarm", "spacing_m", float, DEFAULT_SWARM_SPACING_M))
        if not (math.isfinite(spacing) and spacing > 0):
            raise self.fail("swarm.spacing_m", f"expected metres above 0, got {spacing:g}")
        return tuple(names), spacing

    def _hosts(self, table: dict) -> dict[str, HostEntry]:
        hosts = {}
        for name, entry in table.items():
            where = f"hosts.{name}"
            try:
                keys.check_name("host", name)
            except ValueError as e:
                raise self.fail(where, str(e)) from None
            if not isinstance(entry, dict):
                raise self.fail(where, 'expected a table with endpoint = "tcp/ADDR:PORT"')
            self._only(entry, where, {"endpoint"})
            endpoint = self._get(entry, where, "endpoint", str, None)
            if endpoint is None:
                raise self.fail(f"{where}.endpoint", 'missing (where its router listens: "tcp/ADDR:PORT")')
            problem = endpoint_problem(endpoint)
            if problem:
                raise self.fail(f"{where}.endpoint", problem)
            hosts[name] = HostEntry(name, endpoint)
        seen: dict[str, str] = {}
        for h in hosts.values():
            if h.endpoint in seen:
                raise self.fail(f"hosts.{h.name}.endpoint", f"{h.endpoint} is host {seen[h.endpoint]}'s endpoint too")
            seen[h.endpoint] = h.name
        return hosts

    def _check_placement(self, profile: Profile) -> None:
        """With ``[hosts]``, every module and process names one of them; without, none names a host."""
        for kind, entries in (("module", profile.modules), ("process", profile.processes)):
            for entry in entries:
                where = f"{kind} ({entry.name}).host"
                if not profile.hosts and entry.host:
                    raise self.fail(where, f"'{entry.host}': this profile declares no [hosts.{entry.host}]")
                if profile.hosts and not entry.host:
                    raise self.fail(where, f"missing: say which host runs it ({', '.join(profile.hosts)})")
                if profile.hosts and entry.host not in profile.hosts:
                    hint = suggestion(entry.host, profile.hosts)
                    raise self.fail(where, f"'{entry.host}' is not a host of this profile{hint}")

    def _check_process_groups(self, profile: Profile) -> None:
        """A process group's name is not another module's or a ``[[process]]``'s, and its modules are on one host."""
        first: dict[str, ModuleEntry] = {}
        for module in profile.modules:
            group = module.process
            if not group:
                continue
            where = f"module ({module.name}).process"
            clash = [m.name for m in profile.modules if m.name == group and m.process != group]
            clash += [p.name for p in profile.processes if p.name == group]
            if clash:
                raise self.fail(where, f"'{group}' is also the name of {clash[0]}")
            other = first.setdefault(group, module)
            if other.host != module.host:
                raise self.fail(
                    where, f"'{group}' also holds {other.name}, on host {other.host}; a process runs on one host"
                )

    def _scenario_settings(self, table: dict) -> tuple[dict[str, dict[str, float | bool]], dict[str, dict[str, str]]]:
        """Per-scenario check limits and options for this vehicle (``[scenario.attitude_step] yaw_rise_time_s =
        0.3``, ``[scenario.plane_mission] mission = "c172_rectangle"``)."""
        from stack.scenario.catalogue import scenarios, unknown_scenario

        known = scenarios()
        limits: dict[str, dict[str, float | bool]] = {}
        options: dict[str, dict[str, str]] = {}
        for name, overrides in table.items():
            if name not in known:
                raise self.fail(f"scenario.{name}", unknown_scenario(name))
            if not isinstance(overrides, dict):
                raise self.fail(f"scenario.{name}", "expected a table of check limits and options")
            checks = {c.metric: c for c in known[name].all_checks}
            choices = known[name].options
            for key, value in overrides.items():
                where = f"scenario.{name}.{key}"
                if key in choices:
                    if not isinstance(value, str):
                        raise self.fail(where, "expected a string")
                    if key == "mission":  # found now, not once the stack is up
                        try:
                            find_mission(value)
                        except FileNotFoundError as e:
                            raise self.fail(where, str(e)) from None
                    allowed = known[name].choices.get(key)
                    if allowed is not None and value not in allowed:
                        raise self.fail(where, f"{value!r} is not one of {', '.join(allowed)}")
                    options.setdefault(name, {})[key] = value
                    continue
                if key not in checks:
                    raise self.fail(where, f"not a check or option of {name} ({', '.join([*checks, *choices])})")
                if type(value) is not type(checks[key].limit) and not (
                    isinstance(value, int | float) and isinstance(checks[key].limit, float)
                ):
                    raise self.fail(where, f"expected {type(checks[key].limit).__name__}")
                limits.setdefault(name, {})[key] = value
        return limits, options

    def _bus(self, table: dict) -> tuple[BusConfig, int]:
        self._only(table, "bus", {"port", "connect", "listen", "mode", "low_latency", "lease_ms", "host_lease_ms"})
        port = self._get(table, "bus", "port", int, 0)
        if not 0 <= port <= 65535:
            raise self.fail("bus.port", f"{port} is not a TCP port")
        connect = tuple(self._get(table, "bus", "connect", list, []))
        listen = tuple(self._get(table, "bus", "listen", list, ["tcp/127.0.0.1:0"]))
        for key, endpoints in (("bus.connect", connect), ("bus.listen", listen)):
            for e in endpoints:
                if not isinstance(e, str) or "/" not in e:
                    raise self.fail(key, f"{e!r} is not a Zenoh endpoint like tcp/127.0.0.1:7447")
        try:
            bus = BusConfig(
                mode=self._get(table, "bus", "mode", str, "peer"),
                connect=connect,
                listen=listen,
                low_latency=self._get(table, "bus", "low_latency", bool, True),
                lease_ms=self._get(table, "bus", "lease_ms", int, BusConfig.lease_ms),
            )
        except ValueError as e:
            raise self.fail("bus.mode", str(e)) from None
        return bus, port

    def _host_lease(self, table: dict) -> int:
        lease = self._get(table, "bus", "host_lease_ms", int, DEFAULT_LEASE_MS)
        if lease < MIN_LEASE_MS:
            raise self.fail(
                "bus.host_lease_ms", f"{lease} ms is shorter than {MIN_LEASE_MS} ms (a beat every {BEAT_PERIOD_S:g} s)"
            )
        return lease

    def _airframe_params(self, airframe: str) -> dict[str, object]:
        if not airframe:
            return {}
        from stack.airframe.model import load_vehicle

        try:
            model = load_vehicle(airframe)
        except (ValueError, FileNotFoundError) as e:
            raise self.fail("stack.airframe", str(e)) from None
        return dict(model.airframe)

    def _module(self, i: int, entry: object, shared: dict[str, object], variables: dict[str, object]) -> ModuleEntry:
        where = f"module[{i}]"
        if not isinstance(entry, dict):
            raise self.fail(where, "expected a table")
        self._only(
            entry,
            where,
            {
                "name",
                "module",
                "params",
                "args",
                "condition",
                "restart",
                "max_restarts",
                "critical",
                "process",
                "transport",
                "host",
            },
        )
        ref = self._get(entry, where, "module", str, None)
        if ref is None:
            raise self.fail(f"{where}.module", "missing (which module to start)")
        try:
            cls = load_module_class(ref)
        except ValueError as e:
            raise self.fail(f"{where}.module", str(e)) from None
        name = self._get(entry, where, "name", str, cls.NAME or ref)
        try:
            keys.check_name("module", name)
        except ValueError as e:
            raise self.fail(f"{where}.name", str(e)) from None
        where = f"module[{i}] ({name})"
        declared = {p.name: p for p in cls.PARAMS}
        params: dict[str, ParamValue] = {}
        for pname, value in shared.items():
            if pname in declared:
                params[pname] = self._check_param(f"params.{pname}", declared, pname, value)
        for pname, value in self._table(entry, "params", where).items():
            if pname not in declared:
                raise self.fail(f"{where}.params.{pname}", f"{cls.NAME or ref} has no such parameter")
            params[pname] = self._check_param(f"{where}.params.{pname}", declared, pname, value)
        try:
            args = resolve_args(cls.ARGS, self._table(entry, "args", where))
        except ParamError as e:
            raise self.fail(f"{where}.args", str(e)) from None
        restart = self._get(entry, where, "restart", str, "no")
        if restart not in RESTART_POLICIES:
            raise self.fail(f"{where}.restart", f"'{restart}' is not one of {', '.join(RESTART_POLICIES)}")
        max_restarts = self._get(entry, where, "max_restarts", int, 5)
        if max_restarts < 0:
            raise self.fail(f"{where}.max_restarts", "must be >= 0")
        condition = self._get(entry, where, "condition", str, "")
        if condition:
            self._condition(f"{where}.condition", condition, variables, shared)
        process = self._get(entry, where, "process", str, "")
        if process:
            try:
                keys.check_name("process", process)
            except ValueError as e:
                raise self.fail(f"{where}.process", str(e)) from None
            if cls.PASSIVE or cls.OUTSIDE_LOCKSTEP:
                kind = "reads on the wall clock beside the lockstep" if cls.PASSIVE else "runs outside the lockstep"
                raise self.fail(
                    f"{where}.process", f"{name} {kind}; only lockstep modules can share a process (leave it its own)"
                )
        transport = self._get(entry, where, "transport", str, "shm")
        if transport not in LOCKSTEP_TRANSPORTS:
            raise self.fail(f"{where}.transport", f"'{transport}' is not one of {', '.join(LOCKSTEP_TRANSPORTS)}")
        if transport == "zenoh":
            if cls.PASSIVE or cls.OUTSIDE_LOCKSTEP or cls.LOCKSTEP_COORDINATOR:
                kind = "the lockstep's coordinator" if cls.LOCKSTEP_COORDINATOR else "not a lockstep member"
                raise self.fail(f"{where}.transport", f"{name} is {kind}; only lockstep members take part over Zenoh")
            if process:
                raise self.fail(f"{where}.transport", f"{name} over Zenoh runs in its own process (drop 'process')")
        return ModuleEntry(
            name=name,
            module=ref,
            cls=cls,
            params=params,
            args=args,
            condition=condition,
            restart=restart,
            max_restarts=max_restarts,
            critical=self._get(entry, where, "critical", bool, False),
            process=process,
            transport=transport,
            host=self._get(entry, where, "host", str, ""),
        )

    def _process(self, i: int, entry: object, shared: dict[str, object], variables: dict[str, object]) -> ProcessEntry:
        where = f"process[{i}]"
        if not isinstance(entry, dict):
            raise self.fail(where, "expected a table")
        self._only(
            entry,
            where,
            {"name", "command", "condition", "restart", "max_restarts", "critical", "ready_after_s", "host"},
        )
        name = self._get(entry, where, "name", str, None)
        if name is None:
            raise self.fail(f"{where}.name", "missing (a process needs a name)")
        try:
            keys.check_name("process", name)
        except ValueError as e:
            raise self.fail(f"{where}.name", str(e)) from None
        where = f"process[{i}] ({name})"
        command = self._get(entry, where, "command", list, None)
        if not command or not all(isinstance(part, str) and part for part in command):
            raise self.fail(f"{where}.command", "expected a non-empty list of non-empty strings (program, arguments)")
        for part in command:
            self._check_placeholders(f"{where}.command", part)
        restart = self._get(entry, where, "restart", str, "no")
        if restart not in RESTART_POLICIES:
            raise self.fail(f"{where}.restart", f"'{restart}' is not one of {', '.join(RESTART_POLICIES)}")
        max_restarts = self._get(entry, where, "max_restarts", int, 5)
        if max_restarts < 0:
            raise self.fail(f"{where}.max_restarts", "must be >= 0")
        ready_after_s = float(self._get(entry, where, "ready_after_s", float, 0.5))
        if not 0.0 <= ready_after_s <= 60.0:
            raise self.fail(f"{where}.ready_after_s", "must be between 0 and 60 s")
        condition = self._get(entry, where, "condition", str, "")
        if condition:
            self._condition(f"{where}.condition", condition, variables, shared)
        return ProcessEntry(
            name=name,
            command=list(command),
            condition=condition,
            restart=restart,
            max_restarts=max_restarts,
            critical=self._get(entry, where, "critical", bool, False),
            ready_after_s=ready_after_s,
            host=self._get(entry, where, "host", str, ""),
        )

    def _check_placeholders(self, key: str, text: str, allow_json: bool = False) -> None:
        """Every ``{name}`` must be one of PLACEHOLDERS (a module argument may also hold JSON)."""
        try:
            fields = [f for _, f, _, _ in string.Formatter().parse(text) if f is not None]
        except ValueError:
            if allow_json:
                return
            raise self.fail(key, f"unbalanced braces in {text!r}") from None
        for f in fields:
            if f not in PLACEHOLDERS and not (allow_json and not f.isidentifier()):
                raise self.fail(key, f"unknown placeholder {{{f}}} (known: {', '.join(PLACEHOLDERS)})")

    def _check_param(self, key: str, declared: dict, name: str, value: object) -> ParamValue:
        try:
            return declared[name].check(value)
        except ParamError as e:
            raise self.fail(key, str(e).split(": ", 1)[-1]) from None

    def _condition(self, key: str, text: str, variables: dict[str, object], params: dict[str, object]) -> bool:
        """Evaluate a start condition: flags (plot, record, realtime, lockstep) and parameter comparisons."""
        try:
            tree = ast.parse(text, mode="eval")
        except SyntaxError:
            raise self.fail(key, f"cannot parse condition {text!r}") from None
        return bool(self._eval(key, tree.body, {**params, **variables}))

    def _eval(self, key: str, node: ast.expr, env: dict[str, object]) -> object:
        if isinstance(node, ast.BoolOp):
            values = [self._eval(key, v, env) for v in node.values]
            return all(values) if isinstance(node.op, ast.And) else any(values)
        if isinstance(node, ast.UnaryOp) and isinstance(node.op, ast.Not):
            return not self._eval(key, node.operand, env)
        if isinstance(node, ast.Compare) and len(node.ops) == 1:
            left = self._eval(key, node.left, env)
            right = self._eval(key, node.comparators[0], env)
            ops = {
                ast.Eq: "__eq__",
                ast.NotEq: "__ne__",
                ast.Lt: "__lt__",
                ast.LtE: "__le__",
                ast.Gt: "__gt__",
                ast.GtE: "__ge__",
            }
            op = ops.get(type(node.ops[0]))
            if op is None:
                raise self.fail(key, "only ==, !=, <, <=, >, >= comparisons are allowed")
            return getattr(left, op)(right) is True
        if isinstance(node, ast.Name):
            if node.id in env:
                return env[node.id]
            if node.id in FLAGS:
                return False
            raise self.fail(key, f"unknown name '{node.id}' (use a flag: {', '.join(FLAGS)}, or a set parameter)")
        if isinstance(node, ast.Constant) and isinstance(node.value, int | float | str | bool):
            return node.value
        raise self.fail(key, "conditions may only use names, numbers, comparisons, and/or/not")

    # -- small typed accessors -------------------------------------------------------------------------

    def _only(self, table: dict, where: str, allowed: set[str]) -> None:
        for k in table:
            if k not in allowed:
                prefix = f"{where}." if where else ""
                raise self.fail(f"{prefix}{k}", f"unknown key (expected one of: {', '.join(sorted(allowed))})")

    def _table(self, doc: dict, key: str, where: str = "") -> dict:
        value = doc.get(key, {})
        if not isinstance(value, dict):
            raise self.fail(f"{where}.{key}" if where else key, "expected a table")
        return value

    def _open_topics(self, stack: dict) -> tuple[str, ...]:
        topics = self._get(stack, "stack", "open_topics", list, [])
        for i, topic in enumerate(topics):
            if topic not in TOPICS:
                raise self.fail(f"stack.open_topics[{i}]", f"'{topic}' is not a topic{suggestion(str(topic), TOPICS)}")
        return tuple(topics)

    def _get(self, table: dict, where: str, key: str, typ: type, default: object) -> object:
        if key not in table:
            return default
        value = table[key]
        ok = isinstance(value, typ) and not (typ is int and isinstance(value, bool))
        if typ is float and isinstance(value, int) and not isinstance(value, bool):
            ok = True
        if not ok:
            raise self.fail(f"{where}.{key}", f"expected {typ.__name__}, got {value!r}")
        return value
