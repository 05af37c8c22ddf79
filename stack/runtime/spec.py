"""What the supervisor tells a module process: which module, its name, parameters, arguments, bus."""

from __future__ import annotations

import ast
import importlib
import importlib.machinery
import importlib.util
import json
import re
import sys
from dataclasses import asdict, dataclass, field
from typing import TYPE_CHECKING

from stack.bus.config import BusConfig
from stack.bus.supervisors import SINGLE_HOST
from stack.params.param import ParamError, ParamValue

if TYPE_CHECKING:
    from stack.runtime.module import Arg, Module

# The modules of the product, by the name a launch profile uses (like PX4's module names).
MODULES: dict[str, str] = {
    "simulator": "stack.sim.module:SimulatorModule",
    "attitude_estimator_q": "stack.estimator.attitude_module:AttitudeEstimatorModule",
    "local_position_estimator": "stack.estimator.position_module:LocalPositionEstimatorModule",
    "mc_att_control": "stack.attctl.att_module:MulticopterAttitudeControl",
    "mc_rate_control": "stack.attctl.rate_module:MulticopterRateControl",
    "control_allocator": "stack.mixer.module:ControlAllocatorModule",
    "roll_pitch_yawrate_thrust_controller": "stack.attctl.rpyt_module:RollPitchYawrateThrustController",
    "rotors_joy_interface": "stack.attctl.rotors_joy_module:RotorsJoyInterface",
    "commander": "stack.commander.module:CommanderModule",
    "mc_pos_control": "stack.posctl.pos_module:MulticopterPositionControl",
    "flight_mode_manager": "stack.posctl.fmm_module:FlightModeManagerModule",
    "mc_hover_thrust_estimator": "stack.posctl.hte_module:HoverThrustEstimatorModule",
    "pixhawk": "stack.pixhawk.module:PixhawkAdapterModule",
    "mavlink": "stack.mavlink.module:MavlinkModule",
    "rerun_bridge": "stack.viz.module:RerunBridgeModule",
    "recorder": "stack.record.module:RecorderModule",
    "scenario": "stack.scenario.module:ScenarioModule",
    "airspeed_selector": "stack.fw.airspeed_module:AirspeedSelectorModule",
    "fw_att_control": "stack.fw.att_module:FixedwingAttitudeControl",
    "fw_pos_control": "stack.fw.pos_module:FixedwingPositionControl",
    "navigator": "stack.fw.navigator_module:NavigatorModule",
}


_DOTTED = re.compile(r"^[A-Za-z_][A-Za-z0-9_]*(\.[A-Za-z_][A-Za-z0-9_]*)*$")
_IDENTIFIER = re.compile(r"^[A-Za-z_][A-Za-z0-9_]*$")


def load_module_class(ref: str) -> type[Module]:
    """A module class from a registry name or a ``package.module:Class`` path.

    A path is code the profile runs, as a ROS 2 launch file runs the nodes it names. Before importing it, what
    can be checked without executing anything is: the path's form, that the module is installed or on the path,
    and that its source binds the class's name; a path failing these is refused with nothing imported.
    """
    if ref in MODULES:
        mod_name, cls_name = MODULES[ref].split(":")
    else:
        mod_name, _, cls_name = ref.partition(":")
        if not _DOTTED.match(mod_name) or not _IDENTIFIER.match(cls_name):
            known = ", ".join(sorted(MODULES))
            raise ValueError(f"unknown module '{ref}' (known: {known}; or give package.module:Class)")
        spec = _find_without_importing(mod_name)
        if spec is None:
            raise ValueError(f"module '{ref}' cannot be loaded: no module '{mod_name}' is installed or on the path")
        if not _may_define(spec, cls_name):
            raise ValueError(f"module '{ref}' cannot be loaded: {mod_name} ({spec.origin}) defines no '{cls_name}'")
    path = f"{mod_name}:{cls_name}"
    try:
        cls = getattr(importlib.import_module(mod_name), cls_name)
    except Exception as e:  # whatever the module raised on import: one line, not a traceback
        raise ValueError(f"module '{ref}' cannot be loaded from {path}: {type(e).__name__}: {e}") from None
    from stack.runtime.module import Module

    if not (isinstance(cls, type) and issubclass(cls, Module)):
        raise ValueError(f"module '{ref}': {path} is not a stack Module class")
    return cls


def _find_without_importing(name: str) -> importlib.machinery.ModuleSpec | None:
    """The spec of module ``name``, or None if there is none. ``importlib.util.find_spec`` imports (runs) the
    packages a dotted name lies in, so only the top-level name goes through it; each part below is looked for in
    its package's directories."""
    parts = name.split(".")
    spec: importlib.machinery.ModuleSpec | None = None
    for i in range(len(parts)):
        full = ".".join(parts[: i + 1])
        loaded = sys.modules.get(full)
        if loaded is not None and getattr(loaded, "__spec__", None) is not None:
            spec = loaded.__spec__
        elif i == 0:
            try:
                spec = importlib.util.find_spec(full)
            except ValueError:  # in sys.modules without a spec (__main__ run as a script)
                return None
        elif spec is None or spec.submodule_search_locations is None:
            return None
        else:
            spec = importlib.machinery.PathFinder.find_spec(full, list(spec.submodule_search_locations))
        if spec is None:
            return None
    return spec


