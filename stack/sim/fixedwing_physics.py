"""6-DOF rigid-body fixed-wing plant: PX4 SIH's airplane with a landing gear.

The forces and moments follow PX4 SIH (``src/modules/simulation/simulator_sih/sih.cpp``,
``generate_fw_aerodynamics``): the flat-plate segments of :mod:`stack.sim.aero` (wings with ailerons,
tailplane with elevator and fin with rudder in the propeller's slipstream, fuselage), thrust along
body +x through the centre of gravity (SIH's advance-ratio propeller, or a constant T_max·s) from the
throttle state s, which follows the command through a first-order lag; linear drag −K_dv·v_air,
angular damping −K_dw·ω, gravity, and the gyroscopic term of the full inertia tensor (with its xz
element). Surfaces follow their commands at once, as in SIH.
The air density is the ISA density at the vehicle's altitude; v_air = v − wind.

SIH's ground only cancels the downward force; here a landing gear carries the plane (see the vehicle
file's ``[ground]`` and ``[[contact]]``): each contact point is a spring-damper along the ground normal,
and in the ground plane a "tread" spring from the point where it gripped, capped at μ·N, holds it
still or lets it slide. Free wheels roll along their direction with a small rolling resistance
(linear below ``rolling_speed``, so smooth at rest); the steerable wheel turns by the rudder command
times ``max_steering``; braked wheels hold while the throttle command is below ``brake_throttle``.
The runway is the plane NED z = h, with h the height of the centre of gravity above the ground when the
plane rests on its gear (solved from the gear's static equilibrium), so the plane at rest has z = 0,
as the multicopters do.

Integration: semi-implicit (symplectic) Euler, one force evaluation per step — body rates, then the
attitude with the new rates (exact rotation), then velocity and position with the new velocity.
PX4 SIH integrates explicitly at 250–400 Hz. The gear (≈ 9 Hz vertical mode, 300 N/m tread springs)
is stable from 250 Hz up; 500 Hz (``Simulator(physics_rate_hz=500)``, two steps per IMU period)
flies a trim within about a centimetre of a 4 kHz run over 10 s, at ~100× real time with the sensors.

Frames and units are PX4's: NED position and velocity about home, Hamilton quaternion body FRD → NED,
body rates FRD.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import NamedTuple

from stack.airframe.model import FIXEDWING_CONTROLS, FixedwingModel, propeller_thrust
from stack.mathlib.quaternion import IDENTITY, Quat, from_euler, yaw
from stack.mathlib.scalar import CONSTANTS_ONE_G
from stack.mathlib.vector import ZERO3, Vec3
from stack.sim.aero import AeroSegment, slipstream_speed
from stack.sim.airspeed_sensor import air_density
from stack.sim.physics import SIH_MAX_BODY_RATE
from stack.sim.rigid_body import RigidBodyState

_REST_TOLERANCE = 1e-12
_REST_ITERATIONS = 50


class FixedwingPhysics(RigidBodyState):
    """The plant of one fixed-wing (see the module docstring).

    ``home_altitude`` (m AMSL) sets the air density at z = 0; ``max_body_rate`` clamps each body rate
    (SIH: 6π rad/s). Commands: (throttle [0, 1], aileron, elevator, rudder [−1, 1]); a non-finite
    command counts as 0, values out of range are clamped.
    """

    __slots__ = (
        "_alpha",
        "_alpha_dt",
        "_anchors",
        "_angular_velocity",
        "_attitude",
        "_contacts",
        "_controlled",
        "_gravity",
        "_ground_depth",
        "_home_altitude",
        "_inertia",
        "_inverse_inertia",
        "_last_dt",
        "_max_rate",
        "_on_ground",
        "_position",
        "_previous_angular_velocity",
        "_previous_velocity",
        "_rest_roll_pitch",
        "_segments",
        "_throttle",
        "_thrust",
        "_velocity",
        "model",
    )

    def __init__(
        self,
        model: FixedwingModel,
        home_altitude: float = 0.0,
        max_body_rate: float = SIH_MAX_BODY_RATE,
        gravity: float = CONSTANTS_ONE_G,
    ) -> None:
        if max_body_rate <= 0.0:
            raise ValueError("max_body_rate must be > 0")
        self.model = model
        self._home_altitude = home_altitude
        self._max_rate = max_body_rate
        self._gravity = gravity
        ixx, iyy, izz = model.inertia
        ixz = model.inertia_xz
        det = ixx * izz - ixz * ixz
        self._inertia = (ixx, iyy, izz, ixz)
        self._inverse_inertia = (izz / det, 1.0 / iyy, ixx / det, -ixz / det)
        self._segments = tuple(
            (
                AeroSegment(
                    s.span, s.chord, s.position, alpha_0=s.alpha_0, dihedral=s.dihedral, aspect_ratio=s.aspect_ratio,
                    flap_chord=s.flap_chord, lift_slope_2d=s.lift_slope, stall_angle_max=s.stall_angle,
                    stall_angle_min=None if s.stall_angle is None else -s.stall_angle,
                ),
                s.slipstream,
            )
            for s in model.segments
        )
        self._controlled = tuple(
            (segment, 1 + FIXEDWING_CONTROLS.index(spec.control), spec.direction * model.max_deflection)
            for (segment, _), spec in zip(self._segments, model.segments, strict=True)
            if spec.control is not None
        )
        self._contacts = tuple(
            (c.position, c.stiffness, c.damping, c.wheel, c.steering, c.brake) for c in model.contacts
        )
        height, roll, pitch = rest_pose(model, gravity)
        self._ground_depth = height
        self._rest_roll_pitch = (roll, pitch)
        self._alpha_dt = -1.0
        self._alpha = 0.0
        self.reset()

    @property
    def ground_depth(self) -> float:
        """How far the runway lies below NED z = 0 (m): the centre of gravity's height above it at rest."""
        return self._ground_depth

    def reset(
        self,
        position: Vec3 = ZERO3,
        velocity: Vec3 = ZERO3,
        attitude: Quat = IDENTITY,
        angular_velocity: Vec3 = ZERO3,
        motor_states: Sequence[float] | None = None,
    ) -> None:
        """Place the vehicle; at or below z = 0 it rests on its gear, at rest, with the heading of ``attitude``.

        ``motor_states``: the throttle state (one value in [0, 1]); default 0.
        """
        if motor_states is None:
            self._throttle = 0.0
        else:
            if len(motor_states) != 1:
                raise ValueError(f"expected 1 motor state (the throttle), got {len(motor_states)}")
            self._throttle = min(max(float(motor_states[0]), 0.0), 1.0)
        qn = math.sqrt(sum(c * c for c in attitude))
        if not qn > 0.0:
            raise ValueError("attitude must be a non-zero quaternion")
        q = (attitude[0] / qn, attitude[1] / qn, attitude[2] / qn, attitude[3] / qn)
        self._anchors: list[tuple[float, float] | None] = [None] * len(self._contacts)
        if position[2] >= 0.0:
            roll, pitch = self._rest_roll_pitch
            self._position = (float(position[0]), float(position[1]), 0.0)
            self._velocity = ZERO3
            self._attitude = from_euler(roll, pitch, yaw(q))
            self._angular_velocity = ZERO3
            self._on_ground = True
        else:
            self._position = (float(position[0]), float(position[1]), float(position[2]))
            self._velocity = (float(velocity[0]), float(velocity[1]), float(velocity[2]))
            self._attitude = q
            self._angular_velocity = (float(angular_velocity[0]), float(angular_velocity[1]),
                                      float(angular_velocity[2]))
            self._on_ground = False
        self._previous_velocity = self._velocity
        self._previous_angular_velocity = self._angular_velocity
        self._last_dt = 0.0
        self._thrust = 0.0

    def step(self, dt: float, commands: Sequence[float], wind_ned: Vec3 = ZERO3) -> None:
        """Advance by dt seconds with the commands held (throttle, aileron, elevator, rudder) in the wind (NED)."""
        if len(commands) != 4:
            raise ValueError(f"expected 4 commands (throttle, aileron, elevator, rudder), got {len(commands)}")
        throttle_cmd, aileron, elevator, rudder = (c if math.isfinite(c) else 0.0 for c in commands)
        throttle_cmd = min(max(throttle_cmd, 0.0), 1.0)
        surfaces = (throttle_cmd, min(max(aileron, -1.0), 1.0), min(max(elevator, -1.0), 1.0),
                    min(max(rudder, -1.0), 1.0))
        model = self.model
        if dt != self._alpha_dt:
            self._alpha = math.exp(-dt / model.thruster.time_constant)
            self._alpha_dt = dt
        throttle = throttle_cmd + (self._throttle - throttle_cmd) * self._alpha
        self._throttle = throttle

        x, y, z = self._position
        vx, vy, vz = self._velocity
        qw, qx, qy, qz = self._attitude
        p, q, r = self._angular_velocity
        # Rotation matrix body → NED.
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

        an = vx - wind_ned[0]
        ae = vy - wind_ned[1]
        ad = vz - wind_ned[2]
        u = r00 * an + r10 * ae + r20 * ad
        v = r01 * an + r11 * ae + r21 * ad
        w = r02 * an + r12 * ae + r22 * ad

        density = air_density(self._home_altitude - z)
        thruster = model.thruster
        propeller = thruster.propeller
        if propeller is None:
            thrust = thruster.max_thrust * throttle
        else:
            thrust = propeller_thrust(throttle, u, density, propeller.diameter, propeller.max_rpm,
                                      propeller.thrust_coefficients)
        self._thrust = thrust
        slip = slipstream_speed(thrust, density, thruster.prop_radius)
        for segment, index, gain in self._controlled:
            segment.set_deflection(gain * surfaces[index])
        fx = fy = fz = mx = my = mz = 0.0
        for segment, in_slipstream in self._segments:
            sfx, sfy, sfz, smx, smy, smz = segment.wrench(u, v, w, p, q, r, density, slip if in_slipstream else 0.0)
            fx += sfx
            fy += sfy
            fz += sfz
            mx += smx
            my += smy
            mz += smz
        drag = model.drag
        k = drag.linear + drag.quadratic * math.sqrt(u * u + v * v + w * w)
        fx += thrust - k * u
        fy -= k * v
        fz -= k * w
        mx -= drag.angular * p
        my -= drag.angular * q
        mz -= drag.angular * r

        inv_m = 1.0 / model.mass
        acc_n = (r00 * fx + r01 * fy + r02 * fz) * inv_m
        acc_e = (r10 * fx + r11 * fy + r12 * fz) * inv_m
        acc_d = (r20 * fx + r21 * fy + r22 * fz) * inv_m + self._gravity
        rotation = (r00, r01, r02, r10, r11, r12, r20, r21, r22)
        gn, ge, gd, gmx, gmy, gmz = self._gear(rotation, throttle_cmd < model.ground.brake_throttle, rudder)
        acc_n += gn * inv_m
        acc_e += ge * inv_m
        acc_d += gd * inv_m
        mx += gmx
        my += gmy
        mz += gmz

        ixx, iyy, izz, ixz = self._inertia
        hx = ixx * p + ixz * r
        hy = iyy * q
        hz = ixz * p + izz * r
        tx = mx - (q * hz - r * hy)
        ty = my - (r * hx - p * hz)
        tz = mz - (p * hy - q * hx)
        jxx, jyy, jzz, jxz = self._inverse_inertia
        m = self._max_rate
        p = min(max(p + (jxx * tx + jxz * tz) * dt, -m), m)
        q = min(max(q + jyy * ty * dt, -m), m)
        r = min(max(r + (jxz * tx + jzz * tz) * dt, -m), m)
        # Attitude: the exact rotation by ω·dt in the body frame.
        angle = math.sqrt(p * p + q * q + r * r) * dt
        if angle > 1e-12:
            half = 0.5 * angle
            s = math.sin(half) / angle * dt
            dw, dx, dy, dz = math.cos(half), p * s, q * s, r * s
            qw, qx, qy, qz = (
                qw * dw - qx * dx - qy * dy - qz * dz,
                qw * dx + qx * dw + qy * dz - qz * dy,
                qw * dy - qx * dz + qy * dw + qz * dx,
                qw * dz + qx * dy - qy * dx + qz * dw,
            )
            n = 1.0 / math.sqrt(qw * qw + qx * qx + qy * qy + qz * qz)
            self._attitude = (qw * n, qx * n, qy * n, qz * n)
        self._previous_velocity = self._velocity
        self._previous_angular_velocity = self._angular_velocity
        self._last_dt = dt
        vx += acc_n * dt
        vy += acc_e * dt
        vz += acc_d * dt
        self._velocity = (vx, vy, vz)
        self._position = (x + vx * dt, y + vy * dt, z + vz * dt)
        self._angular_velocity = (p, q, r)

    def _gear(self, rot: tuple[float, ...], braking: bool, rudder: float) -> tuple[float, ...]:
        """Ground-contact force (NED, N) and moment (body, N·m) now; moves the grip points of the contacts."""
        r00, r01, r02, r10, r11, r12, r20, r21, r22 = rot
        x, y, z = self._position
        vx, vy, vz = self._velocity
        p, q, r = self._angular_velocity
        ground = self.model.ground
        depth = self._ground_depth
        kt = ground.tread_stiffness
        ct = ground.tread_damping
        fn = fe = fd = mx = my = mz = 0.0
        on_ground = False
        anchors = self._anchors
        for i, ((bx, by, bz), stiffness, damping, wheel, steering, brake) in enumerate(self._contacts):
            oz = r20 * bx + r21 * by + r22 * bz
            penetration = z + oz - depth
            if penetration <= 0.0:
                anchors[i] = None
                continue
            # Velocity of the contact point: v + R(ω × b).
            wx = q * bz - r * by
            wy = r * bx - p * bz
            wz = p * by - q * bx
            cvz = vz + r20 * wx + r21 * wy + r22 * wz
            normal = stiffness * penetration + damping * cvz
            if normal <= 0.0:
                anchors[i] = None
                continue
            on_ground = True
            on = r00 * bx + r01 * by + r02 * bz
            oe = r10 * bx + r11 * by + r12 * bz
            cn = x + on
            ce = y + oe
            cvn = vx + r00 * wx + r01 * wy + r02 * wz
            cve = vy + r10 * wx + r11 * wy + r12 * wz
            # The wheel's rolling direction on the ground: body x, turned by the steering angle.
            if steering:
                delta = rudder * ground.max_steering
                hx, hy = math.cos(delta), math.sin(delta)
                en, ee = r00 * hx + r01 * hy, r10 * hx + r11 * hy
            else:
                en, ee = r00, r10
            length = math.hypot(en, ee)
            rolling = wheel and length > 0.1
            if length > 1e-9:
                en /= length
                ee /= length
            else:
                en, ee = 1.0, 0.0
            ln, le = -ee, en
            anchor = anchors[i]
            dn, de = (0.0, 0.0) if anchor is None else (cn - anchor[0], ce - anchor[1])
            d_long = dn * en + de * ee
            d_lat = dn * ln + de * le
            v_long = cvn * en + cve * ee
            v_lat = cvn * ln + cve * le
            if rolling:
                if brake and braking:
                    f_long, d_long = _grip(d_long, v_long, kt, ct, ground.brake_friction * normal)
                else:
                    f_long = -ground.rolling_friction * normal * min(max(v_long / ground.rolling_speed, -1.0), 1.0)
                    d_long = 0.0
                f_lat, d_lat = _grip(d_lat, v_lat, kt, ct, ground.side_friction * normal)
            else:
                # A skid (or a wheel on its side): one friction limit in every direction.
                f_long = -kt * d_long - ct * v_long
                f_lat = -kt * d_lat - ct * v_lat
                limit = ground.skid_friction * normal
                magnitude = math.hypot(f_long, f_lat)
                if magnitude > limit:
                    scale = limit / magnitude
                    f_long *= scale
                    f_lat *= scale
                    d_long = -f_long / kt
                    d_lat = -f_lat / kt
            anchors[i] = (cn - d_long * en - d_lat * ln, ce - d_long * ee - d_lat * le)
            f_n = f_long * en + f_lat * ln
            f_e = f_long * ee + f_lat * le
            f_d = -normal
            fn += f_n
            fe += f_e
            fd += f_d
            # Moment about the CG in body axes: b × Rᵀf.
            gx = r00 * f_n + r10 * f_e + r20 * f_d
            gy = r01 * f_n + r11 * f_e + r21 * f_d
            gz = r02 * f_n + r12 * f_e + r22 * f_d
            mx += by * gz - bz * gy
            my += bz * gx - bx * gz
            mz += bx * gy - by * gx
        self._on_ground = on_ground
        return fn, fe, fd, mx, my, mz

    # Truth accessors (for the ground-truth topic and the sensor models).

    @property
    def motor_states(self) -> tuple[float, ...]:
        """The throttle state in [0, 1] (thrust = SIH_T_MAX × it)."""
        return (self._throttle,)

    @property
    def thrust(self) -> float:
        """The propeller's thrust in the last step (N, along body +x)."""
        return self._thrust


