"""Vehicle models as data: loading and validating ``stack/airframe/vehicles/*.toml``.

A file's ``type`` says what it describes: ``"multicopter"`` (the default) or ``"fixedwing"`` (see
:class:`FixedwingModel`, the PX4 SIH airplane's figures: aerodynamic segments, thruster, landing gear).

A multicopter file holds the rigid-body figures (mass, diagonal inertia), the rotors (position in FRD
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
from typing import TYPE_CHECKING, Any

from stack.mathlib.atmosphere import AIR_DENSITY_SEA_LEVEL
from stack.mathlib.scalar import CONSTANTS_ONE_G
from stack.mathlib.vector import Vec3

if TYPE_CHECKING:
    from stack.airframe.jsbsim import JsbsimAircraft

VEHICLES_DIR = Path(__file__).with_name("vehicles")

VEHICLE_TYPES = ("multicopter", "fixedwing", "jsbsim")
THRUST_MODELS = ("linear", "quadratic")
SPIN_CCW = 1
SPIN_CW = -1
FIXEDWING_CONTROLS = ("aileron", "elevator", "rudder")
"""The plane's surfaces in the order of ``actuator_outputs_sim`` output[1..3] (output[0] is the throttle)."""
CA_AIRFRAME_FIXEDWING = 1  # PX4 CA_AIRFRAME: 1 = fixed wing

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
    def input_count(self) -> int:
        """Actuator outputs the plant reads: one motor command per rotor."""
        return len(self.rotors)

    @property
    def hover_thrust_fraction(self) -> float:
        """Collective thrust at hover as a fraction of the total maximum thrust (PX4 ``MPC_THR_HOVER``)."""
        return self.mass * CONSTANTS_ONE_G / (len(self.rotors) * self.motor.max_thrust)

    @property
    def hover_command(self) -> float:
        """Motor command in [0, 1] that, given to every rotor, makes the total thrust equal the weight."""
        return self.motor.command_for_thrust_fraction(self.hover_thrust_fraction)


def propeller_thrust(
    throttle: float, axial_speed: float, density: float, diameter: float, max_rpm: float,
    coefficients: tuple[float, float, float],
) -> float:
    """Thrust (N) of a propeller with the advance-ratio model of PX4 SIH's ``Thruster`` (aero.hpp; UIUC
    propeller database fits): n = rpm_max·√u / 60 rev/s, J = V/(n·D), T = max(C_T(J), 0)·ρ·n²·D⁴ with
    C_T(J) = c0 + c1·J + c2·J² (no windmilling)."""
    if throttle <= 0.0:
        return 0.0
    n = max_rpm * math.sqrt(min(throttle, 1.0)) / 60.0
    if n <= 1e-4:
        return 0.0
    j = axial_speed / (n * diameter)
    c0, c1, c2 = coefficients
    ct = c0 + c1 * j + c2 * j * j
    if ct <= 0.0:
        return 0.0
    d2 = diameter * diameter
    return ct * density * n * n * d2 * d2


@dataclass(frozen=True, slots=True)
class Propeller:
    """PX4 SIH's advance-ratio propeller (SIH_F_DIA_INCH, SIH_F_RPM_MAX, SIH_F_CT0..2): see
    :func:`propeller_thrust`. ``diameter`` in m."""

    diameter: float
    max_rpm: float
    thrust_coefficients: tuple[float, float, float]


@dataclass(frozen=True, slots=True)
class Thruster:
    """A fixed-wing's propeller, pulling along body +x through the centre of gravity (no torque).

    With ``propeller`` None the thrust is ``max_thrust``·s at every speed (SIH_T_MAX); otherwise the
    propeller model gives it and ``max_thrust`` is its static thrust at full throttle at sea level.
    s follows the throttle command with the first-order lag ``time_constant`` (SIH_T_TAU);
    ``prop_radius`` (m) sizes the slipstream √(2T/(ρπr²)) on the segments in it.
    """

    max_thrust: float
    time_constant: float
    prop_radius: float
    propeller: Propeller | None


