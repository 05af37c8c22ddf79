"""Flat-plate aerodynamic segments: PX4 SIH's ``AeroSeg`` (``src/modules/simulation/simulator_sih/aero.hpp``).

The model is Khan and Nahon's (W. Khan, "Dynamics modeling of agile fixed-wing unmanned aerial
vehicles", PhD thesis, McGill University 2016, §3.1–3.3; Khan & Nahon, "Real-time modeling of agile
fixed-wing UAV aerodynamics", ICUAS 2015): a wing, tailplane or fin is a rectangular flat plate,
valid over the full 360° of angle of attack, with a control surface (flap) on its trailing edge.

Per segment, with α the angle of attack in the plate's x-z plane (minus its zero-lift angle α₀):

* attached flow: C_L = k_p·sin α·cos²α + K_v·|sin α|·sin α·cos α, with the 3-D lift slope
  k_p = c_lα / (1 + 2(AR + 4)/(AR(AR + 2))) and the vortex-lift parameter K_v = π;
  C_D = C_D0 + |C_L,high·tan α| with C_D0 = 0.04; C_M = −0.17·K_v·|sin α|·sin α;
* fully separated flow (flat plate): normal coefficient
  C_N = C_D90·sin α'·(1/(0.56 + 0.44|sin α'|) − 0.41(1 − e^(−17/AR))), tangential C_T = ½·C_D0·cos α',
  C_D90 = 1.98 (corrected for the flap), α' = α + asin(c_f/c_eff·sin δ); C_L, C_D from C_N, C_T;
* the two are blended over 10° around the stall angles, f = ½(1 − tanh(±4(α − α_stall)/10°));
* a flap deflection δ shifts the lift by ΔC_L = k_p·τ_f·η_f·δ (τ_f from the flap chord ratio, η_f a
  second-order fit of the flap effectiveness in |δ|) and moves the effective zero-lift angle and
  stall angles, each found by three Newton steps on the lift curve (as SIH does);
* the segment sees the body velocity at its position, v + ω × p, plus, in the propeller's wake, the
  slipstream speed of momentum theory √(2T/(ρπr²)) along its x axis;
* force ½ρV²·span·chord·(C_L sin α − C_D cos α, 0, −C_L cos α − C_D sin α) in the segment frame (the
  body frame rolled by the dihedral), moment ½ρV²·span·chord²·C_M about the segment's y axis plus
  p × F about the centre of gravity.

Where SIH's code and the thesis differ, this module does what SIH's code does: the separated-flow
C_L enters the attached-flow drag; the force is resolved with α (which includes α₀) rather than with
the flow angle, so a segment with α₀ ≠ 0 tilts its lift by α₀; the flap's C_D90 correction uses the
signed deflection; the flap effectiveness fit is SIH's. SIH's lookup of the stall angle reads past the
end of its 10-entry aspect-ratio table and returns 20° for every segment; :data:`FLAT_PLATE_STALL`
here is the thesis' table, and a vehicle file that wants SIH's figure gives the stall angle.
"""

from __future__ import annotations

import math
from math import asin, atan2, cos, sin, sqrt, tan, tanh

TWO_PI = 2.0 * math.pi
KV = math.pi  # total vortex-lift parameter
CD0 = 0.04  # zero-lift drag coefficient
CD90 = 1.98  # drag coefficient at 90° angle of attack
ALPHA_BLEND = math.pi / 18.0  # 10°: width of the attached/separated blend
FLAP_EFFECTIVENESS = (0.0535, -0.2688, 0.5817)  # η_f = a·|δ|² + b·|δ| + c, δ in rad
MAX_FLAP_FOR_EFFECTIVENESS = math.radians(70.0)  # the fit holds up to 70°
MIN_SPEED_SQUARED = 0.01  # (m/s)²: below this in the segment's x-z plane, no aerodynamic force
NEWTON_STEPS = 3

# Khan's Table 3.1: stall angle (deg) of rectangular flat plates by aspect ratio.
FLAT_PLATE_ASPECT_RATIO = (0.1666, 0.333, 0.4, 0.5, 1.0, 1.25, 2.0, 3.0, 4.0, 6.0)
FLAT_PLATE_STALL = (49.0, 54.0, 56.0, 48.0, 40.0, 29.0, 27.0, 25.0, 24.0, 22.0)

ZERO_WRENCH = (0.0, 0.0, 0.0, 0.0, 0.0, 0.0)


def lift_slope(aspect_ratio: float, section_slope: float = TWO_PI) -> float:
    """3-D lift slope k_p (1/rad) of a plate from its 2-D slope: c_lα / (1 + 2(AR + 4)/(AR(AR + 2)))."""
    ar = aspect_ratio
    return section_slope / (1.0 + 2.0 * (ar + 4.0) / (ar * (ar + 2.0)))


def flat_plate_stall_angle(aspect_ratio: float) -> float:
    """Stall angle (rad) of a flat plate, interpolated in Khan's table (held at its ends)."""
    xs, ys = FLAT_PLATE_ASPECT_RATIO, FLAT_PLATE_STALL
    if aspect_ratio <= xs[0]:
        return math.radians(ys[0])
    for i in range(1, len(xs)):
        if aspect_ratio <= xs[i]:
            t = (aspect_ratio - xs[i - 1]) / (xs[i] - xs[i - 1])
            return math.radians(ys[i - 1] + t * (ys[i] - ys[i - 1]))
    return math.radians(ys[-1])


