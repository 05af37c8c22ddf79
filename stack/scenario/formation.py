"""Flying in formation behind a leader heard over the radio: where a follower should be, when the leader is lost,
and the leader's box.

A follower keeps an offset (north, east, down, m) from its leader. It places the leader horizontally by latitude
and longitude (the leader's local position and its frame's reference point, projected into the follower's frame)
and vertically by height: the leader's height above where its estimator started (its ground) is taken as the
follower's height above its home, as each vehicle of a swarm measures height about its own ground. The position
heard is some time old: the follower carries it on to now with the leader's velocity and flies that velocity as
its feed-forward (PX4's ``trajectory_setpoint`` with position and velocity, as an offboard companion sends it). A
leader not heard for LEADER_TIMEOUT_S is lost, and nothing it said before is followed any more.
"""

from __future__ import annotations

import math

from stack.mathlib.geo import MapProjection
from stack.msg.estimation import VehicleLocalPosition
from stack.msg.setpoints import TrajectorySetpoint

Vec3 = tuple[float, float, float]

LEADER_DELAY_S = 0.1
"""How long after the leader publishes its position the others hear it (a radio link's latency). Longer than the
world clock's slack (stack.runtime.world_clock.SLACK_US) and the leader's publication period together, a follower
finds the position due already there and never waits for it."""
LEADER_TIMEOUT_S = 0.5
"""A leader whose newest position heard is older than this is lost."""
BOX_SIDE_M = 20.0
BOX_SPEED_M_S = 2.0
BOX_ACCEL_M_S2 = 1.0
_LEGS = ((1.0, 0.0), (0.0, 1.0), (-1.0, 0.0), (0.0, -1.0))  # north, east, south, west


def slot_offset(slot: int, spacing_m: float) -> Vec3:
    """Vehicle ``slot``'s place about the leader (slot 1): as far east as its home is from the leader's, so that the
    formation lines up abreast and every vehicle comes back over its own home."""
    return (0.0, (slot - 1) * spacing_m, 0.0)


def heard_age_s(leader: VehicleLocalPosition, now_us: int) -> float:
    """How old the leader's position is at ``now_us``."""
    return (now_us - leader.timestamp_sample) * 1e-6


def leader_lost(leader: VehicleLocalPosition | None, now_us: int) -> bool:
    return leader is None or heard_age_s(leader, now_us) > LEADER_TIMEOUT_S


def leader_height_m(leader: VehicleLocalPosition) -> float:
    """The leader's height above where its estimator started."""
    return -leader.z


def formation_setpoint(
    leader: VehicleLocalPosition, own: VehicleLocalPosition, own_home_z: float, offset: Vec3, now_us: int
) -> TrajectorySetpoint | None:
    """Where the follower flies now (position and velocity in its frame), or None while either position has no
    reference point or the leader's is not valid."""
    if not (leader.xy_valid and leader.z_valid and leader.xy_global and own.xy_global):
        return None
    age = heard_age_s(leader, now_us)
    lat, lon = MapProjection(leader.ref_lat, leader.ref_lon).reproject(leader.x + leader.vx * age,
                                                                       leader.y + leader.vy * age)
    north, east = MapProjection(own.ref_lat, own.ref_lon).project(lat, lon)
    down = own_home_z + leader.z + leader.vz * age
    position = (north + offset[0], east + offset[1], down + offset[2])
    if not all(math.isfinite(v) for v in position):
        return None
    return TrajectorySetpoint(position=position, velocity=(leader.vx, leader.vy, leader.vz))


def box_setpoint(start: Vec3, t: float) -> tuple[Vec3, Vec3, bool]:
    """The leader's box ``t`` seconds after it left ``start``: a BOX_SIDE_M square flown north, east, south and west,
    each side from a stop to a stop at BOX_ACCEL_M_S2 up to BOX_SPEED_M_S (as a mission stops at its waypoints).
    Position, velocity, and whether it is back at the start."""
    ramp_s = BOX_SPEED_M_S / BOX_ACCEL_M_S2
    ramp_m = BOX_SPEED_M_S * ramp_s / 2.0
    leg_s = ramp_s + BOX_SIDE_M / BOX_SPEED_M_S
    leg = int(t // leg_s)
    if leg >= len(_LEGS):
        return start, (0.0, 0.0, 0.0), True
    north, east = start[0], start[1]
    for dn, de in _LEGS[:leg]:
        north, east = north + dn * BOX_SIDE_M, east + de * BOX_SIDE_M
    tau = t - leg * leg_s
    if tau < ramp_s:
        along, speed = BOX_ACCEL_M_S2 * tau * tau / 2.0, BOX_ACCEL_M_S2 * tau
    elif tau < leg_s - ramp_s:
        along, speed = ramp_m + (tau - ramp_s) * BOX_SPEED_M_S, BOX_SPEED_M_S
    else:
        left = leg_s - tau
        along, speed = BOX_SIDE_M - BOX_ACCEL_M_S2 * left * left / 2.0, BOX_ACCEL_M_S2 * left
    dn, de = _LEGS[leg]
    return (north + dn * along, east + de * along, start[2]), (dn * speed, de * speed, 0.0), False
