"""RotorS' roll-pitch-yawrate-thrust controller: its attitude law and rotor allocation, with no I/O.

ethz-asl/rotors_simulator, ``rotors_control/src/library/roll_pitch_yawrate_thrust_controller.cpp`` with
``calculateAllocationMatrix`` and ``vectorFromSkewMatrix`` of ``rotors_control/include/rotors_control/common.h``
(after Lee, Leok and McClamroch's geometric controller on SE(3)), all in RotorS' frames, body FLU and world ENU:

    R_d = Rz(ψ)·Rx(roll)·Ry(pitch)        ψ = atan2(R₁₀, R₀₀), the current heading
    e_R = ½·vee(R_dᵀR − RᵀR_d)             e_ω = ω − R_dᵀR·(0, 0, yaw_rate)
    α = −(K_R/I)∘e_R − (K_ω/I)∘e_ω         (RotorS adds ω×ω, which is zero)
    ω_i² = [A⁺·diag(I, 1)·(α; T)]_i        ω_i = √max(0, ·)

A⁺ = Aᵀ(AAᵀ)⁻¹, and A has one column per rotor at arm angle γ, arm length l, spin direction dir (+1
counter-clockwise seen from above): (sinγ·l·k_f, −cosγ·l·k_f, −dir·k_f·k_m, k_f). The gains K_R and K_ω are
torques per unit error (``roll_pitch_yawrate_thrust_controller_<mav>.yaml``, RPYT_* here). There is no integrator.

Frames. The class takes and gives the stack's frames and converts at its edges: R_ENU←FLU = P·R_NED←FRD·F with
F = diag(1, −1, −1) and P the NED ↔ ENU swap, ω_FLU = F·ω_FRD, and a hub at (x, y) FRD sits at γ = atan2(−y, x).
So a command's roll is RotorS' roll while its pitch and yaw rate (the stack's: + nose up, + clockwise from
above) are the negatives of RotorS', and the heading ψ_ENU = π/2 − ψ_NED that R_d keeps is RotorS' own.

Units. A rotor's thrust is k_f·ω², at most k_f·ω_max² (the vehicle's ``max_thrust``, PX4's CA_ROTORi_CT). A is
built with k_f·ω_max² in place of k_f, which solves for ω²/ω_max² (A⁺ scales by 1/ω_max², nothing else
changes): each rotor's fraction of its full thrust, which the vehicle's motor model turns into the motor command,
u = ω/ω_max for RotorS' motors (``gazebo_motor_model``: ω = u·ω_max), clipped to [0, 1].

The stack's extension: a body-rate command (Acro, or a rate setpoint from Offboard) runs the same law with
e_R = 0 and e_ω = ω − ω_sp, so every mode flies through one allocation.
"""

from __future__ import annotations

import math
from collections.abc import Mapping

import numpy as np

from stack.airframe.model import VehicleModel
from stack.attctl.rotors_joy import RollPitchYawrateThrust
from stack.mathlib import quaternion as quat
from stack.mathlib.quaternion import Mat3, Quat
from stack.mathlib.vector import Vec3
from stack.params.binding import ParamSet
from stack.params.param import Param


class RpytParams(ParamSet):
    """The attitude and rate gains per axis (the catalogue's RPYT_*)."""

    rpyt_att_gain_x: float
    rpyt_att_gain_y: float
    rpyt_att_gain_z: float
    rpyt_rate_gain_x: float
    rpyt_rate_gain_y: float
    rpyt_rate_gain_z: float


PARAMS: tuple[Param, ...] = RpytParams.PARAMS

RANK_THRESHOLD = 1e-9
"""Pivots below this do not count toward the allocation's rank (RotorS' ``lu.setThreshold``)."""


def zxy(yaw: float, roll: float, pitch: float) -> Mat3:
    """Rz(yaw)·Rx(roll)·Ry(pitch), rows."""
    cy, sy = math.cos(yaw), math.sin(yaw)
    cr, sr = math.cos(roll), math.sin(roll)
    cp, sp = math.cos(pitch), math.sin(pitch)
    return (
        (cy * cp - sy * sr * sp, -sy * cr, cy * sp + sy * sr * cp),
        (sy * cp + cy * sr * sp, cy * cr, sy * sp - cy * sr * cp),
        (-cr * sp, sr, cr * cp),
    )


