"""Multicopter vehicle models as data: loading and validating ``stack/sim/vehicles/*.toml``.

A vehicle file holds the rigid-body figures (mass, diagonal inertia), the rotors (position in FRD
metres, spin direction), the motor and rotor model, the body drag, and an ``[airframe]`` table of
PX4 control-allocation parameters (``CA_ROTOR*``, ``THR_MDL_FAC``, ``MPC_THR_HOVER``) that launch
profiles hand to the mixer. The loader checks that the airframe table agrees with the geometry, so
the plant and the mixer are configured from one set of figures.

Two thrust models are supported:

* ``linear`` (PX4 SIH, ``simulator_sih``): thrust = ``max_thrust``·s and yaw moment =
  ``max_moment``·s, with s the motor state in [0, 1] following the command.
* ``quadratic`` (RotorS ``gazebo_motor_model``): the command sets the rotor speed ω = u·ω_max,
  thrust = k_F·ω², reaction moment = k_M·thrust (k_M in metres).

Both are expressed as thrust = ``max_thrust``·f(s), f(s) = s or s², with ``moment_ratio`` the
yaw-moment-to-thrust ratio; that is exactly PX4's ``CA_ROTORi_CT`` / ``CA_ROTORi_KM`` and
``THR_MDL_FAC`` (0 or 1) view of a rotor.

Sign convention (PX4's): a rotor spinning counter-clockwise seen from above (``spin = "ccw"``)
pushes the air clockwise around it, so its reaction moment turns the body clockwise seen from above,
which is a positive moment about the FRD z (down) axis. Its ``CA_ROTORi_KM`` is therefore positive.
"""

from __future__ import annotations

import math
import re
import tomllib
from collections.abc import Mapping
from dataclasses import dataclass, replace
from pathlib import Path
from types import MappingProxyType
from typing import Any

from stack.mathlib.scalar import CONSTANTS_ONE_G
from stack.mathlib.vector import Vec3

VEHICLES_DIR = Path(__file__).with_name("vehicles")

THRUST_MODELS = ("linear", "quadratic")
SPIN_CCW = 1
SPIN_CW = -1

_PARAM_NAME = re.compile(r"^[A-Z][A-Z0-9_]*$")
_ROTOR_PARAM = re.compile(r"^CA_ROTOR(\d+)_(PX|PY|PZ|KM|CT)$")
_POSITION_TOLERANCE = 1e-6
_KM_TOLERANCE = 1e-6
_CT_RELATIVE_TOLERANCE = 1e-3
_HOVER_TOLERANCE = 0.005


@dataclass(frozen=True, slots=True)
class Rotor:
    """One rotor: hub position in the body frame (FRD, m) and spin direction (+1 CCW, −1 CW seen from above).

    The thrust axis is the body −z axis for every rotor (PX4's default ``CA_ROTORi_AX/AY/AZ`` = 0, 0, −1).
    """

    position: Vec3
    spin: int


@dataclass(frozen=True, slots=True)
class MotorModel:
    """Motor and rotor aerodynamics shared by all rotors of a vehicle.

    ``max_thrust`` is the thrust of one rotor at full command (N; PX4 ``CA_ROTORi_CT``).
    ``moment_ratio`` is the reaction moment per unit thrust (m; PX4 ``CA_ROTORi_KM`` magnitude).
    ``max_rotor_speed`` (rad/s) is 0 for the linear model, which has no rotor speed.
    ``rotor_drag_coefficient`` is RotorS' H-force coefficient k_D (N per (rad/s)·(m/s)) and
    ``rolling_moment_coefficient`` RotorS' k_R (N·m per (rad/s)·(m/s)).
    """

    thrust_model: str
    max_thrust: float
    moment_ratio: float
    max_rotor_speed: float
    time_constant_up: float
    time_constant_down: float
    rotor_drag_coefficient: float
    rolling_moment_coefficient: float

    def thrust_fraction(self, motor_state: float) -> float:
        """Rotor thrust as a fraction of ``max_thrust`` for a motor state (= steady command) in [0, 1]."""
        return motor_state * motor_state if self.thrust_model == "quadratic" else motor_state

    def command_for_thrust_fraction(self, fraction: float) -> float:
        """Steady motor command that produces ``fraction`` of ``max_thrust`` (inverse of ``thrust_fraction``)."""
        return math.sqrt(fraction) if self.thrust_model == "quadratic" else fraction


