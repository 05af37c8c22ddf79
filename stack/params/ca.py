"""Geometry (PX4 ``src/modules/control_allocator/module.yaml``): the airframe, the rotors' positions, axes, thrust
and moment coefficients, each motor's slew limit, and a plane's control surfaces."""

from stack.params.param import Param

MAX_ROTORS = 12
"""PX4 ``NUM_ROTORS_MAX``: CA_ROTOR0_* … CA_ROTOR11_*."""


def _rotor(i: int) -> tuple[Param, ...]:
    return (
        Param(f"CA_ROTOR{i}_PX", 0.0, -100.0, 100.0, "m", f"Rotor {i} position x (forward)"),
        Param(f"CA_ROTOR{i}_PY", 0.0, -100.0, 100.0, "m", f"Rotor {i} position y (right)"),
        Param(f"CA_ROTOR{i}_PZ", 0.0, -100.0, 100.0, "m", f"Rotor {i} position z (down)"),
        Param(f"CA_ROTOR{i}_AX", 0.0, -100.0, 100.0, "", f"Rotor {i} thrust axis x"),
        Param(f"CA_ROTOR{i}_AY", 0.0, -100.0, 100.0, "", f"Rotor {i} thrust axis y"),
        Param(f"CA_ROTOR{i}_AZ", -1.0, -100.0, 100.0, "", f"Rotor {i} thrust axis z (−1 = thrust up)"),
        Param(f"CA_ROTOR{i}_CT", 6.5, 0.0, 100.0, "N", f"Rotor {i} thrust at full command"),
        Param(f"CA_ROTOR{i}_KM", 0.05, -1.0, 1.0, "m", f"Rotor {i} moment ratio (+ counter-clockwise)"),
    )


ROTOR_PARAMS: tuple[Param, ...] = (
    Param("CA_ROTOR_COUNT", 0, 0, MAX_ROTORS, "", "Number of rotors"),
    *(p for i in range(MAX_ROTORS) for p in _rotor(i)),
)
SLEW_PARAMS: tuple[Param, ...] = tuple(
    Param(f"CA_R{i}_SLEW", 0.0, 0.0, 10.0, "s", f"Motor {i}: minimum time to cross the full range (0 = off)")
    for i in range(MAX_ROTORS)
)
AIRFRAME_MULTIROTOR = 0
AIRFRAME_FIXED_WING = 1
AIRFRAME_PARAMS: tuple[Param, ...] = (
    Param("CA_AIRFRAME", AIRFRAME_MULTIROTOR, doc="Airframe: which actuators the allocator drives",
          values={AIRFRAME_MULTIROTOR: "Multirotor", AIRFRAME_FIXED_WING: "Fixed Wing"}),
)

MAX_SURFACES = 8
"""PX4 ``ActuatorEffectivenessControlSurfaces::MAX_COUNT``: CA_SV_CS0_* … CA_SV_CS7_*."""
SURFACE_TYPES: dict[int, str] = {
    0: "(Not set)", 1: "Left Aileron", 2: "Right Aileron", 3: "Elevator", 4: "Rudder", 5: "Left Elevon",
    6: "Right Elevon", 7: "Left V-Tail", 8: "Right V-Tail", 9: "Left Flap", 10: "Right Flap", 11: "Airbrake",
    12: "Custom", 13: "Left A-tail", 14: "Right A-tail", 15: "Single Channel Aileron", 16: "Steering Wheel",
    17: "Left Spoiler", 18: "Right Spoiler",
}
SURFACE_TYPES_WITHOUT_TORQUE = frozenset({9, 10, 11, 16, 17, 18})
"""Flaps, airbrakes, the steering wheel and spoilers: PX4 zeroes their torque whatever CA_SV_CS<n>_TRQ_* say."""
# The SIH airplane's surfaces (airframe 10041_sihsim_airplane): aileron (one channel), elevator, rudder.
_DEFAULT_SURFACES: dict[int, tuple[int, tuple[float, float, float]]] = {
    0: (15, (1.0, 0.0, 0.0)),
    1: (3, (0.0, 1.0, 0.0)),
    2: (4, (0.0, 0.0, 1.0)),
}


def _surface(i: int) -> tuple[Param, ...]:
    kind, (roll, pitch, yaw) = _DEFAULT_SURFACES.get(i, (0, (0.0, 0.0, 0.0)))
    return (
        Param(f"CA_SV_CS{i}_TYPE", kind, doc=f"Control surface {i} type", values=SURFACE_TYPES),
        Param(f"CA_SV_CS{i}_TRQ_R", roll, -1.0, 1.0, "", f"Control surface {i}: roll torque at full deflection"),
        Param(f"CA_SV_CS{i}_TRQ_P", pitch, -1.0, 1.0, "", f"Control surface {i}: pitch torque at full deflection"),
        Param(f"CA_SV_CS{i}_TRQ_Y", yaw, -1.0, 1.0, "", f"Control surface {i}: yaw torque at full deflection"),
    )


SURFACE_PARAMS: tuple[Param, ...] = (
    Param("CA_SV_CS_COUNT", len(_DEFAULT_SURFACES), 0, MAX_SURFACES, "", "Number of control surfaces (fixed wing)"),
    *(p for i in range(MAX_SURFACES) for p in _surface(i)),
)
PARAMS: tuple[Param, ...] = ROTOR_PARAMS + SLEW_PARAMS + AIRFRAME_PARAMS + SURFACE_PARAMS