def zxy_angles(r: Mat3) -> Vec3:
    """(yaw, roll, pitch) with ``zxy(yaw, roll, pitch) == r``, roll in [−π/2, π/2]."""
    roll = math.asin(min(max(r[2][1], -1.0), 1.0))
    return math.atan2(-r[0][1], r[1][1]), roll, math.atan2(-r[2][0], r[2][2])


def _enu_flu(q: Quat) -> Mat3:
    """R_ENU←FLU = P·R_NED←FRD·F for the stack's attitude quaternion."""
    (r00, r01, r02), (r10, r11, r12), (r20, r21, r22) = quat.to_dcm(q)
    return (r10, -r11, -r12), (r00, -r01, -r02), (-r20, r21, r22)


def _flu(v: Vec3) -> Vec3:
    """A body vector FRD ↔ FLU (F is its own inverse)."""
    return v[0], -v[1], -v[2]


def allocation_matrix(vehicle: VehicleModel) -> np.ndarray:
    """RotorS' allocation matrix A (4 × N: roll, pitch and yaw torque about FLU, thrust) with k_f·ω_max² for k_f.

    Raises ValueError when its rank is below 4 (RotorS only warns: such a vehicle cannot be controlled)."""
    k_f = vehicle.motor.max_thrust
    k_m = vehicle.motor.moment_ratio
    columns = []
    for rotor in vehicle.rotors:
        x, y_frd = rotor.position[0], rotor.position[1]
        angle, arm = math.atan2(-y_frd, x), math.hypot(x, y_frd)
        columns.append((math.sin(angle) * arm * k_f, -math.cos(angle) * arm * k_f, -rotor.spin * k_f * k_m, k_f))
    a = np.array(columns, dtype=float).T
    rank = int(np.linalg.matrix_rank(a, tol=RANK_THRESHOLD))
    if rank < 4:
        raise ValueError(f"{vehicle.name}: the rotor allocation has rank {rank}, not 4: it cannot be controlled")
    return a