@dataclass(frozen=True, slots=True)
class BodyDrag:
    """Drag of the airframe itself, isotropic, on the air-relative velocity and the body rates.

    ``linear`` N/(m/s) (PX4 ``SIH_KDV``), ``quadratic`` N/(m/s)², ``angular`` N·m/(rad/s) (``SIH_KDW``).
    """

    linear: float
    quadratic: float
    angular: float


@dataclass(frozen=True, slots=True)
class VehicleModel:
    """A multicopter model loaded from a vehicle TOML file (see the module docstring)."""

    name: str
    description: str
    mass: float
    inertia: Vec3
    rotors: tuple[Rotor, ...]
    motor: MotorModel
    drag: BodyDrag
    airframe: Mapping[str, float]
    path: str

    @property
    def rotor_count(self) -> int:
        return len(self.rotors)

    @property
    def hover_thrust_fraction(self) -> float:
        """Collective thrust at hover as a fraction of the total maximum thrust (PX4 ``MPC_THR_HOVER``)."""
        return self.mass * CONSTANTS_ONE_G / (len(self.rotors) * self.motor.max_thrust)

    @property
    def hover_command(self) -> float:
        """Motor command in [0, 1] that, given to every rotor, makes the total thrust equal the weight."""
        return self.motor.command_for_thrust_fraction(self.hover_thrust_fraction)


def available_vehicles() -> list[str]:
    """Names of the vehicle files shipped in ``stack/sim/vehicles``."""
    return sorted(p.stem for p in VEHICLES_DIR.glob("*.toml"))


def load_vehicle(name_or_path: str | Path) -> VehicleModel:
    """Load a vehicle by name (``"sih_quad"``) or by path to a TOML file.

    Raises ``ValueError`` naming the file, the key and the problem when the file is malformed,
    incomplete or inconsistent (e.g. ``"hummingbird.toml: rotor[2].position: expected 3 numbers"``).
    """
    text = str(name_or_path)
    if isinstance(name_or_path, Path) or text.endswith(".toml") or "/" in text or "\\" in text:
        path = Path(name_or_path)
    else:
        path = VEHICLES_DIR / f"{text}.toml"
        if not path.is_file():
            raise ValueError(f"unknown vehicle {text!r}; available: {', '.join(available_vehicles())}")
    with path.open("rb") as f:
        try:
            data = tomllib.load(f)
        except tomllib.TOMLDecodeError as exc:
            raise ValueError(f"{path.name}: invalid TOML: {exc}") from None
    return _Parser(path).vehicle(data)