@dataclass(frozen=True, slots=True)
class AeroSurfaceSegment:
    """One flat-plate segment of a fixed-wing (:class:`stack.sim.aero.AeroSegment`), angles in rad.

    ``control`` names the input that deflects its flap (one of FIXEDWING_CONTROLS, or None) and
    ``direction`` (±1) the sign of the flap angle for a positive command; ``slipstream`` says whether the
    propeller's wake washes it; ``stall_angle`` None means the flat-plate table's.
    """

    name: str
    span: float
    chord: float
    position: Vec3
    alpha_0: float
    dihedral: float
    aspect_ratio: float
    flap_chord: float
    control: str | None
    direction: int
    slipstream: bool
    lift_slope: float
    stall_angle: float | None


@dataclass(frozen=True, slots=True)
class GroundContact:
    """A landing-gear contact point (body FRD, m): a spring-damper normal to the ground.

    A ``wheel`` rolls along its direction (body x, turned by the steering angle if ``steering``) and grips
    across it; a skid (``wheel`` False) slides with the skid friction every way. ``brake``: the wheel is
    braked while the throttle command is below the ground's ``brake_throttle``.
    """

    name: str
    position: Vec3
    stiffness: float
    damping: float
    wheel: bool
    steering: bool
    brake: bool


@dataclass(frozen=True, slots=True)
class GroundModel:
    """Friction figures shared by the contacts (coefficients of the normal force; see the vehicle file)."""

    rolling_friction: float
    side_friction: float
    brake_friction: float
    skid_friction: float
    tread_stiffness: float
    tread_damping: float
    rolling_speed: float
    max_steering: float
    brake_throttle: float


@dataclass(frozen=True, slots=True)
class FixedwingModel:
    """A fixed-wing model loaded from a ``type = "fixedwing"`` vehicle file.

    ``inertia`` is the diagonal and ``inertia_xz`` the xz element of the inertia tensor (kg·m²; PX4 SIH puts
    SIH_IXZ into I(0, 2) and I(2, 0) as it is). ``max_deflection`` (rad) is the flap angle at a ±1 command.
    The inputs are (throttle [0, 1], aileron, elevator, rudder [−1, 1]).
    """

    name: str
    description: str
    mass: float
    inertia: Vec3
    inertia_xz: float
    thruster: Thruster
    segments: tuple[AeroSurfaceSegment, ...]
    max_deflection: float
    drag: BodyDrag
    contacts: tuple[GroundContact, ...]
    ground: GroundModel
    airframe: Mapping[str, float]
    path: str

    @property
    def input_count(self) -> int:
        """Actuator outputs the plant reads: the throttle and the three surfaces."""
        return 1 + len(FIXEDWING_CONTROLS)

    @property
    def rotor_count(self) -> int:
        """Motors (PX4's CA_ROTOR_COUNT): the one propeller."""
        return 1


def available_vehicles() -> list[str]:
    """Names of the vehicle files shipped in ``stack/airframe/vehicles``."""
    return sorted(p.stem for p in VEHICLES_DIR.glob("*.toml"))


def vehicle_path(name_or_path: str | Path) -> Path:
    """The file of a vehicle name in ``stack/airframe/vehicles``, or the path given."""
    text = str(name_or_path)
    if isinstance(name_or_path, Path) or text.endswith(".toml") or "/" in text or "\\" in text:
        return Path(name_or_path)
    path = VEHICLES_DIR / f"{text}.toml"
    if not path.is_file():
        raise ValueError(f"unknown vehicle {text!r}; available: {', '.join(available_vehicles())}")
    return path


def read_vehicle_file(path: Path) -> dict[str, Any]:
    try:
        with path.open("rb") as f:
            return tomllib.load(f)
    except tomllib.TOMLDecodeError as exc:
        raise ValueError(f"{path.name}: invalid TOML: {exc}") from None
    except OSError as exc:
        raise ValueError(f"{path}: {exc.strerror}") from None


