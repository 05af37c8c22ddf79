"""Geometry (PX4 ``src/modules/control_allocator/module.yaml``): the rotors' positions, axes, thrust and
moment coefficients, and each motor's slew limit."""

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
PARAMS: tuple[Param, ...] = ROTOR_PARAMS + SLEW_PARAMS