class _Parser:
    """Validating reader of one vehicle file; every error names the file and the key."""

    def __init__(self, path: Path) -> None:
        self.path = path

    def error(self, key: str, problem: str) -> ValueError:
        return ValueError(f"{self.path.name}: {key}: {problem}")

    def table(self, data: Mapping[str, Any], key: str, allowed: set[str]) -> Mapping[str, Any]:
        value = data.get(key)
        if not isinstance(value, dict):
            raise self.error(key, "expected a table")
        for k in value:
            if k not in allowed:
                raise self.error(f"{key}.{k}", "unknown key")
        return value

    def number(self, data: Mapping[str, Any], key: str, where: str, minimum: float | None = None,
               positive: bool = False, default: float | None = None) -> float:
        if key not in data:
            if default is not None:
                return default
            raise self.error(where, "missing")
        value = data[key]
        if isinstance(value, bool) or not isinstance(value, int | float) or not math.isfinite(value):
            raise self.error(where, "expected a finite number")
        if positive and value <= 0.0:
            raise self.error(where, f"must be > 0, got {value}")
        if minimum is not None and value < minimum:
            raise self.error(where, f"must be >= {minimum}, got {value}")
        return float(value)

    def vector(self, value: Any, where: str) -> Vec3:
        if (
            not isinstance(value, list)
            or len(value) != 3
            or not all(isinstance(v, int | float) and not isinstance(v, bool) and math.isfinite(v) for v in value)
        ):
            raise self.error(where, "expected 3 numbers")
        return (float(value[0]), float(value[1]), float(value[2]))

    def string(self, data: Mapping[str, Any], key: str, where: str) -> str:
        value = data.get(key)
        if not isinstance(value, str) or not value:
            raise self.error(where, "expected a non-empty string")
        return value

    def vehicle(self, data: Mapping[str, Any]) -> VehicleModel:
        allowed = {"name", "description", "mass", "inertia", "motor", "drag", "rotor", "airframe"}
        for k in data:
            if k not in allowed:
                raise self.error(k, "unknown key")
        name = self.string(data, "name", "name")
        description = self.string(data, "description", "description")
        mass = self.number(data, "mass", "mass", positive=True)
        if "inertia" not in data:
            raise self.error("inertia", "missing")
        inertia = self.vector(data["inertia"], "inertia")
        if min(inertia) <= 0.0:
            raise self.error("inertia", "every diagonal element must be > 0")
        motor = self.motor(data)
        drag = self.drag(data)
        rotors = self.rotors(data)
        model = VehicleModel(
            name=name,
            description=description,
            mass=mass,
            inertia=inertia,
            rotors=rotors,
            motor=motor,
            drag=drag,
            airframe=MappingProxyType({}),
            path=str(self.path),
        )
        return replace(model, airframe=self.airframe(data, model))

    def motor(self, data: Mapping[str, Any]) -> MotorModel:
        common = {"thrust_model", "time_constant_up", "time_constant_down", "rotor_drag_coefficient",
                  "rolling_moment_coefficient"}
        table = self.table(data, "motor", common | {"max_thrust", "max_moment", "motor_constant",
                                                     "moment_constant", "max_rotor_speed"})
        kind = table.get("thrust_model")
        if kind not in THRUST_MODELS:
            raise self.error("motor.thrust_model", f"expected one of {', '.join(THRUST_MODELS)}")
        if kind == "linear":
            for k in ("motor_constant", "moment_constant", "max_rotor_speed"):
                if k in table:
                    raise self.error(f"motor.{k}", 'only for thrust_model = "quadratic"')
            max_thrust = self.number(table, "max_thrust", "motor.max_thrust", positive=True)
            moment_ratio = self.number(table, "max_moment", "motor.max_moment", minimum=0.0) / max_thrust
            max_rotor_speed = 0.0
        else:
            for k in ("max_thrust", "max_moment"):
                if k in table:
                    raise self.error(f"motor.{k}", 'only for thrust_model = "linear"')
            k_f = self.number(table, "motor_constant", "motor.motor_constant", positive=True)
            moment_ratio = self.number(table, "moment_constant", "motor.moment_constant", minimum=0.0)
            max_rotor_speed = self.number(table, "max_rotor_speed", "motor.max_rotor_speed", positive=True)
            max_thrust = k_f * max_rotor_speed * max_rotor_speed
        rotor_drag = self.number(table, "rotor_drag_coefficient", "motor.rotor_drag_coefficient", minimum=0.0,
                                 default=0.0)
        rolling = self.number(table, "rolling_moment_coefficient", "motor.rolling_moment_coefficient",
                              minimum=0.0, default=0.0)
        if kind == "linear":
            if rotor_drag > 0.0:
                raise self.error("motor.rotor_drag_coefficient", 'needs thrust_model = "quadratic" (a rotor speed)')
            if rolling > 0.0:
                raise self.error("motor.rolling_moment_coefficient",
                                 'needs thrust_model = "quadratic" (a rotor speed)')
        return MotorModel(
            thrust_model=kind,
            max_thrust=max_thrust,
            moment_ratio=moment_ratio,
            max_rotor_speed=max_rotor_speed,
            time_constant_up=self.number(table, "time_constant_up", "motor.time_constant_up", positive=True),
            time_constant_down=self.number(table, "time_constant_down", "motor.time_constant_down", positive=True),
            rotor_drag_coefficient=rotor_drag,
            rolling_moment_coefficient=rolling,
        )

    def drag(self, data: Mapping[str, Any]) -> BodyDrag:
        table = self.table(data, "drag", {"linear", "quadratic", "angular"})
        return BodyDrag(
            linear=self.number(table, "linear", "drag.linear", minimum=0.0),
            quadratic=self.number(table, "quadratic", "drag.quadratic", minimum=0.0),
            angular=self.number(table, "angular", "drag.angular", minimum=0.0),
        )

    def rotors(self, data: Mapping[str, Any]) -> tuple[Rotor, ...]:
        entries = data.get("rotor")
        if not isinstance(entries, list) or not all(isinstance(e, dict) for e in entries):
            raise self.error("rotor", "expected an array of tables ([[rotor]])")
        if len(entries) < 3:
            raise self.error("rotor", f"a multicopter needs at least 3 rotors, got {len(entries)}")
        rotors = []
        for i, entry in enumerate(entries):
            where = f"rotor[{i}]"
            for k in entry:
                if k not in ("position", "spin"):
                    raise self.error(f"{where}.{k}", "unknown key")
            if "position" not in entry:
                raise self.error(f"{where}.position", "missing")
            position = self.vector(entry["position"], f"{where}.position")
            spin = entry.get("spin")
            if spin not in ("ccw", "cw"):
                raise self.error(f"{where}.spin", 'expected "ccw" or "cw"')
            rotors.append(Rotor(position=position, spin=SPIN_CCW if spin == "ccw" else SPIN_CW))
        return tuple(rotors)

    def airframe(self, data: Mapping[str, Any], model: VehicleModel) -> Mapping[str, float]:
        table = data.get("airframe")
        if not isinstance(table, dict):
            raise self.error("airframe", "expected a table")
        params: dict[str, float] = {}
        n = model.rotor_count
        for key, value in table.items():
            where = f"airframe.{key}"
            if not _PARAM_NAME.match(key):
                raise self.error(where, "expected an upper-case PX4 parameter name")
            if isinstance(value, bool) or not isinstance(value, int | float) or not math.isfinite(value):
                raise self.error(where, "expected a finite number")
            match = _ROTOR_PARAM.match(key)
            if match and int(match.group(1)) >= n:
                raise self.error(where, f"rotor index out of range (the vehicle has {n} rotors)")
            params[key] = value

        def need(key: str) -> float:
            if key not in params:
                raise self.error(f"airframe.{key}", "missing")
            return params[key]

        if need("CA_ROTOR_COUNT") != n:
            raise self.error("airframe.CA_ROTOR_COUNT", f"is {params['CA_ROTOR_COUNT']}, the vehicle has {n} rotors")
        for i, rotor in enumerate(model.rotors):
            for axis, coordinate in zip(("PX", "PY", "PZ"), rotor.position, strict=True):
                key = f"CA_ROTOR{i}_{axis}"
                if abs(need(key) - coordinate) > _POSITION_TOLERANCE:
                    raise self.error(f"airframe.{key}", f"is {params[key]}, rotor[{i}].position gives {coordinate}")
            key = f"CA_ROTOR{i}_KM"
            expected_km = rotor.spin * model.motor.moment_ratio
            if abs(need(key) - expected_km) > _KM_TOLERANCE:
                raise self.error(f"airframe.{key}",
                                 f"is {params[key]}, expected {expected_km:.6g} (positive for a ccw rotor)")
            key = f"CA_ROTOR{i}_CT"
            if abs(need(key) - model.motor.max_thrust) > _CT_RELATIVE_TOLERANCE * model.motor.max_thrust:
                raise self.error(f"airframe.{key}", f"is {params[key]}, the motor gives {model.motor.max_thrust:.6g} N")
        expected_fac = 1.0 if model.motor.thrust_model == "quadratic" else 0.0
        if need("THR_MDL_FAC") != expected_fac:
            raise self.error("airframe.THR_MDL_FAC",
                             f"is {params['THR_MDL_FAC']}, the {model.motor.thrust_model} motor needs {expected_fac:g}")
        hover = model.hover_thrust_fraction
        if not 0.0 < hover < 1.0:
            raise self.error("mass", f"the rotors cannot lift the vehicle (hover thrust fraction {hover:.3f})")
        if abs(need("MPC_THR_HOVER") - hover) > _HOVER_TOLERANCE:
            raise self.error("airframe.MPC_THR_HOVER", f"is {params['MPC_THR_HOVER']}, the model hovers at {hover:.4f}")
        return MappingProxyType(params)