def load_vehicle(name_or_path: str | Path) -> VehicleModel | FixedwingModel | JsbsimAircraft:
    """Load a vehicle by name (``"sih_quad"``, ``"sih_plane"``, ``"jsbsim_c172"``) or by path to a TOML file.

    Raises ``ValueError`` naming the file, the key and the problem when the file is malformed,
    incomplete or inconsistent (e.g. ``"hummingbird.toml: rotor[2].position: expected 3 numbers"``).
    """
    path = vehicle_path(name_or_path)
    data = read_vehicle_file(path)
    kind = data.get("type", "multicopter")
    if kind == "fixedwing":
        return _Parser(path).fixedwing(data)
    if kind == "jsbsim":
        from stack.airframe.jsbsim import JsbsimParser

        return JsbsimParser(path).aircraft(data)
    if kind != "multicopter":
        raise ValueError(f"{path.name}: type: {kind!r} is not a vehicle type this loader reads "
                         f"(expected one of {', '.join(VEHICLE_TYPES)})")
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

    def flag(self, data: Mapping[str, Any], key: str, where: str, default: bool) -> bool:
        value = data.get(key, default)
        if not isinstance(value, bool):
            raise self.error(where, "expected true or false")
        return value

    def entries(self, data: Mapping[str, Any], key: str) -> list[Mapping[str, Any]]:
        entries = data.get(key)
        if not isinstance(entries, list) or not all(isinstance(e, dict) for e in entries):
            raise self.error(key, f"expected an array of tables ([[{key}]])")
        return entries

    def vehicle(self, data: Mapping[str, Any]) -> VehicleModel:
        allowed = {"type", "name", "description", "mass", "inertia", "motor", "drag", "rotor", "airframe"}
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

    def fixedwing(self, data: Mapping[str, Any]) -> FixedwingModel:
        allowed = {"type", "name", "description", "mass", "inertia", "inertia_xz", "max_deflection", "thruster",
                   "drag", "segment", "ground", "contact", "airframe"}
        for k in data:
            if k not in allowed:
                raise self.error(k, "unknown key")
        if "inertia" not in data:
            raise self.error("inertia", "missing")
        inertia = self.vector(data["inertia"], "inertia")
        if min(inertia) <= 0.0:
            raise self.error("inertia", "every diagonal element must be > 0")
        inertia_xz = self.number(data, "inertia_xz", "inertia_xz", default=0.0)
        if inertia_xz * inertia_xz >= inertia[0] * inertia[2]:
            raise self.error("inertia_xz", "makes the inertia tensor singular or not positive definite")
        max_deflection = self.number(data, "max_deflection", "max_deflection", positive=True)
        if max_deflection > 70.0:
            raise self.error("max_deflection", "the flap model holds up to 70 degrees")
        thruster = self.thruster(data)
        model = FixedwingModel(
            name=self.string(data, "name", "name"),
            description=self.string(data, "description", "description"),
            mass=self.number(data, "mass", "mass", positive=True),
            inertia=inertia,
            inertia_xz=inertia_xz,
            thruster=thruster,
            segments=self.segments(data),
            max_deflection=math.radians(max_deflection),
            drag=self.drag(data),
            contacts=self.contacts(data),
            ground=self.ground(data),
            airframe=MappingProxyType({}),
            path=str(self.path),
        )
        return replace(model, airframe=self.fixedwing_airframe(data))

    def thruster(self, data: Mapping[str, Any]) -> Thruster:
        propeller_keys = ("diameter", "max_rpm", "thrust_coefficients")
        table = self.table(data, "thruster", {"max_thrust", "time_constant", "prop_radius", *propeller_keys})
        time_constant = self.number(table, "time_constant", "thruster.time_constant", positive=True)
        prop_radius = self.number(table, "prop_radius", "thruster.prop_radius", positive=True)
        given = [k for k in propeller_keys if k in table]
        if not given:
            max_thrust = self.number(table, "max_thrust", "thruster.max_thrust", positive=True)
            return Thruster(max_thrust, time_constant, prop_radius, None)
        if "max_thrust" in table:
            raise self.error("thruster.max_thrust", "either max_thrust or a propeller (diameter, max_rpm, "
                                                    "thrust_coefficients), not both")
        for k in propeller_keys:
            if k not in table:
                raise self.error(f"thruster.{k}", "missing (a propeller needs diameter, max_rpm and "
                                                  "thrust_coefficients)")
        coefficients = self.vector(table["thrust_coefficients"], "thruster.thrust_coefficients")
        if coefficients[0] <= 0.0:
            raise self.error("thruster.thrust_coefficients", "the static coefficient (the first) must be > 0")
        propeller = Propeller(
            diameter=self.number(table, "diameter", "thruster.diameter", positive=True),
            max_rpm=self.number(table, "max_rpm", "thruster.max_rpm", positive=True),
            thrust_coefficients=coefficients,
        )
        static = propeller_thrust(1.0, 0.0, AIR_DENSITY_SEA_LEVEL, propeller.diameter, propeller.max_rpm,
                                  coefficients)
        return Thruster(static, time_constant, prop_radius, propeller)

    def segments(self, data: Mapping[str, Any]) -> tuple[AeroSurfaceSegment, ...]:
        keys = {"name", "span", "chord", "position", "incidence", "dihedral", "aspect_ratio", "flap_chord",
                "control", "direction", "slipstream", "lift_slope", "stall_angle"}
        segments = []
        for i, entry in enumerate(self.entries(data, "segment")):
            where = f"segment[{i}]"
            for k in entry:
                if k not in keys:
                    raise self.error(f"{where}.{k}", "unknown key")
            span = self.number(entry, "span", f"{where}.span", positive=True)
            chord = self.number(entry, "chord", f"{where}.chord", positive=True)
            if "position" not in entry:
                raise self.error(f"{where}.position", "missing")
            flap_chord = self.number(entry, "flap_chord", f"{where}.flap_chord", minimum=0.0, default=0.0)
            if flap_chord > chord:
                raise self.error(f"{where}.flap_chord", f"is longer than the chord {chord}")
            control = entry.get("control")
            if control is not None and control not in FIXEDWING_CONTROLS:
                raise self.error(f"{where}.control", f"expected one of {', '.join(FIXEDWING_CONTROLS)}")
            if control is not None and flap_chord == 0.0:
                raise self.error(f"{where}.control", "needs a flap_chord > 0")
            direction = entry.get("direction", 1)
            if direction not in (1, -1) or isinstance(direction, bool):
                raise self.error(f"{where}.direction", "expected 1 or -1")
            if "direction" in entry and control is None:
                raise self.error(f"{where}.direction", "only with a control")
            stall = self.number(entry, "stall_angle", f"{where}.stall_angle", positive=True, default=math.nan)
            if stall > 90.0:
                raise self.error(f"{where}.stall_angle", "expected at most 90 degrees")
            segments.append(AeroSurfaceSegment(
                name=self.string(entry, "name", f"{where}.name"),
                span=span,
                chord=chord,
                position=self.vector(entry["position"], f"{where}.position"),
                alpha_0=-math.radians(self.number(entry, "incidence", f"{where}.incidence", default=0.0)),
                dihedral=math.radians(self.number(entry, "dihedral", f"{where}.dihedral", default=0.0)),
                aspect_ratio=self.number(entry, "aspect_ratio", f"{where}.aspect_ratio", positive=True,
                                         default=span / chord),
                flap_chord=flap_chord,
                control=control,
                direction=direction,
                slipstream=self.flag(entry, "slipstream", f"{where}.slipstream", False),
                lift_slope=self.number(entry, "lift_slope", f"{where}.lift_slope", positive=True,
                                       default=2.0 * math.pi),
                stall_angle=None if math.isnan(stall) else math.radians(stall),
            ))
        if not segments:
            raise self.error("segment", "a fixed-wing needs at least one segment")
        for control in FIXEDWING_CONTROLS:
            if not any(s.control == control for s in segments):
                raise self.error("segment", f"no segment is moved by the {control}")
        return tuple(segments)

    def ground(self, data: Mapping[str, Any]) -> GroundModel:
        names = ("rolling_friction", "side_friction", "brake_friction", "skid_friction", "tread_stiffness",
                 "tread_damping", "rolling_speed", "max_steering", "brake_throttle")
        table = self.table(data, "ground", set(names))
        values = {k: self.number(table, k, f"ground.{k}", minimum=0.0) for k in names}
        for k in ("tread_stiffness", "rolling_speed"):
            if values[k] <= 0.0:
                raise self.error(f"ground.{k}", f"must be > 0, got {values[k]}")
        if values["max_steering"] >= 90.0:
            raise self.error("ground.max_steering", "expected less than 90 degrees")
        values["max_steering"] = math.radians(values["max_steering"])
        return GroundModel(**values)

    def contacts(self, data: Mapping[str, Any]) -> tuple[GroundContact, ...]:
        keys = {"name", "position", "stiffness", "damping", "wheel", "steering", "brake"}
        contacts = []
        for i, entry in enumerate(self.entries(data, "contact")):
            where = f"contact[{i}]"
            for k in entry:
                if k not in keys:
                    raise self.error(f"{where}.{k}", "unknown key")
            if "position" not in entry:
                raise self.error(f"{where}.position", "missing")
            wheel = self.flag(entry, "wheel", f"{where}.wheel", True)
            steering = self.flag(entry, "steering", f"{where}.steering", False)
            brake = self.flag(entry, "brake", f"{where}.brake", False)
            if not wheel and (steering or brake):
                raise self.error(f"{where}.{'steering' if steering else 'brake'}", "only for a wheel")
            contacts.append(GroundContact(
                name=self.string(entry, "name", f"{where}.name"),
                position=self.vector(entry["position"], f"{where}.position"),
                stiffness=self.number(entry, "stiffness", f"{where}.stiffness", positive=True),
                damping=self.number(entry, "damping", f"{where}.damping", minimum=0.0),
                wheel=wheel,
                steering=steering,
                brake=brake,
            ))
        if sum(c.wheel for c in contacts) < 3:
            raise self.error("contact", "the plane needs at least 3 wheels to stand on")
        return tuple(contacts)

    def parameters(self, data: Mapping[str, Any]) -> dict[str, float]:
        table = data.get("airframe")
        if not isinstance(table, dict):
            raise self.error("airframe", "expected a table")
        params: dict[str, float] = {}
        for key, value in table.items():
            where = f"airframe.{key}"
            if not _PARAM_NAME.match(key):
                raise self.error(where, "expected an upper-case PX4 parameter name")
            if isinstance(value, bool) or not isinstance(value, int | float) or not math.isfinite(value):
                raise self.error(where, "expected a finite number")
            params[key] = value
        return params

    def fixedwing_airframe(self, data: Mapping[str, Any]) -> Mapping[str, float]:
        params = self.parameters(data)
        for key, expected in (("CA_AIRFRAME", CA_AIRFRAME_FIXEDWING), ("CA_ROTOR_COUNT", 1)):
            if key not in params:
                raise self.error(f"airframe.{key}", "missing")
            if params[key] != expected:
                raise self.error(f"airframe.{key}", f"is {params[key]}, the fixed-wing model needs {expected}")
        for key in params:
            match = _ROTOR_PARAM.match(key)
            if match and int(match.group(1)) >= 1:
                raise self.error(f"airframe.{key}", "rotor index out of range (the vehicle has 1 rotor)")
        return MappingProxyType(params)

    def drag(self, data: Mapping[str, Any]) -> BodyDrag:
        table = self.table(data, "drag", {"linear", "quadratic", "angular"})
        return BodyDrag(
            linear=self.number(table, "linear", "drag.linear", minimum=0.0),
            quadratic=self.number(table, "quadratic", "drag.quadratic", minimum=0.0),
            angular=self.number(table, "angular", "drag.angular", minimum=0.0),
        )

    def rotors(self, data: Mapping[str, Any]) -> tuple[Rotor, ...]:
        entries = self.entries(data, "rotor")
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
        params = self.parameters(data)
        n = model.rotor_count
        for key in params:
            match = _ROTOR_PARAM.match(key)
            if match and int(match.group(1)) >= n:
                raise self.error(f"airframe.{key}", f"rotor index out of range (the vehicle has {n} rotors)")

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
