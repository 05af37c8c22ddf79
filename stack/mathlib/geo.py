"""Local NED ↔ geodetic conversion about a reference point (PX4 ``MapProjection``).

Azimuthal equidistant projection on a spherical Earth, as PX4 uses for its local frame; accurate to
centimetres over the few kilometres a multicopter flies.
"""

from __future__ import annotations

import math

EARTH_RADIUS_M = 6371000.0


class MapProjection:
    __slots__ = ("_cos_lat0", "_lat0", "_lon0", "_sin_lat0", "lat0_deg", "lon0_deg")

    def __init__(self, lat0_deg: float, lon0_deg: float) -> None:
        self.lat0_deg = lat0_deg
        self.lon0_deg = lon0_deg
        self._lat0 = math.radians(lat0_deg)
        self._lon0 = math.radians(lon0_deg)
        self._sin_lat0 = math.sin(self._lat0)
        self._cos_lat0 = math.cos(self._lat0)

    def project(self, lat_deg: float, lon_deg: float) -> tuple[float, float]:
        """Geodetic (deg) → local north, east (m)."""
        lat = math.radians(lat_deg)
        lon = math.radians(lon_deg)
        sin_lat, cos_lat = math.sin(lat), math.cos(lat)
        cos_d_lon = math.cos(lon - self._lon0)
        arg = self._sin_lat0 * sin_lat + self._cos_lat0 * cos_lat * cos_d_lon
        arg = max(-1.0, min(1.0, arg))
        c = math.acos(arg)
        k = c / math.sin(c) if abs(c) > 0.0 else 1.0
        north = k * (self._cos_lat0 * sin_lat - self._sin_lat0 * cos_lat * cos_d_lon) * EARTH_RADIUS_M
        east = k * cos_lat * math.sin(lon - self._lon0) * EARTH_RADIUS_M
        return north, east

    def reproject(self, north: float, east: float) -> tuple[float, float]:
        """Local north, east (m) → geodetic (deg); NaN for a non-finite position."""
        x = north / EARTH_RADIUS_M
        y = east / EARTH_RADIUS_M
        c = math.sqrt(x * x + y * y)
        if not math.isfinite(c):
            return math.nan, math.nan
        if c == 0.0:
            return self.lat0_deg, self.lon0_deg
        sin_c, cos_c = math.sin(c), math.cos(c)
        lat = math.asin(cos_c * self._sin_lat0 + (x * sin_c * self._cos_lat0) / c)
        lon = self._lon0 + math.atan2(y * sin_c, c * self._cos_lat0 * cos_c - x * self._sin_lat0 * sin_c)
        return math.degrees(lat), math.degrees(lon)
