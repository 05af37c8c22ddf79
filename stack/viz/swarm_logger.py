"""Every vehicle of a swarm in one Rerun view (``stack plot --all``): where each is, how high and fast, its battery,
its mode changes.

Each vehicle's estimate is placed by latitude and longitude (its local position and its frame's reference point)
in one north-east-down frame about the first reference point seen, so vehicles with homes apart are drawn apart,
each in its colour with its name; heights are each about its own ground, as the vehicle reports it. Positions
are drawn at most POSE_RATE_HZ per vehicle, a trail segment at most TRAIL_RATE_HZ. Times are the messages' own:
in lockstep every vehicle of a world is on one simulated clock from zero.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
import rerun as rr
import rerun.blueprint as rrb

from stack.commander.modes import mode_name
from stack.mathlib.geo import MapProjection
from stack.msg.estimation import VehicleLocalPosition
from stack.msg.system import BatteryStatus, VehicleStatus
from stack.viz import layout as lay

WORLD = "/swarm/world"
EVENTS = "/swarm/events"
HEIGHT = "/swarm/height"
SPEED = "/swarm/speed"
BATTERY = "/swarm/battery"
POSE_RATE_HZ = 10.0
TRAIL_RATE_HZ = 2.0


def vehicle_path(root: str, vehicle: str) -> str:
    return f"{root}/{vehicle}"


@dataclass
class _Vehicle:
    color: tuple[int, int, int]
    mode: int = -1
    armed: bool | None = None
    pose_at: int = -(10**18)
    trail_at: int = -(10**18)
    last: tuple[float, float, float] | None = None
    trail: list[tuple[float, float, float]] = field(default_factory=list)


class SwarmLogger:
    """Draws the vehicles' messages into ``rec``; :meth:`log_position`, :meth:`log_status` and :meth:`log_battery`
    take one message of one vehicle."""

    def __init__(self, rec: rr.RecordingStream) -> None:
        self.rec = rec
        self.frame: MapProjection | None = None
        self.vehicles: dict[str, _Vehicle] = {}
        self.drawn = 0
        rec.log(WORLD, rr.ViewCoordinates.RIGHT_HAND_Z_DOWN, static=True)

    def _vehicle(self, name: str) -> _Vehicle:
        vehicle = self.vehicles.get(name)
        if vehicle is None:
            vehicle = self.vehicles[name] = _Vehicle(lay.PALETTE[len(self.vehicles) % len(lay.PALETTE)])
            style = rr.SeriesLines(colors=[vehicle.color], names=[name])
            for root in (HEIGHT, SPEED, BATTERY):
                self.rec.log(vehicle_path(root, name), style, static=True)
        return vehicle

    def _at(self, t_us: int) -> None:
        self.rec.reset_time()
        self.rec.set_time(lay.SIM_TIME, duration=np.timedelta64(t_us, "us"))

    def log_position(self, name: str, m: VehicleLocalPosition) -> bool:
        """Draw the vehicle where it is (when its position is tied to latitude and longitude); whether it was."""
        vehicle = self._vehicle(name)
        t = m.timestamp
        if not (m.xy_valid and m.xy_global) or t - vehicle.pose_at < 1e6 / POSE_RATE_HZ:
            return False
        if self.frame is None:
            self.frame = MapProjection(m.ref_lat, m.ref_lon)
        lat, lon = MapProjection(m.ref_lat, m.ref_lon).reproject(m.x, m.y)
        north, east = self.frame.project(lat, lon)
        here = (north, east, m.z)
        if not all(math.isfinite(v) for v in here):
            return False
        vehicle.pose_at = t
        self._at(t)
        self.rec.log(
            vehicle_path(WORLD, name), rr.Points3D([here], colors=[vehicle.color], radii=[0.3], labels=[name])
        )
        self.rec.log(vehicle_path(HEIGHT, name), rr.Scalars(-m.z))
        self.rec.log(vehicle_path(SPEED, name), rr.Scalars(math.hypot(m.vx, m.vy, m.vz)))
        if vehicle.last is not None and t - vehicle.trail_at >= 1e6 / TRAIL_RATE_HZ:
            self.rec.log(
                vehicle_path(f"{WORLD}/trail", name),
                rr.LineStrips3D([[vehicle.last, here]], colors=[vehicle.color], radii=[0.05]),
            )
            vehicle.trail_at, vehicle.last = t, here
        elif vehicle.last is None:
            vehicle.trail_at, vehicle.last = t, here
        self.drawn += 1
        return True

    def log_status(self, name: str, m: VehicleStatus) -> None:
        """A line in the swarm's events when the vehicle's mode or arming changes."""
        vehicle = self._vehicle(name)
        armed = m.arming_state == VehicleStatus.ARMING_STATE_ARMED
        if m.nav_state == vehicle.mode and armed == vehicle.armed:
            return
        changes = []
        if m.nav_state != vehicle.mode:
            changes.append(mode_name(m.nav_state))
        if armed != vehicle.armed:
            changes.append("armed" if armed else "disarmed")
        vehicle.mode, vehicle.armed = m.nav_state, armed
        self._at(m.timestamp)
        self.rec.log(EVENTS, rr.TextLog(f"{name}: {', '.join(changes)}", level="INFO"))

    def log_battery(self, name: str, m: BatteryStatus) -> None:
        self._vehicle(name)
        if m.connected and math.isfinite(m.remaining) and m.remaining >= 0.0:
            self._at(m.timestamp)
            self.rec.log(vehicle_path(BATTERY, name), rr.Scalars(100.0 * m.remaining))


def swarm_blueprint(window_s: float | None) -> rrb.Blueprint:
    """Every vehicle in 3D with the events below; height, speed and battery of each, one line per vehicle."""
    window = None
    if window_s is not None:
        window = rrb.VisibleTimeRange(
            lay.SIM_TIME,
            start=rrb.TimeRangeBoundary.cursor_relative(seconds=-window_s),
            end=rrb.TimeRangeBoundary.cursor_relative(),
        )
    up_to_cursor = rrb.VisibleTimeRanges(
        timeline=lay.SIM_TIME, start=rrb.TimeRangeBoundary.infinite(), end=rrb.TimeRangeBoundary.cursor_relative()
    )
    scene = rrb.Spatial3DView(origin=WORLD, name="swarm (NED)", overrides={f"{WORLD}/trail": up_to_cursor})
    series = rrb.Vertical(
        rrb.TimeSeriesView(origin=HEIGHT, name="height [m]", time_ranges=window),
        rrb.TimeSeriesView(origin=SPEED, name="speed [m/s]", time_ranges=window),
        rrb.TimeSeriesView(origin=BATTERY, name="battery [%]", time_ranges=window),
    )
    events = rrb.TextLogView(origin=EVENTS, name="modes")
    return rrb.Blueprint(
        rrb.Horizontal(rrb.Vertical(scene, events, row_shares=[3, 1]), series, column_shares=[3, 2]),
        rrb.TimePanel(timeline=lay.SIM_TIME),
    )
