"""The home position (PX4 ``home_position``): where the vehicle armed, used by return and the geofence."""

from __future__ import annotations

import math
from typing import NamedTuple

from stack.mathlib.geo import MapProjection


class HomePosition(NamedTuple):
    """Home in the local NED frame (x, y, z in m, yaw in rad) and, when the local frame has a global
    reference, geodetically (lat, lon in deg, alt in m AMSL; NaN otherwise)."""

    x: float
    y: float
    z: float
    yaw: float
    lat: float = math.nan
    lon: float = math.nan
    alt: float = math.nan

    @property
    def position(self) -> tuple[float, float, float]:
        return (self.x, self.y, self.z)

    @property
    def global_valid(self) -> bool:
        return math.isfinite(self.lat) and math.isfinite(self.lon) and math.isfinite(self.alt)


def home_from_local_position(
    x: float, y: float, z: float, heading: float, ref_lat: float, ref_lon: float, ref_alt: float
) -> HomePosition:
    """Home at the given local position; lat/lon/alt follow from the local frame's reference when set."""
    lat = lon = alt = math.nan
    if math.isfinite(ref_lat) and math.isfinite(ref_lon):
        lat, lon = MapProjection(ref_lat, ref_lon).reproject(x, y)
    if math.isfinite(ref_alt):
        alt = ref_alt - z
    return HomePosition(x, y, z, heading if math.isfinite(heading) else 0.0, lat, lon, alt)