def slipstream_speed(thrust: float, density: float, prop_radius: float) -> float:
    """Momentum-theory speed of the propeller's wake (m/s), √(2T/(ρπr²)), added to the segments it washes."""
    if thrust <= 0.0:
        return 0.0
    return sqrt(2.0 * thrust / (density * math.pi * prop_radius * prop_radius))


def _sign(x: float) -> float:
    return (x > 0.0) - (x < 0.0)


def _attached_lift(kp: float, a: float) -> float:
    s = sin(a)
    c = cos(a)
    return kp * s * c * c + KV * abs(s) * s * c


def solve_alpha_eff(kp: float, kv: float, delta_cl: float, a0: float) -> float:
    """SIH's ``solve_alpha_eff``: three Newton steps from a0 on −k_p·s·c² − k_v·|s|·s·c − ΔC_L = 0."""
    a = a0
    for _ in range(NEWTON_STEPS):
        s = sin(a)
        c = cos(a)
        f = -kp * s * c * c - kv * abs(s) * s * c - delta_cl
        df = (kv * abs(s) * s * s - kv * abs(s) * c * c - kp * c * c * c + 2.0 * kp * c * s * s
              - kv * _sign(s) * c * c * s)
        a = a - f / df
    return a


class AeroSegment:
    """One flat-plate segment (see the module docstring).

    Geometry in SI units and radians, body FRD: ``span`` and ``chord`` (the mean aerodynamic chord)
    of the segment; ``position`` of its aerodynamic centre from the centre of gravity; ``alpha_0``
    the zero-lift angle of attack (negative = the plate is set nose-up, e.g. −4° for a 4° incidence);
    ``dihedral`` the roll of the plate about body x (a fin is −90°); ``aspect_ratio`` that of the whole
    plate the segment belongs to (default span/chord); ``flap_chord`` the control surface's chord (0 =
    none); ``lift_slope_2d`` the section's lift slope; ``stall_angle_max``/``stall_angle_min`` the
    stall angles (default ± :func:`flat_plate_stall_angle`).

    :meth:`set_deflection` sets the flap angle (rad, positive = trailing edge down = more lift);
    :meth:`wrench` returns the force and moment about the centre of gravity, in body axes.
    """

    __slots__ = (
        "_alpha_0",
        "_cd90_eff",
        "_cl_at_max",
        "_cl_at_min",
        "_cos_dihedral",
        "_deflection",
        "_flap_fraction",
        "_flap_tau",
        "_full_flap",
        "_high_shift",
        "_kn",
        "_kp",
        "_lift_offset",
        "_moment_area",
        "_sin_dihedral",
        "_stall_eff_max",
        "_stall_eff_min",
        "alpha_0",
        "area",
        "aspect_ratio",
        "chord",
        "flap_chord",
        "position",
        "span",
        "stall_angle_max",
        "stall_angle_min",
    )

    def __init__(
        self,
        span: float,
        chord: float,
        position: tuple[float, float, float],
        *,
        alpha_0: float = 0.0,
        dihedral: float = 0.0,
        aspect_ratio: float | None = None,
        flap_chord: float = 0.0,
        lift_slope_2d: float = TWO_PI,
        stall_angle_max: float | None = None,
        stall_angle_min: float | None = None,
    ) -> None:
        if not (span > 0.0 and chord > 0.0):
            raise ValueError("span and chord must be > 0")
        self.span = span
        self.chord = chord
        self.position = (float(position[0]), float(position[1]), float(position[2]))
        self.alpha_0 = alpha_0
        self.aspect_ratio = span / chord if aspect_ratio is None or aspect_ratio <= 0.0 else aspect_ratio
        self.flap_chord = min(max(flap_chord, 0.0), chord)
        ar = self.aspect_ratio
        self._kp = lift_slope(ar, lift_slope_2d)
        self._kn = 0.41 * (1.0 - math.exp(-17.0 / ar))
        stall = flat_plate_stall_angle(ar)
        self.stall_angle_max = stall if stall_angle_max is None else stall_angle_max
        self.stall_angle_min = -stall if stall_angle_min is None else stall_angle_min
        self._alpha_0 = alpha_0
        self._sin_dihedral = sin(dihedral)
        self._cos_dihedral = cos(dihedral)
        self.area = span * chord
        self._moment_area = span * chord * chord
        self._flap_fraction = self.flap_chord / chord
        self._full_flap = self._flap_fraction >= 0.999
        theta_f = math.acos(2.0 * self._flap_fraction - 1.0)
        self._flap_tau = 1.0 - (theta_f - sin(theta_f)) / math.pi
        # The lift at the stall angles with fully attached flow (the flap adds to it).
        self._cl_at_max = _attached_lift(self._kp, self.stall_angle_max - alpha_0)
        self._cl_at_min = _attached_lift(self._kp, self.stall_angle_min - alpha_0)
        self._deflection = math.nan
        self.set_deflection(0.0)

    @property
    def deflection(self) -> float:
        return self._deflection

    def set_deflection(self, deflection: float) -> None:
        """Set the flap angle (rad): computes the terms that depend on it only (SIH's ``aoa_coeff`` preamble)."""
        if deflection == self._deflection:
            return
        self._deflection = d = deflection
        cf = self.flap_chord
        mac = self.chord
        if self._full_flap:
            self._lift_offset = -d
            self._stall_eff_max = self.stall_angle_max
            self._stall_eff_min = self.stall_angle_min
        else:
            da = min(abs(d), MAX_FLAP_FOR_EFFECTIVENESS)
            e2, e1, e0 = FLAP_EFFECTIVENESS
            eta_f = da * da * e2 + da * e1 + e0
            kp = self._kp
            delta_cl = kp * self._flap_tau * eta_f * d
            delta_cl_max = (1.0 - self._flap_fraction) * delta_cl
            alpha_0 = self._alpha_0
            zero_lift = solve_alpha_eff(kp, KV, delta_cl, alpha_0)
            cl_max = self._cl_at_max + delta_cl_max
            cl_min = self._cl_at_min + delta_cl_max
            self._lift_offset = zero_lift
            self._stall_eff_max = zero_lift - solve_alpha_eff(kp, KV, cl_max, self.stall_angle_max - alpha_0)
            self._stall_eff_min = zero_lift - solve_alpha_eff(kp, KV, cl_min, self.stall_angle_min - alpha_0)
        mac_eff = sqrt((mac - cf) * (mac - cf) + cf * cf + 2.0 * (mac - cf) * cf * cos(abs(d)))
        self._high_shift = asin(cf / mac_eff * sin(d))
        self._cd90_eff = CD90 + 0.21 * d - 0.0426 * d * d

    def coefficients(self, alpha: float) -> tuple[float, float, float]:
        """(C_L, C_D, C_M) at the angle of attack ``alpha`` (rad, α₀ already removed) and the set deflection."""
        ae = alpha - self._lift_offset
        # Separated flow (flat plate, normal and tangential coefficients).
        ah = ae + self._high_shift
        sh = sin(ah)
        ch = cos(ah)
        cn = self._cd90_eff * sh * (1.0 / (0.56 + 0.44 * abs(sh)) - self._kn)
        ct = 0.5 * CD0 * ch
        cl_high = cn * ch - ct * sh
        cd_high = cn * sh + ct * ch
        cm_high = -cn * (0.25 - 0.175 * (1.0 - 2.0 / math.pi * abs(ah)))
        # Attached flow.
        se = sin(ae)
        ce = cos(ae)
        abs_se = abs(se)
        cl_low = self._kp * se * ce * ce + KV * abs_se * se * ce
        cd_low = CD0 + abs(cl_high * tan(ae))
        cm_low = -0.17 * KV * abs_se * se
        if ae > 0.0:
            f = 0.5 * (1.0 - tanh(4.0 * (ae - self._stall_eff_max) / ALPHA_BLEND))
        else:
            f = 0.5 * (1.0 - tanh(-4.0 * (ae - self._stall_eff_min) / ALPHA_BLEND))
        g = 1.0 - f
        return cl_low * f + cl_high * g, cd_low * f + cd_high * g, cm_low * f + cm_high * g

    def wrench(
        self, u: float, v: float, w: float, p: float, q: float, r: float, density: float, slipstream: float = 0.0
    ) -> tuple[float, float, float, float, float, float]:
        """Force (N) and moment about the centre of gravity (N·m), body FRD, of this segment.

        (u, v, w): air-relative velocity of the centre of gravity in body axes (m/s); (p, q, r): body
        rates (rad/s); ``density`` in kg/m³; ``slipstream`` the propeller wake's speed (m/s) if the
        segment is in it.
        """
        px, py, pz = self.position
        vx = u + q * pz - r * py + slipstream
        vy = v + r * px - p * pz
        vz = w + p * py - q * px
        sd = self._sin_dihedral
        cd = self._cos_dihedral
        sz = cd * vz - sd * vy
        speed2 = vx * vx + sz * sz
        if speed2 < MIN_SPEED_SQUARED:
            return ZERO_WRENCH
        alpha = atan2(sz, vx) - self._alpha_0
        if alpha >= math.pi:
            alpha -= 2.0 * math.pi
        elif alpha < -math.pi:
            alpha += 2.0 * math.pi
        cl, cdrag, cm = self.coefficients(alpha)
        dynamic = 0.5 * density * speed2
        qs = dynamic * self.area
        sa = sin(alpha)
        ca = cos(alpha)
        fx = qs * (cl * sa - cdrag * ca)
        fz_seg = qs * (-cl * ca - cdrag * sa)
        pitching = dynamic * self._moment_area * cm
        fy = -sd * fz_seg
        fz = cd * fz_seg
        return (
            fx,
            fy,
            fz,
            py * fz - pz * fy,
            pz * fx - px * fz + cd * pitching,
            px * fy - py * fx + sd * pitching,
        )
