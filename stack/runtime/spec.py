"""What the supervisor tells a module process: which module, its name, parameters, arguments, bus."""

from __future__ import annotations

import importlib
import json
from dataclasses import asdict, dataclass, field
from typing import TYPE_CHECKING

from stack.bus.config import BusConfig
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
    "pixhawk": "stack.mavlink.module:PixhawkAdapterModule",
    "mavlink": "stack.gcs.module:MavlinkModule",
    "rerun_bridge": "stack.viz.module:RerunBridgeModule",
    "recorder": "stack.record.module:RecorderModule",
    "scenario": "stack.scenario.module:ScenarioModule",
    "airspeed_selector": "stack.fw.airspeed_module:AirspeedSelectorModule",
    "fw_att_control": "stack.fw.att_module:FixedwingAttitudeControl",
    "fw_pos_control": "stack.fw.pos_module:FixedwingPositionControl",
    "navigator": "stack.fw.navigator_module:NavigatorModule",
}


def load_module_class(ref: str) -> type[Module]:
    """A module class from a registry name or a ``package.module:Class`` path."""
    path = MODULES.get(ref, ref)
    if ":" not in path:
        known = ", ".join(sorted(MODULES))
        raise ValueError(f"unknown module '{ref}' (known: {known}; or give package.module:Class)")
    mod_name, cls_name = path.split(":", 1)
    try:
        cls = getattr(importlib.import_module(mod_name), cls_name)
    except (ImportError, AttributeError) as e:
        raise ValueError(f"module '{ref}' cannot be loaded from {path}: {e}") from None
    from stack.runtime.module import Module

    if not (isinstance(cls, type) and issubclass(cls, Module)):
        raise ValueError(f"module '{ref}': {path} is not a stack Module class")
    return cls


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

    def to_json(self) -> str:
        d = asdict(self)
        d["bus"] = json.loads(self.bus.to_json())
        return json.dumps(d)

    @staticmethod
    def from_json(text: str) -> ModuleSpec:
        d = json.loads(text)
        d["bus"] = BusConfig.from_json(json.dumps(d["bus"]))
        return ModuleSpec(**d)