class RollPitchYawrateThrustControl:
    """RotorS' controller for one vehicle: a command in, one motor command per rotor out (see the module docstring).

    Until the first command every rotor is stopped, as in RotorS. A command with a non-finite value is refused and
    the last good one kept.
    """

    __slots__ = ("_acc_to_fraction", "_attitude_gain", "_command", "_inertia", "_motor", "_rate_gain", "_rates",
                 "max_thrust", "num_rotors")

    def __init__(self, vehicle: VehicleModel, params: Mapping[str, object] | None = None) -> None:
        a = allocation_matrix(vehicle)
        inertia = np.diag([*vehicle.inertia, 1.0])
        self._acc_to_fraction = tuple(tuple(row) for row in (a.T @ np.linalg.inv(a @ a.T) @ inertia).tolist())
        self._inertia = vehicle.inertia
        self._motor = vehicle.motor
        self.num_rotors = vehicle.rotor_count
        self.max_thrust = vehicle.rotor_count * vehicle.motor.max_thrust
        """Collective thrust at full command [N]: what a normalised thrust of 1 means."""
        self._command: RollPitchYawrateThrust | None = None
        self._rates: Vec3 | None = None
        self.set_params(params or {})

    def set_params(self, params: Mapping[str, object]) -> None:
        p = RpytParams.from_params(params)
        self._attitude_gain = (p.rpyt_att_gain_x, p.rpyt_att_gain_y, p.rpyt_att_gain_z)
        self._rate_gain = (p.rpyt_rate_gain_x, p.rpyt_rate_gain_y, p.rpyt_rate_gain_z)

    @property
    def thrust(self) -> float:
        """The commanded collective thrust [N] (0 before the first command)."""
        return self._command.thrust if self._command is not None else 0.0

    def reset(self) -> None:
        """Forget the command: the rotors stop until the next one (on disarming)."""
        self._command = None
        self._rates = None

    def set_command(self, command: RollPitchYawrateThrust) -> bool:
        """Follow a roll, pitch, yaw rate and thrust command (the stack's frames); False if refused."""
        if not all(math.isfinite(v) for v in command):
            return False
        self._command = RollPitchYawrateThrust(command.roll, -command.pitch, -command.yaw_rate, command.thrust)
        self._rates = None
        return True

    def set_rates_command(self, rates: Vec3, thrust: float) -> bool:
        """Follow body rates [rad/s, FRD; NaN holds that axis' rate] and a thrust [N]; False if refused."""
        if any(math.isinf(v) for v in rates) or not math.isfinite(thrust):
            return False
        self._command = RollPitchYawrateThrust(0.0, 0.0, 0.0, thrust)
        self._rates = _flu(rates)
        return True

    def errors(self, q: Quat, rates: Vec3) -> tuple[Vec3, Vec3]:
        """(e_R, e_ω) of the current command for attitude ``q`` and body rates ``rates`` (FRD), in body FRD."""
        e_r, e_w = self._errors(q, _flu(rates))
        return _flu(e_r), _flu(e_w)

    def motors(self, q: Quat, rates: Vec3) -> tuple[float, ...]:
        """Motor commands in [0, 1] for attitude ``q`` and body rates ``rates`` [rad/s, FRD].

        A state that is not finite (no estimate) leaves only the thrust: no torque from errors it cannot measure."""
        command = self._command
        if command is None:
            return (0.0,) * self.num_rotors
        w = _flu(rates)
        e_r, e_w = self._errors(q, w)
        if not all(math.isfinite(v) for v in (*e_r, *e_w)):
            e_r = e_w = (0.0, 0.0, 0.0)
        kr, kw, inertia = self._attitude_gain, self._rate_gain, self._inertia
        ax, ay, az = (-kr[i] / inertia[i] * e_r[i] - kw[i] / inertia[i] * e_w[i] for i in range(3))
        return self._allocate((ax, ay, az), command.thrust)

    def allocate(self, angular_acceleration: Vec3, thrust: float) -> tuple[float, ...]:
        """Motor commands for an angular acceleration [rad/s², body FRD] and a collective thrust [N]."""
        return self._allocate(_flu(angular_acceleration), thrust)

    def _errors(self, q: Quat, w: Vec3) -> tuple[Vec3, Vec3]:
        command = self._command
        if command is None:
            return (0.0, 0.0, 0.0), (0.0, 0.0, 0.0)
        if self._rates is not None:
            px, py, pz = (w[i] - sp if sp == sp else 0.0 for i, sp in enumerate(self._rates))
            return (0.0, 0.0, 0.0), (px, py, pz)
        r = _enu_flu(quat.normalized(q))
        rd = zxy(math.atan2(r[1][0], r[0][0]), command.roll, command.pitch)
        m = [[rd[0][i] * r[0][j] + rd[1][i] * r[1][j] + rd[2][i] * r[2][j] for j in range(3)] for i in range(3)]
        e_r = (0.5 * (m[2][1] - m[1][2]), 0.5 * (m[0][2] - m[2][0]), 0.5 * (m[1][0] - m[0][1]))
        yaw_rate = command.yaw_rate
        e_w = (w[0] - m[0][2] * yaw_rate, w[1] - m[1][2] * yaw_rate, w[2] - m[2][2] * yaw_rate)
        return e_r, e_w

    def _allocate(self, alpha: Vec3, thrust: float) -> tuple[float, ...]:
        demand = (alpha[0], alpha[1], alpha[2], thrust)
        command_for = self._motor.command_for_thrust_fraction
        motors = []
        for row in self._acc_to_fraction:
            fraction = row[0] * demand[0] + row[1] * demand[1] + row[2] * demand[2] + row[3] * demand[3]
            motors.append(min(command_for(fraction), 1.0) if fraction > 0.0 else 0.0)
        return tuple(motors)