def _grip(displacement: float, speed: float, stiffness: float, damping: float, limit: float) -> tuple[float, float]:
    """Tread spring along one axis, capped at ``limit``: (force, the displacement it leaves)."""
    force = -stiffness * displacement - damping * speed
    if force > limit:
        return limit, -limit / stiffness
    if force < -limit:
        return -limit, limit / stiffness
    return force, displacement


def rest_pose(model: FixedwingModel, gravity: float = CONSTANTS_ONE_G) -> tuple[float, float, float]:
    """(height of the CG above the ground (m), roll, pitch (rad)) where the gear's springs carry the weight.

    Newton's method on the static balance of the contacts' spring forces: their sum equals the weight
    and their moments about the centre of gravity vanish. Raises ``ValueError`` if the contacts cannot
    hold the plane up.
    """
    weight = model.mass * gravity
    contacts = [(c.position, c.stiffness) for c in model.contacts]

    def residual(state: tuple[float, float, float]) -> tuple[float, float, float]:
        height, roll, pitch = state
        sr, cr, sp, cp = math.sin(roll), math.cos(roll), math.sin(pitch), math.cos(pitch)
        total = moment_n = moment_e = 0.0
        for (bx, by, bz), stiffness in contacts:
            # Body → NED for yaw 0: rows of R(roll, pitch).
            on = cp * bx + sp * sr * by + sp * cr * bz
            oe = cr * by - sr * bz
            od = -sp * bx + cp * sr * by + cp * cr * bz
            penetration = od - height
            if penetration > 0.0:
                force = stiffness * penetration
                total += force
                moment_n += oe * force
                moment_e += on * force
        return total - weight, moment_n, moment_e

    # Start with the lowest contacts pressed in as if they shared the weight evenly.
    lowest = max(c.position[2] for c in model.contacts)
    state = (lowest - weight / sum(c.stiffness for c in model.contacts if c.position[2] == lowest), 0.0, 0.0)
    for _ in range(_REST_ITERATIONS):
        f = residual(state)
        if max(abs(f[0]), abs(f[1]), abs(f[2])) < _REST_TOLERANCE * max(weight, 1.0):
            break
        jacobian = []
        for j in range(3):
            h = 1e-7
            shifted = tuple(s + (h if k == j else 0.0) for k, s in enumerate(state))
            g = residual(shifted)  # type: ignore[arg-type]
            jacobian.append([(g[i] - f[i]) / h for i in range(3)])
        step = _solve3([[jacobian[j][i] for j in range(3)] for i in range(3)], [-c for c in f])
        if step is None:
            raise ValueError(f"{model.name}: the landing gear cannot carry the plane (no static equilibrium)")
        state = (state[0] + step[0], state[1] + step[1], state[2] + step[2])
    else:
        raise ValueError(f"{model.name}: the landing gear's static equilibrium did not converge")
    height, roll, pitch = state
    if height <= 0.0 or abs(roll) > 0.5 or abs(pitch) > 0.5:
        raise ValueError(f"{model.name}: the plane does not stand on its gear (height {height:.3f} m, "
                         f"roll {math.degrees(roll):.1f}°, pitch {math.degrees(pitch):.1f}°)")
    return state