def _may_define(spec: importlib.machinery.ModuleSpec, name: str) -> bool:
    """False only if the module's source surely binds no ``name`` at its top level (any assignment, import,
    definition, ``import *`` or module ``__getattr__`` counts); a module without source is given the benefit."""
    if not isinstance(spec.loader, importlib.machinery.SourceFileLoader) or spec.origin is None:
        return True
    try:
        with open(spec.origin, "rb") as f:
            tree = ast.parse(f.read(), spec.origin)
    except (OSError, SyntaxError, ValueError):
        return True  # the import says what is wrong
    bound: set[str] = set()
    todo: list[ast.stmt] = list(tree.body)
    while todo:
        node = todo.pop()
        if isinstance(node, (ast.ClassDef, ast.FunctionDef, ast.AsyncFunctionDef)):
            bound.add(node.name)
        elif isinstance(node, (ast.Import, ast.ImportFrom)):
            for alias in node.names:
                if alias.name == "*":
                    return True
                bound.add(alias.asname or alias.name.split(".")[0])
        elif isinstance(node, (ast.Assign, ast.AnnAssign, ast.AugAssign)):
            targets = node.targets if isinstance(node, ast.Assign) else [node.target]
            bound.update(n.id for t in targets for n in ast.walk(t) if isinstance(n, ast.Name))
        else:
            # Top-level blocks (if, try, with, for, match) bind names at the top level too.
            todo.extend(child for child in ast.iter_child_nodes(node) if isinstance(child, ast.stmt))
            for handler in getattr(node, "handlers", []):
                todo.extend(handler.body)
            for case in getattr(node, "cases", []):
                todo.extend(case.body)
        if "__getattr__" in bound or name in bound:
            return True
    return False


def resolve_args(declared: tuple[Arg, ...], given: dict[str, object]) -> dict[str, ParamValue]:
    by_name = {a.name: a for a in declared}
    unknown = sorted(set(given) - set(by_name))
    if unknown:
        raise ParamError(f"unknown argument '{unknown[0]}' (accepted: {', '.join(sorted(by_name)) or 'none'})")
    return {a.name: a.check(given[a.name]) if a.name in given else a.default for a in declared}


@dataclass
class ModuleSpec:
    name: str
    module: str
    vehicle: str = "v1"
    bus: BusConfig = field(default_factory=BusConfig)
    params: dict[str, ParamValue] = field(default_factory=dict)
    args: dict[str, ParamValue] = field(default_factory=dict)
    lockstep: bool = False
    # The lockstep's pace (stack.runtime.pacing): simulated seconds per wall-clock second; 0 as fast as possible.
    speed: float = 0.0
    seed: int = 1
    log_level: str = "INFO"
    supervisor_pid: int = 0
    stall_timeout_s: float = 10.0
    run_dir: str = ""
    # A restart while the stack runs: join the lockstep without the start-up probe handshake.
    late_join: bool = False
    # The lockstep run's random id (stack.bus.topics.HEADER) and, on the same-host fast path, the
    # inherited file descriptor of its shared-memory region (stack.fastpath); -1 when over Zenoh.
    run_id: int = 0
    fastpath_fd: int = -1
    # Whom the module hears (stack.bus.access): the profile's modules by name, each with the topics it publishes, and
    # the topics the profile opens to anyone beyond those open to tools. No modules: one outside any profile hears
    # everyone.
    peers: dict[str, list[str]] = field(default_factory=dict)
    open_topics: list[str] = field(default_factory=list)
    # A shared-memory run's members over Zenoh (a profile's transport = "zenoh"), whose places in the run the
    # coordinator's process serves (stack.fastpath.bridge): given to the coordinator.
    bridged: list[str] = field(default_factory=list)
    # A member over Zenoh in a shared-memory run: the modules whose start-up sync it waits for (the others do
    # not sync over Zenoh). None: every module of the roster.
    sync_with: list[str] | None = None
    # The hosts whose supervisors start the vehicle's modules: the lockstep's roster is complete once each of
    # them has started its own (stack.bus.supervisors).
    hosts: list[str] = field(default_factory=lambda: [SINGLE_HOST])
    # A shared-memory lockstep run, whose shared memory is on the coordinator's host (this module's or another).
    shm_run: bool = False
    # The vehicle's modules outside the lockstep (links, observers), wherever they run.
    outside: list[str] = field(default_factory=list)
    # A vehicle over several hosts: this module's host, every host's modules, and how long a host may go without a
    # beat before it counts as lost (stack.bus.host_beats). No placement: one host.
    host: str = SINGLE_HOST
    placement: dict[str, list[str]] = field(default_factory=dict)
    host_lease_ms: int = 0
    # A swarm's one simulated clock (stack.runtime.world_clock), given to the lockstep's coordinator: the world's file
    # (empty: a vehicle on its own clock), this vehicle's slot in it and the vehicles by slot.
    world: str = ""
    world_slot: int = -1
    world_vehicles: list[str] = field(default_factory=list)

    def to_json(self) -> str:
        d = asdict(self)
        d["bus"] = json.loads(self.bus.to_json())
        return json.dumps(d)

    @staticmethod
    def from_json(text: str) -> ModuleSpec:
        d = json.loads(text)
        d["bus"] = BusConfig.from_json(json.dumps(d["bus"]))
        return ModuleSpec(**d)
