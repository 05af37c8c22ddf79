"""6-DOF rigid-body multicopter plant: motors, rotor aerodynamics, drag, gravity and ground contact.

The model combines PX4 SIH (``simulator_sih``: linear thrust, linear drag and angular damping, rate
clamp, ground handling) and RotorS (``gazebo_motor_model``: asymmetric first-order rotor-speed lag,
quadratic thrust, reaction moment k_M·thrust, rotor H-force and rolling moment on the air velocity
at each hub). Which terms are active follows from the :class:`~stack.airframe.model.VehicleModel`.

Frames and units follow PX4: position and velocity NED (m, m/s) about the home point, attitude a
Hamilton quaternion rotating body FRD to NED, body rates FRD (rad/s). The ground is the plane
NED z = 0 (the home altitude).

One :meth:`MulticopterPhysics.step` of length dt:

1. Each motor state s_i ∈ [0, 1] (normalised rotor speed for the quadratic model, normalised thrust
   for the linear one) follows its command through a first-order lag discretised exactly:
   s ← c + (s − c)·exp(−dt/τ), with τ = ``time_constant_up`` when c > s, else ``time_constant_down``.
2. The motor states are held over the step and the rigid body is advanced by classic RK4 with
   - per-rotor thrust T_i = CT·f(s_i) along body −z, f(s) = s or s², and yaw moment spin_i·KM·T_i;
   - rotor H-force −k_D·ω_i·P(v_hub) and rolling moment −k_R·ω_i·P(v_hub), where v_hub is the
     air-relative velocity at the hub (v − wind + ω × p_i, in body) and P removes the axial part;
   - body drag −(k_lin + k_quad·|v_air|)·v_air, angular damping −k_ang·ω, gravity, and −ω × Iω.
3. Body rates are clamped (SIH: ±6π rad/s), the quaternion is renormalised, and ground contact
   is resolved.

Ground contact: the vehicle rests on the ground (velocity zero, horizontal position held by static
friction) as long as the free motion would take it below z = 0; it lifts off as soon as the net force
points up. A touchdown at any speed stops it in the step where it reaches the ground, without
penetration or bounce (SIH's "full stop" for multicopters). A vehicle that touches down tilted (in
wind, say) tips onto its legs, turning level about its heading at up to GROUND_TIP_RATE: the body
rates of that rotation are real, so the gyro measures it and an attitude estimate follows it.

The sums over rotors that the aerodynamic terms need are formed once per step (they depend only on
the held motor states), so each RK4 stage costs the same for 4 or 6 rotors.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

from stack.airframe.model import VehicleModel
from stack.mathlib.quaternion import (
    IDENTITY,
    Quat,
    conj,
    from_rotation_vector,
    mul,
    normalized,
    to_rotation_vector,
)
from stack.mathlib.scalar import CONSTANTS_ONE_G
from stack.mathlib.vector import ZERO3, Vec3
from stack.sim.rigid_body import RigidBodyState

SIH_MAX_BODY_RATE = 6.0 * math.pi
GROUND_TIP_RATE = 3.0  # rad/s: how fast a vehicle resting tilted on the ground tips onto its legs


def _derivative_basic(
    vx: float, vy: float, vz: float, qw: float, qx: float, qy: float, qz: float,
    wx: float, wy: float, wz: float, held: tuple, const: tuple,
) -> tuple[float, float, float, float, float, float, float, float, float, float]:
    """State derivative without rotor aerodynamics: (v̇ NED, q̇, ω̇ body)."""
    thrust_acc, mx, my, mz, wind_n, wind_e, wind_d = held
    g, lin_m, quad_m, k_ang, ixx_inv, iyy_inv, izz_inv, izz_iyy, ixx_izz, iyy_ixx = const
    an = vx - wind_n
    ae = vy - wind_e
    ad = vz - wind_d
    drag = lin_m + quad_m * math.sqrt(an * an + ae * ae + ad * ad) if quad_m else lin_m
    return (
        -thrust_acc * 2.0 * (qw * qy + qx * qz) - drag * an,
        -thrust_acc * 2.0 * (qy * qz - qw * qx) - drag * ae,
        g - thrust_acc * (qw * qw - qx * qx - qy * qy + qz * qz) - drag * ad,
        -0.5 * (qx * wx + qy * wy + qz * wz),
        0.5 * (qw * wx + qy * wz - qz * wy),
        0.5 * (qw * wy - qx * wz + qz * wx),
        0.5 * (qw * wz + qx * wy - qy * wx),
        (mx - k_ang * wx - izz_iyy * wy * wz) * ixx_inv,
        (my - k_ang * wy - ixx_izz * wz * wx) * iyy_inv,
        (mz - k_ang * wz - iyy_ixx * wx * wy) * izz_inv,
    )


def _derivative_rotor_drag(
    vx: float, vy: float, vz: float, qw: float, qx: float, qy: float, qz: float,
    wx: float, wy: float, wz: float, held: tuple, const: tuple,
) -> tuple[float, float, float, float, float, float, float, float, float, float]:
    """State derivative including the rotor H-force and rolling moment (RotorS)."""
    (thrust, mx, my, mz, wind_n, wind_e, wind_d,
     s, spx, spy, spz, ka, kb, kc, kd) = held
    (g, inv_m, lin_m, quad_m, k_ang, ixx_inv, iyy_inv, izz_inv, izz_iyy, ixx_izz, iyy_ixx,
     k_drag, k_roll) = const
    an = vx - wind_n
    ae = vy - wind_e
    ad = vz - wind_d
    # Rotation matrix body → NED (columns are the body axes in NED).
    ww, xx, yy, zz = qw * qw, qx * qx, qy * qy, qz * qz
    r00 = ww + xx - yy - zz
    r01 = 2.0 * (qx * qy - qw * qz)
    r02 = 2.0 * (qw * qy + qx * qz)
    r10 = 2.0 * (qx * qy + qw * qz)
    r11 = ww - xx + yy - zz
    r12 = 2.0 * (qy * qz - qw * qx)
    r20 = 2.0 * (qx * qz - qw * qy)
    r21 = 2.0 * (qw * qx + qy * qz)
    r22 = ww - xx - yy + zz
    # Air velocity in body, only its rotor-plane part matters.
    ubx = r00 * an + r10 * ae + r20 * ad
    uby = r01 * an + r11 * ae + r21 * ad
    # Σ ω_i·P(u + ω × p_i) = P(S·u + ω × Σ ω_i p_i)
    hx = s * ubx + wy * spz - wz * spy
    hy = s * uby + wz * spx - wx * spz
    fx = -k_drag * hx
    fy = -k_drag * hy
    # Σ p_i × F_i = −k_D·(Σω_i p_i × P u + K·ω), K from the per-step sums ka..kd.
    tx = mx - k_drag * (-spz * uby + ka * wx - kb * wz) - k_roll * hx
    ty = my - k_drag * (spz * ubx + ka * wy - kc * wz) - k_roll * hy
    tz = mz - k_drag * (spx * uby - spy * ubx + kd * wz - kb * wx - kc * wy)
    fz = -thrust
    drag = lin_m + quad_m * math.sqrt(an * an + ae * ae + ad * ad) if quad_m else lin_m
    return (
        (r00 * fx + r01 * fy + r02 * fz) * inv_m - drag * an,
        (r10 * fx + r11 * fy + r12 * fz) * inv_m - drag * ae,
        g + (r20 * fx + r21 * fy + r22 * fz) * inv_m - drag * ad,
        -0.5 * (qx * wx + qy * wy + qz * wz),
        0.5 * (qw * wx + qy * wz - qz * wy),
        0.5 * (qw * wy - qx * wz + qz * wx),
        0.5 * (qw * wz + qx * wy - qy * wx),
        (tx - k_ang * wx - izz_iyy * wy * wz) * ixx_inv,
        (ty - k_ang * wy - ixx_izz * wz * wx) * iyy_inv,
        (tz - k_ang * wz - iyy_ixx * wx * wy) * izz_inv,
    )


class MulticopterPhysics(RigidBodyState):
    """The rigid-body plant of one multicopter (see the module docstring for the model).

    ``max_body_rate`` (rad/s, default 6π as SIH) clamps each body-rate component; ``gravity`` in m/s².
    Motor commands are in [0, 1] in the vehicle's rotor order; NaN or negative means stopped.
    """

    __slots__ = (
        "_alpha_down",
        "_alpha_dt",
        "_alpha_up",
        "_angular_velocity",
        "_attitude",
        "_const",
        "_derivative",
        "_gravity",
        "_inv_mass",
        "_last_dt",
        "_max_rate",
        "_max_rotor_speed",
        "_max_thrust",
        "_motor_states",
        "_on_ground",
        "_position",
        "_previous_angular_velocity",
        "_previous_velocity",
        "_quadratic",
        "_rotor_drag",
        "_rotor_terms",
        "_velocity",
        "model",
    )

    def __init__(
        self, model: VehicleModel, max_body_rate: float = SIH_MAX_BODY_RATE, gravity: float = CONSTANTS_ONE_G
    ) -> None:
        if max_body_rate <= 0.0:
            raise ValueError("max_body_rate must be > 0")
        self.model = model
        self._max_rate = max_body_rate
        self._gravity = gravity
        self._inv_mass = 1.0 / model.mass
        motor = model.motor
        ixx, iyy, izz = model.inertia
        self._quadratic = motor.thrust_model == "quadratic"
        self._max_thrust = motor.max_thrust
        self._rotor_drag = motor.rotor_drag_coefficient > 0.0 or motor.rolling_moment_coefficient > 0.0
        inertia_terms = (1.0 / ixx, 1.0 / iyy, 1.0 / izz, izz - iyy, ixx - izz, iyy - ixx)
        drag = model.drag
        if self._rotor_drag:
            self._derivative = _derivative_rotor_drag
            self._const = (
                gravity, 1.0 / model.mass, drag.linear / model.mass, drag.quadratic / model.mass, drag.angular,
                *inertia_terms, motor.rotor_drag_coefficient, motor.rolling_moment_coefficient,
            )
        else:
            self._derivative = _derivative_basic
            self._const = (
                gravity, drag.linear / model.mass, drag.quadratic / model.mass, drag.angular, *inertia_terms,
            )
        self._max_rotor_speed = motor.max_rotor_speed
        # Per rotor: position, signed moment ratio (+ for CCW) and the products the H-force sums need.
        terms = []
        for rotor in model.rotors:
            px, py, pz = rotor.position
            terms.append((px, py, pz, rotor.spin * motor.moment_ratio, pz * pz, pz * px, pz * py, px * px + py * py))
        self._rotor_terms = tuple(terms)
        self._alpha_dt = -1.0
        self._alpha_up = self._alpha_down = 0.0
        self.reset()

    def reset(
        self,
        position: Vec3 = ZERO3,
        velocity: Vec3 = ZERO3,
        attitude: Quat = IDENTITY,
        angular_velocity: Vec3 = ZERO3,
        motor_states: Sequence[float] | None = None,
    ) -> None:
        """Place the vehicle; at or below z = 0 it is put on the ground, at rest and level."""
        n = len(self._rotor_terms)
        if motor_states is None:
            self._motor_states = [0.0] * n
        else:
            if len(motor_states) != n:
                raise ValueError(f"expected {n} motor states, got {len(motor_states)}")
            self._motor_states = [min(max(float(s), 0.0), 1.0) for s in motor_states]
        qn = math.sqrt(sum(c * c for c in attitude))
        if not qn > 0.0:
            raise ValueError("attitude must be a non-zero quaternion")
        self._position = (float(position[0]), float(position[1]), float(position[2]))
        self._velocity = (float(velocity[0]), float(velocity[1]), float(velocity[2]))
        self._attitude = (attitude[0] / qn, attitude[1] / qn, attitude[2] / qn, attitude[3] / qn)
        self._angular_velocity = (float(angular_velocity[0]), float(angular_velocity[1]), float(angular_velocity[2]))
        self._on_ground = False
        if self._position[2] >= 0.0:
            self._rest_on_ground(self._position[0], self._position[1], self._attitude)
        self._previous_velocity = self._velocity
        self._previous_angular_velocity = self._angular_velocity
        self._last_dt = 0.0

    def _rest_on_ground(self, north: float, east: float, attitude: Quat) -> None:
        self._position = (north, east, 0.0)
        self._velocity = ZERO3
        self._attitude = _level_about_heading(attitude)
        self._angular_velocity = ZERO3
        self._on_ground = True

    def _tip_onto_legs(self, attitude: Quat, dt: float) -> None:
        """On the ground: turn toward level about the heading, at most GROUND_TIP_RATE, with those rates."""
        level = _level_about_heading(attitude)
        ex, ey, ez = to_rotation_vector(mul(conj(attitude), level))  # body frame
        angle = math.sqrt(ex * ex + ey * ey + ez * ez)
        most = GROUND_TIP_RATE * dt
        if angle < 1e-9:  # resting level
            self._angular_velocity = ZERO3
            return
        if angle <= most:
            self._attitude = level
            self._angular_velocity = (ex / dt, ey / dt, ez / dt)
            return
        f = most / angle
        turn = (ex * f, ey * f, ez * f)
        self._attitude = normalized(mul(attitude, from_rotation_vector(turn)))
        self._angular_velocity = (turn[0] / dt, turn[1] / dt, turn[2] / dt)

    def step(self, dt: float, motor_commands: Sequence[float], wind_ned: Vec3 = ZERO3) -> None:
        """Advance the plant by dt seconds with the motor commands held and the given wind (NED, m/s)."""
        if dt != self._alpha_dt:
            model_motor = self.model.motor
            self._alpha_up = math.exp(-dt / model_motor.time_constant_up)
            self._alpha_down = math.exp(-dt / model_motor.time_constant_down)
            self._alpha_dt = dt
        alpha_up = self._alpha_up
        alpha_down = self._alpha_down
        states = self._motor_states
        if len(motor_commands) != len(states):
            raise ValueError(f"expected {len(states)} motor commands, got {len(motor_commands)}")
        quadratic = self._quadratic
        rotor_drag = self._rotor_drag
        thrust = mx = my = mz = 0.0
        s_sum = spx = spy = spz = ka = kb = kc = kd = 0.0
        for i, ((px, py, pz, km, pzz, pzx, pzy, prr), c) in enumerate(
            zip(self._rotor_terms, motor_commands, strict=False)
        ):
            c = 0.0 if not c > 0.0 else 1.0 if c > 1.0 else c
            s = states[i]
            s = c + (s - c) * (alpha_up if c > s else alpha_down)
            states[i] = s
            t = s * s if quadratic else s
            thrust += t
            mx -= py * t
            my += px * t
            mz += km * t
            if rotor_drag:
                s_sum += s
                spx += s * px
                spy += s * py
                spz += s * pz
                ka += s * pzz
                kb += s * pzx
                kc += s * pzy
                kd += s * prr
        max_thrust = self._max_thrust
        thrust *= max_thrust
        mx *= max_thrust
        my *= max_thrust
        mz *= max_thrust
        wind_n, wind_e, wind_d = wind_ned
        const = self._const
        if rotor_drag:
            w_max = self._max_rotor_speed
            held = (thrust, mx, my, mz, wind_n, wind_e, wind_d, s_sum * w_max, spx * w_max, spy * w_max,
                    spz * w_max, ka * w_max, kb * w_max, kc * w_max, kd * w_max)
        else:
            held = (thrust * self._inv_mass, mx, my, mz, wind_n, wind_e, wind_d)
        f = self._derivative

        x, y, z = self._position
        vx, vy, vz = self._velocity
        qw, qx, qy, qz = self._attitude
        wx, wy, wz = self._angular_velocity
        h = 0.5 * dt

        a1x, a1y, a1z, d1w, d1x, d1y, d1z, e1x, e1y, e1z = f(vx, vy, vz, qw, qx, qy, qz, wx, wy, wz, held, const)
        v2x = vx + h * a1x
        v2y = vy + h * a1y
        v2z = vz + h * a1z
        a2x, a2y, a2z, d2w, d2x, d2y, d2z, e2x, e2y, e2z = f(
            v2x, v2y, v2z, qw + h * d1w, qx + h * d1x, qy + h * d1y, qz + h * d1z,
            wx + h * e1x, wy + h * e1y, wz + h * e1z, held, const,
        )
        v3x = vx + h * a2x
        v3y = vy + h * a2y
        v3z = vz + h * a2z
        a3x, a3y, a3z, d3w, d3x, d3y, d3z, e3x, e3y, e3z = f(
            v3x, v3y, v3z, qw + h * d2w, qx + h * d2x, qy + h * d2y, qz + h * d2z,
            wx + h * e2x, wy + h * e2y, wz + h * e2z, held, const,
        )
        v4x = vx + dt * a3x
        v4y = vy + dt * a3y
        v4z = vz + dt * a3z
        a4x, a4y, a4z, d4w, d4x, d4y, d4z, e4x, e4y, e4z = f(
            v4x, v4y, v4z, qw + dt * d3w, qx + dt * d3x, qy + dt * d3y, qz + dt * d3z,
            wx + dt * e3x, wy + dt * e3y, wz + dt * e3z, held, const,
        )
        k = dt / 6.0
        x += k * (vx + 2.0 * (v2x + v3x) + v4x)
        y += k * (vy + 2.0 * (v2y + v3y) + v4y)
        z += k * (vz + 2.0 * (v2z + v3z) + v4z)
        vx += k * (a1x + 2.0 * (a2x + a3x) + a4x)
        vy += k * (a1y + 2.0 * (a2y + a3y) + a4y)
        vz += k * (a1z + 2.0 * (a2z + a3z) + a4z)
        qw += k * (d1w + 2.0 * (d2w + d3w) + d4w)
        qx += k * (d1x + 2.0 * (d2x + d3x) + d4x)
        qy += k * (d1y + 2.0 * (d2y + d3y) + d4y)
        qz += k * (d1z + 2.0 * (d2z + d3z) + d4z)
        wx += k * (e1x + 2.0 * (e2x + e3x) + e4x)
        wy += k * (e1y + 2.0 * (e2y + e3y) + e4y)
        wz += k * (e1z + 2.0 * (e2z + e3z) + e4z)

        self._previous_velocity = self._velocity
        self._previous_angular_velocity = self._angular_velocity
        self._last_dt = dt
        if z >= 0.0:
            if not self._on_ground:
                self._position = (x, y, 0.0)
                self._on_ground = True
                attitude = normalized((qw, qx, qy, qz))
            else:
                attitude = self._attitude  # pressed onto the ground: static friction holds it
            self._velocity = ZERO3
            self._tip_onto_legs(attitude, dt)
            return
        self._on_ground = False
        m = self._max_rate
        wx = -m if wx < -m else m if wx > m else wx
        wy = -m if wy < -m else m if wy > m else wy
        wz = -m if wz < -m else m if wz > m else wz
        n = 1.0 / math.sqrt(qw * qw + qx * qx + qy * qy + qz * qz)
        self._position = (x, y, z)
        self._velocity = (vx, vy, vz)
        self._attitude = (qw * n, qx * n, qy * n, qz * n)
        self._angular_velocity = (wx, wy, wz)

    # Truth accessors (for the ground-truth topic and the sensor models).

    @property
    def motor_states(self) -> tuple[float, ...]:
        """Motor states in [0, 1]: normalised rotor speed (quadratic model) or thrust (linear model)."""
        return tuple(self._motor_states)


def _level_about_heading(attitude: Quat) -> Quat:
    """The level attitude with the same heading (yaw) as ``attitude``."""
    w, x, y, z = attitude
    half_yaw = 0.5 * math.atan2(2.0 * (w * z + x * y), 1.0 - 2.0 * (y * y + z * z))
    return (math.cos(half_yaw), 0.0, 0.0, math.sin(half_yaw))