class LevelTrim(NamedTuple):
    """Steady straight and level flight: commands and the pitch angle (= angle of attack, rad)."""

    throttle: float
    elevator: float
    pitch: float


def level_trim(model: FixedwingModel, airspeed: float, altitude: float = 0.0) -> LevelTrim:
    """The throttle, elevator and pitch that hold ``airspeed`` (m/s) level in calm air at ``altitude`` m AMSL.

    Newton's method on the forward, vertical and pitch accelerations of the plant itself. Raises
    ``ValueError`` when there is none within the command ranges (too slow: stalled; too fast: not
    enough thrust).
    """
    height = 1000.0  # well clear of the gear; the density is that of ``altitude``
    plant = FixedwingPhysics(model, home_altitude=altitude - height)
    probe_dt = 1e-4

    def residual(state: tuple[float, float, float]) -> tuple[float, float, float]:
        throttle, elevator, pitch = state
        plant.reset((0.0, 0.0, -height), (airspeed, 0.0, 0.0), from_euler(0.0, pitch, 0.0), ZERO3, [throttle])
        plant.step(probe_dt, (throttle, 0.0, elevator, 0.0))
        a = plant.acceleration
        return a[0], a[2], plant.angular_acceleration[1]

    state = (0.5, 0.0, 0.0)
    for _ in range(_REST_ITERATIONS):
        f = residual(state)
        if max(abs(c) for c in f) < 1e-9:
            break
        columns = []
        for j in range(3):
            shifted = tuple(s + (1e-6 if k == j else 0.0) for k, s in enumerate(state))
            g = residual(shifted)  # type: ignore[arg-type]
            columns.append([(g[i] - f[i]) / 1e-6 for i in range(3)])
        step = _solve3([[columns[j][i] for j in range(3)] for i in range(3)], [-c for c in f])
        if step is None:
            raise ValueError(f"{model.name}: no level trim at {airspeed} m/s within the command ranges")
        state = (state[0] + step[0], state[1] + step[1], state[2] + step[2])
    else:
        raise ValueError(f"{model.name}: no level trim at {airspeed} m/s (Newton did not converge)")
    throttle, elevator, pitch = state
    if not (0.0 <= throttle <= 1.0 and -1.0 <= elevator <= 1.0 and abs(pitch) < 0.5 * math.pi):
        raise ValueError(f"{model.name}: no level trim at {airspeed} m/s within the command ranges")
    return LevelTrim(throttle, elevator, pitch)


def _solve3(a: list[list[float]], b: list[float]) -> list[float] | None:
    """Solve the 3×3 system a·x = b by Cramer's rule; None if it is singular."""
    def det(m: list[list[float]]) -> float:
        return (m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1])
                - m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0])
                + m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0]))

    d = det(a)
    if abs(d) < 1e-15:
        return None
    result = []
    for j in range(3):
        m = [row[:] for row in a]
        for i in range(3):
            m[i][j] = b[i]
        result.append(det(m) / d)
    return result
