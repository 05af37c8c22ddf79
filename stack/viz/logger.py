"""FlightLogger: turns the stack's messages into Rerun entities, batched and decimated.

Fed ``(topic, instance, message)`` one at a time — live by the bridge module, from a recording by
the exporter, directly by tests — it writes to the ``rerun.RecordingStream`` it is given, so every
sink (viewer, web viewer, .rrd file, memory) gets the same entities and the same layout.

Cost model (rerun-sdk 0.41, measured on the 2-core reference machine; upstream, rerun-io/rerun#12602 reports
~40 µs per log call): one ``rr.log`` of a scalar costs ~20 µs, one
``send_columns`` call ~50–90 µs whatever its length, one Arrow record batch of several entities
~25 µs per entity. So scalars are never logged one by one: each topic appends rows to column
buffers, and :meth:`FlightLogger.flush` sends each topic's buffer as one record batch (the 3D
transforms, trail segments and markers with one ``send_columns`` each). High-rate topics are
decimated to ``plot_rate_hz`` per topic (one message per time bucket of 1/plot_rate_hz, so a 250 Hz
topic plotted at 50 Hz keeps every fifth message, exactly); the 3D pose, trails and setpoint marker
to ``pose_rate_hz``. Status topics are never decimated: each change becomes a text event. Only
instance 0 of each topic is drawn.

Time: ``sim_time`` is the message ``timestamp`` (µs) relative to ``time_origin_us`` — 0 in lockstep,
so it reads as simulated time; None takes the first message's timestamp (real-time stacks, whose
clock is CLOCK_MONOTONIC). ``wall_time`` is the receive time the caller passes, if any.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from typing import Any

import numpy as np
import pyarrow as pa
import rerun as rr

from stack.mathlib.quaternion import angle_between, to_euler
from stack.mathlib.vector import Vec3
from stack.msg.registry import ORB_ID
from stack.msg.system import RESULT_NAMES, VehicleCommandAck, VehicleStatus, command_label
from stack.msg.topic import Topic
from stack.viz import layout as lay
from stack.viz.geometry import GENERIC_QUAD_X, disc_radius, rotor_disc

DEG = 180.0 / math.pi
NAN = math.nan
INF = math.inf

DEFAULT_PLOT_RATE_HZ = 50.0
DEFAULT_POSE_RATE_HZ = 20.0
DEFAULT_FLUSH_PERIOD_S = 0.1

# The topics the logger draws; ground truth first, so that at equal timestamps the truth an estimate
# is compared with is already known when messages are fed in this order.
TOPICS: tuple[Topic, ...] = (
    ORB_ID.sim_groundtruth,
    ORB_ID.vehicle_attitude,
    ORB_ID.vehicle_attitude_setpoint,
    ORB_ID.vehicle_angular_velocity,
    ORB_ID.vehicle_rates_setpoint,
    ORB_ID.vehicle_torque_setpoint,
    ORB_ID.vehicle_thrust_setpoint,
    ORB_ID.actuator_motors,
    ORB_ID.actuator_outputs_sim,
    ORB_ID.control_allocator_status,
    ORB_ID.vehicle_local_position,
    ORB_ID.vehicle_local_position_setpoint,
    ORB_ID.trajectory_setpoint,
    ORB_ID.sensor_gps,
    ORB_ID.sensor_baro,
    ORB_ID.vehicle_status,
    ORB_ID.vehicle_command_ack,
    ORB_ID.home_position,
    ORB_ID.mission,
)
EVENT_TOPICS = frozenset({ORB_ID.vehicle_status, ORB_ID.vehicle_command_ack, ORB_ID.home_position, ORB_ID.mission})


def _names(cls: type, prefix: str) -> dict[int, str]:
    """Constant value → short name, from a message class's ``PREFIX_NAME = value`` attributes."""
    return {v: k.removeprefix(prefix) for k, v in vars(cls).items() if k.startswith(prefix) and isinstance(v, int)}


NAV_STATE_NAMES = _names(VehicleStatus, "NAVIGATION_STATE_")
ACK_OK = (VehicleCommandAck.VEHICLE_CMD_RESULT_ACCEPTED, VehicleCommandAck.VEHICLE_CMD_RESULT_IN_PROGRESS)


def new_recording(recording_id: str | None = None) -> rr.RecordingStream:
    """A recording stream for the flight plots: application ``stack`` (so the default blueprint
    applies), and no automatic ``log_time`` timeline (``wall_time`` replaces it).
    """
    rec = rr.RecordingStream(lay.APPLICATION_ID, recording_id=recording_id)
    rec.set_log_time_enabled(False)
    return rec


def _finite_or_nan(x: float) -> float:
    return x if -INF < x < INF else NAN


def _index_field(name: str, arrow_type: pa.DataType) -> pa.Field:
    return pa.field(name, arrow_type, nullable=False, metadata={"rerun:kind": "index", "rerun:index_name": name})


def _scalars_field(path: str) -> pa.Field:
    """An Arrow column that Rerun reads as the ``Scalars`` of entity ``path`` (what ``send_columns`` writes)."""
    metadata = {
        "rerun:kind": "data",
        "rerun:entity_path": path,
        "rerun:archetype": "rerun.archetypes.Scalars",
        "rerun:component": "Scalars:scalars",
        "rerun:component_type": "rerun.components.Scalar",
    }
    return pa.field(f"{path}:Scalars:scalars", pa.list_(pa.float64()), metadata=metadata)


SIM_TIME_FIELD = _index_field(lay.SIM_TIME, pa.duration("ns"))
WALL_TIME_FIELD = _index_field(lay.WALL_TIME, pa.timestamp("ns"))


class _Rows:
    """Buffered rows of one or more entities that share a time column: ``(t_us, wall_us | None, *values)``."""

    __slots__ = ("paths", "rows")

    def __init__(self, *paths: str) -> None:
        self.paths = paths
        self.rows: list[tuple] = []

    def take(self, origin_us: int) -> tuple[np.ndarray, np.ndarray | None, list[tuple]]:
        """The buffered rows as (sim_time ns, wall_time ns or None, value columns); empties the buffer."""
        cols = list(zip(*self.rows, strict=True))
        self.rows = []
        sim_ns = (np.array(cols[0], dtype=np.int64) - origin_us) * 1000
        walls = cols[1]
        wall_ns = None if None in walls else np.array(walls, dtype=np.int64) * 1000
        return sim_ns, wall_ns, cols[2:]

    def send(self, rec: rr.RecordingStream, origin_us: int) -> int:
        """Send the buffered rows; returns the number of entity chunks sent."""
        raise NotImplementedError


class _Batch(_Rows):
    """Scalar time series. All its entities go out as one Arrow record batch (one call, one chunk
    per entity), about half the cost of one ``send_columns`` per entity.
    """

    __slots__ = ("schemas",)

    def __init__(self, *paths: str) -> None:
        super().__init__(*paths)
        fields = [_scalars_field(p) for p in paths]
        self.schemas = (pa.schema([SIM_TIME_FIELD, *fields]), pa.schema([SIM_TIME_FIELD, WALL_TIME_FIELD, *fields]))

    def send(self, rec: rr.RecordingStream, origin_us: int) -> int:
        sim_ns, wall_ns, values = self.take(origin_us)
        arrays = [pa.array(sim_ns, pa.duration("ns"))]
        if wall_ns is not None:
            arrays.append(pa.array(wall_ns, pa.timestamp("ns")))
        for column in values:
            data = np.array(column, dtype=np.float64)
            width = data.shape[1] if data.ndim == 2 else 1
            offsets = np.arange(0, data.size + 1, width, dtype=np.int32)
            arrays.append(pa.ListArray.from_arrays(pa.array(offsets), pa.array(data.ravel())))
        rec.send_record_batch(pa.RecordBatch.from_arrays(arrays, schema=self.schemas[wall_ns is not None]))
        return len(self.paths)


def _time_columns(sim_ns: np.ndarray, wall_ns: np.ndarray | None) -> list[rr.TimeColumn]:
    indexes = [rr.TimeColumn(lay.SIM_TIME, duration=sim_ns.astype("timedelta64[ns]"))]
    if wall_ns is not None:
        indexes.append(rr.TimeColumn(lay.WALL_TIME, timestamp=wall_ns.astype("datetime64[ns]")))
    return indexes


class _PoseBatch(_Rows):
    """Vehicle transforms: rows ``(t, wall, x, y, z, qw, qx, qy, qz)``."""

    def send(self, rec: rr.RecordingStream, origin_us: int) -> int:
        sim_ns, wall_ns, values = self.take(origin_us)
        data = np.array(values, dtype=np.float64).T
        columns = rr.Transform3D.columns(translation=data[:, 0:3], quaternion=data[:, [4, 5, 6, 3]])
        rec.send_columns(self.paths[0], indexes=_time_columns(sim_ns, wall_ns), columns=columns)
        return 1


class _SegmentBatch(_Rows):
    """Trail segments: rows ``(t, wall, x0, y0, z0, x1, y1, z1)``, one line segment per row."""

    def send(self, rec: rr.RecordingStream, origin_us: int) -> int:
        sim_ns, wall_ns, values = self.take(origin_us)
        segments = np.array(values, dtype=np.float64).T.reshape(-1, 2, 3)
        columns = rr.LineStrips3D.columns(strips=list(segments))
        rec.send_columns(self.paths[0], indexes=_time_columns(sim_ns, wall_ns), columns=columns)
        return 1


class _MarkerBatch(_Rows):
    """A point that may be absent: rows ``(t, wall, x, y, z)``, NaN coordinates hide the point."""

    def send(self, rec: rr.RecordingStream, origin_us: int) -> int:
        sim_ns, wall_ns, values = self.take(origin_us)
        points = np.array(values, dtype=np.float64).T
        present = np.isfinite(points).all(axis=1)
        columns = rr.Points3D.columns(positions=points[present]).partition(present.astype(np.int32))
        rec.send_columns(self.paths[0], indexes=_time_columns(sim_ns, wall_ns), columns=columns)
        return 1


class _Topic:
    __slots__ = ("bucket", "handler", "period_us")

    def __init__(self, handler: Callable[[Any, int, int | None], None], period_us: int) -> None:
        self.handler = handler
        self.period_us = period_us
        self.bucket = -1


class FlightLogger:
    """Logs the stack's topics to a Rerun recording with the layout of :mod:`stack.viz.layout`.

    Parameters:

    - ``rec``: the recording stream to write to (see :func:`new_recording`); its sinks and blueprint
      are the caller's business.
    - ``plot_rate_hz`` (50, ≥ 0, Hz): the most rows per second a time series gets; 0 keeps every message.
    - ``pose_rate_hz`` (20, > 0, Hz): rate of the 3D pose, trails and setpoint marker (at most the
      plot rate, as they are drawn from the kept messages).
    - ``flush_period_s`` (0.1, ≥ 0, s of ``sim_time``): send the buffers whenever the data advanced by
      this much; 0 leaves flushing to the caller (the live bridge flushes on its wall-clock timer).
    - ``time_origin_us`` (0, µs, or None): the ``timestamp`` that is ``sim_time`` zero; None takes
      the first message's.
    - ``rotors``: rotor hub positions (body FRD, m), e.g. from
      :func:`stack.viz.geometry.rotors_from_params`; None draws a generic X quad. Their number is the
      number of motors plotted.
    """

    def __init__(
        self,
        rec: rr.RecordingStream,
        *,
        plot_rate_hz: float = DEFAULT_PLOT_RATE_HZ,
        pose_rate_hz: float = DEFAULT_POSE_RATE_HZ,
        flush_period_s: float = DEFAULT_FLUSH_PERIOD_S,
        time_origin_us: int | None = 0,
        rotors: Sequence[Vec3] | None = None,
    ) -> None:
        if plot_rate_hz < 0.0 or not pose_rate_hz > 0.0 or flush_period_s < 0.0:
            raise ValueError("plot_rate_hz and flush_period_s must be >= 0 and pose_rate_hz > 0")
        self.rec = rec
        self._origin = time_origin_us
        self._plot_period_us = round(1e6 / plot_rate_hz) if plot_rate_hz > 0.0 else 0
        self._pose_period_us = max(round(1e6 / pose_rate_hz), self._plot_period_us)
        self._flush_period_us = round(flush_period_s * 1e6)
        self._flushed_at = -1
        self._now = 0
        self._latest: dict[str, Any] = {}
        self._status: tuple[int, int, bool] | None = None
        self._home: Vec3 = (0.0, 0.0, 0.0)
        self._mission_offsets: list[Vec3] = []
        self._pose_bucket = -1
        self._trail_bucket = -1
        self._truth_trail_bucket = -1
        self._marker_bucket = -1
        self._trail_last: tuple[float, float, float] | None = None
        self._truth_trail_last: tuple[float, float, float] | None = None
        self.messages = 0
        self.kept = 0
        self.chunks_sent = 0
        self.flushes = 0
        self._topics: dict[str, _Topic] = {}
        for topic in TOPICS:
            handler = getattr(self, "_on_" + topic.name)
            self._topics[topic.name] = _Topic(handler, 0 if topic in EVENT_TOPICS else self._plot_period_us)
        self._build_batches()
        self.rotors: tuple[Vec3, ...] = ()
        self.set_rotors(rotors)
        colors = lay.SOURCE_COLORS
        rec.log(lay.WORLD, rr.ViewCoordinates.RIGHT_HAND_Z_DOWN, static=True)
        rec.log(
            lay.TRAIL_ESTIMATE, rr.LineStrips3D.from_fields(colors=[colors[lay.ESTIMATE]], radii=[0.02]), static=True
        )
        rec.log(lay.TRAIL_TRUTH, rr.LineStrips3D.from_fields(colors=[colors[lay.TRUTH]], radii=[0.015]), static=True)
        rec.log(lay.SETPOINT_MARKER, rr.Points3D.from_fields(colors=[colors[lay.SETPOINT]], radii=[0.08]), static=True)
        self.log_home(self._home)

    def _build_batches(self) -> None:
        def per_axis(path_of: Callable[[str, str], str], axes: tuple[str, ...], source: str) -> tuple[str, ...]:
            return tuple(path_of(axis, source) for axis in axes)

        est, sp, traj, truth = lay.ESTIMATE, lay.SETPOINT, lay.TRAJECTORY, lay.TRUTH
        self._att = _Batch(*per_axis(lay.attitude_path, lay.AXES, est))
        self._att_sp = _Batch(*per_axis(lay.attitude_path, lay.AXES, sp))
        self._rates = _Batch(*per_axis(lay.rates_path, lay.AXES, est))
        self._rates_sp = _Batch(*per_axis(lay.rates_path, lay.AXES, sp))
        self._truth = _Batch(
            *per_axis(lay.position_path, lay.NED, truth),
            *per_axis(lay.velocity_path, lay.NED, truth),
            *per_axis(lay.attitude_path, lay.AXES, truth),
            *per_axis(lay.rates_path, lay.AXES, truth),
        )
        self._torque = _Batch(lay.TORQUE)
        self._thrust = _Batch(lay.THRUST)
        self._motors = _Batch(lay.MOTOR_COMMANDS)
        self._outputs = _Batch(lay.MOTOR_OUTPUTS)
        self._allocator = _Batch(lay.UNALLOCATED_TORQUE, lay.MOTOR_SATURATION)
        self._lpos = _Batch(
            *per_axis(lay.position_path, lay.NED, est), *per_axis(lay.velocity_path, lay.NED, est), lay.ACCURACY
        )
        self._lpos_sp = _Batch(*per_axis(lay.position_path, lay.NED, sp), *per_axis(lay.velocity_path, lay.NED, sp))
        self._traj = _Batch(*per_axis(lay.position_path, lay.NED, traj), *per_axis(lay.velocity_path, lay.NED, traj))
        self._errors = _Batch(lay.POSITION_ERROR, lay.VELOCITY_ERROR)
        self._att_error = _Batch(lay.ATTITUDE_ERROR)
        self._gps = _Batch(lay.GPS_LATITUDE, lay.GPS_LONGITUDE, lay.GPS_ALTITUDE)
        self._baro = _Batch(lay.BARO_PRESSURE)
        self._pose = _PoseBatch(lay.VEHICLE)
        self._trail = _SegmentBatch(lay.TRAIL_ESTIMATE)
        self._truth_trail = _SegmentBatch(lay.TRAIL_TRUTH)
        self._marker = _MarkerBatch(lay.SETPOINT_MARKER)
        self._batches = [v for v in vars(self).values() if isinstance(v, _Rows)]

    # -- input -------------------------------------------------------------------------------------

    def period_us(self, topic: str) -> int:
        """The plot period of a topic: of its messages the logger draws the first in each period (0: all)."""
        return self._topics[topic].period_us

    def log_message(self, topic: str, instance: int, msg: Any, wall_time_us: int | None = None) -> bool:
        """Take one message; returns True if it was drawn (not decimated, not an unknown topic).

        ``wall_time_us``: when it was received, in µs since the UNIX epoch (the ``wall_time`` timeline).
        """
        self.messages += 1
        entry = self._topics.get(topic)
        if entry is None or instance != 0:
            return False
        t = msg.timestamp
        if self._origin is None:
            self._origin = t
        self._latest[topic] = msg
        if t > self._now:
            self._now = t
        period = entry.period_us
        if period:
            bucket = t // period
            if bucket == entry.bucket:
                return False
            entry.bucket = bucket
        entry.handler(msg, t, wall_time_us)
        self.kept += 1
        if self._flush_period_us and t - self._flushed_at >= self._flush_period_us:
            if self._flushed_at >= 0:
                self.flush()
            self._flushed_at = t
        return True

    def flush(self) -> None:
        """Send every buffered row (one chunk per entity with data)."""
        origin = self._origin or 0
        chunks = 0
        for batch in self._batches:
            if batch.rows:
                chunks += batch.send(self.rec, origin)
        if chunks:
            self.flushes += 1
            self.chunks_sent += chunks

    # -- scene -------------------------------------------------------------------------------------

    def set_rotors(self, rotors: Sequence[Vec3] | None) -> None:
        """Draw the vehicle with these rotor hubs (body FRD, m); None draws a generic X quad."""
        self.flush()
        self.rotors = tuple((float(p[0]), float(p[1]), float(p[2])) for p in (rotors or GENERIC_QUAD_X))
        rotors = self.rotors
        arm = max(math.hypot(p[0], p[1]) for p in rotors) or 0.25
        radius = disc_radius(rotors)
        front, back = (214, 39, 40), (90, 90, 90)
        rec = self.rec
        body = rr.Boxes3D(half_sizes=[(0.3 * arm, 0.2 * arm, 0.06 * arm)], colors=[(60, 60, 60)])
        arms = rr.LineStrips3D([[(0.0, 0.0, 0.0), p] for p in rotors], radii=[0.04 * arm], colors=[(120, 120, 120)])
        rec.log(lay.VEHICLE_BODY, body, static=True)
        rec.log(lay.VEHICLE_ARMS, arms, static=True)
        rec.log(
            lay.VEHICLE_ROTORS,
            rr.LineStrips3D(
                [rotor_disc(p, radius) for p in rotors],
                radii=[0.006],
                colors=[front if p[0] > 0.0 else back for p in rotors],
            ),
            static=True,
        )
        rec.log(lay.VEHICLE_FRONT, rr.Arrows3D(vectors=[(1.3 * arm, 0.0, 0.0)], colors=[front]), static=True)
        for path, style in lay.series_styles(len(rotors)):
            rec.log(path, style, static=True)

    def log_mission(self, waypoints: Sequence[Vec3], home: Vec3 | None = None) -> None:
        """Draw mission waypoints (local NED, m) as numbered points joined by the planned path, at the
        current ``sim_time``; with ``home``, also move the home marker and start the path there.
        """
        self._set_time_now()
        points = [tuple(p) for p in waypoints]
        self.rec.log(
            lay.MISSION_WAYPOINTS,
            rr.Points3D(points, labels=[str(i + 1) for i in range(len(points))], colors=[(255, 190, 0)], radii=[0.1]),
        )
        path = ([tuple(home)] if home is not None else []) + points
        strips = [path] if len(path) > 1 else []
        self.rec.log(lay.MISSION_PATH, rr.LineStrips3D(strips, colors=[(255, 190, 0)], radii=[0.01]))
        if home is not None:
            self.log_home(home)

    def log_home(self, home: Vec3) -> None:
        """Draw the home position (local NED, m) from the current ``sim_time`` on."""
        self._set_time_now()
        self.rec.log(lay.HOME, rr.Points3D([tuple(home)], labels=["home"], colors=[(0, 170, 0)], radii=[0.15]))

    def _set_time_now(self) -> None:
        origin = self._origin if self._origin is not None else self._now
        self.rec.reset_time()
        self.rec.set_time(lay.SIM_TIME, duration=np.timedelta64(max(self._now - origin, 0), "us"))

    def _event(self, t: int, wall: int | None, text: str, level: str) -> None:
        self.rec.reset_time()
        self.rec.set_time(lay.SIM_TIME, duration=np.timedelta64(t - (self._origin or 0), "us"))
        if wall is not None:
            self.rec.set_time(lay.WALL_TIME, timestamp=np.datetime64(wall, "us"))
        self.rec.log(lay.EVENTS, rr.TextLog(text, level=level))

    # -- topic handlers: (message, timestamp µs, wall µs | None) -------------------------------------

    def _on_sim_groundtruth(self, m: Any, t: int, w: int | None) -> None:
        p, v, q, r = m.position, m.velocity, m.q, m.angular_velocity
        roll, pitch, yaw = to_euler(q)
        self._truth.rows.append((t, w, *p, *v, roll * DEG, pitch * DEG, yaw * DEG, r[0] * DEG, r[1] * DEG, r[2] * DEG))
        bucket = t // self._pose_period_us
        if bucket != self._truth_trail_bucket:
            self._truth_trail_bucket = bucket
            last = self._truth_trail_last
            if last is not None:
                self._truth_trail.rows.append((t, w, *last, p[0], p[1], p[2]))
            self._truth_trail_last = (p[0], p[1], p[2])

    def _on_vehicle_attitude(self, m: Any, t: int, w: int | None) -> None:
        q = m.q
        roll, pitch, yaw = to_euler(q)
        self._att.rows.append((t, w, roll * DEG, pitch * DEG, yaw * DEG))
        truth = self._latest.get(ORB_ID.sim_groundtruth.name)
        if truth is not None:
            self._att_error.rows.append((t, w, angle_between(q, truth.q) * DEG))
        bucket = t // self._pose_period_us
        if bucket != self._pose_bucket:
            self._pose_bucket = bucket
            lpos = self._latest.get(ORB_ID.vehicle_local_position.name)
            x, y, z = (lpos.x, lpos.y, lpos.z) if lpos is not None else (0.0, 0.0, 0.0)
            self._pose.rows.append((t, w, x, y, z, q[0], q[1], q[2], q[3]))

    def _on_vehicle_attitude_setpoint(self, m: Any, t: int, w: int | None) -> None:
        roll, pitch, yaw = to_euler(m.q_d)
        self._att_sp.rows.append((t, w, roll * DEG, pitch * DEG, yaw * DEG))

    def _on_vehicle_angular_velocity(self, m: Any, t: int, w: int | None) -> None:
        r = m.xyz
        self._rates.rows.append((t, w, r[0] * DEG, r[1] * DEG, r[2] * DEG))

    def _on_vehicle_rates_setpoint(self, m: Any, t: int, w: int | None) -> None:
        self._rates_sp.rows.append((t, w, m.roll * DEG, m.pitch * DEG, m.yaw * DEG))

    def _on_vehicle_torque_setpoint(self, m: Any, t: int, w: int | None) -> None:
        self._torque.rows.append((t, w, m.xyz))

    def _on_vehicle_thrust_setpoint(self, m: Any, t: int, w: int | None) -> None:
        self._thrust.rows.append((t, w, m.xyz))

    def _on_actuator_motors(self, m: Any, t: int, w: int | None) -> None:
        self._motors.rows.append((t, w, m.control[: len(self.rotors)]))

    def _on_actuator_outputs_sim(self, m: Any, t: int, w: int | None) -> None:
        self._outputs.rows.append((t, w, m.output[: len(self.rotors)]))

    def _on_control_allocator_status(self, m: Any, t: int, w: int | None) -> None:
        self._allocator.rows.append((t, w, m.unallocated_torque, m.actuator_saturation[: len(self.rotors)]))

    def _on_vehicle_local_position(self, m: Any, t: int, w: int | None) -> None:
        x, y, z, vx, vy, vz = m.x, m.y, m.z, m.vx, m.vy, m.vz
        self._lpos.rows.append((t, w, x, y, z, vx, vy, vz, (_finite_or_nan(m.eph), _finite_or_nan(m.epv))))
        truth = self._latest.get(ORB_ID.sim_groundtruth.name)
        if truth is not None:
            p, v = truth.position, truth.velocity
            self._errors.rows.append((t, w, (x - p[0], y - p[1], z - p[2]), (vx - v[0], vy - v[1], vz - v[2])))
        bucket = t // self._pose_period_us
        if bucket != self._trail_bucket:
            self._trail_bucket = bucket
            last = self._trail_last
            if last is not None:
                self._trail.rows.append((t, w, *last, x, y, z))
            self._trail_last = (x, y, z)

    def _on_vehicle_local_position_setpoint(self, m: Any, t: int, w: int | None) -> None:
        self._lpos_sp.rows.append((t, w, m.x, m.y, m.z, m.vx, m.vy, m.vz))

    def _on_trajectory_setpoint(self, m: Any, t: int, w: int | None) -> None:
        p, v = m.position, m.velocity
        self._traj.rows.append((t, w, p[0], p[1], p[2], v[0], v[1], v[2]))
        bucket = t // self._pose_period_us
        if bucket != self._marker_bucket:
            self._marker_bucket = bucket
            self._marker.rows.append((t, w, p[0], p[1], p[2]))

    def _on_sensor_gps(self, m: Any, t: int, w: int | None) -> None:
        self._gps.rows.append((t, w, m.latitude_deg, m.longitude_deg, m.altitude_msl_m))

    def _on_sensor_baro(self, m: Any, t: int, w: int | None) -> None:
        self._baro.rows.append((t, w, m.pressure))

    def _on_vehicle_status(self, m: Any, t: int, w: int | None) -> None:
        state = (m.nav_state, m.arming_state, m.failsafe)
        previous = self._status
        if state == previous:
            return
        self._status = state
        mode = NAV_STATE_NAMES.get(m.nav_state, str(m.nav_state))
        armed = m.arming_state == VehicleStatus.ARMING_STATE_ARMED
        if previous is None:
            self._event(t, w, f"mode {mode}, {'armed' if armed else 'disarmed'}", "INFO")
            if m.failsafe:
                self._event(t, w, "failsafe active", "ERROR")
            return
        if m.nav_state != previous[0]:
            self._event(t, w, f"mode {NAV_STATE_NAMES.get(previous[0], str(previous[0]))} -> {mode}", "INFO")
        if m.arming_state != previous[1]:
            self._event(t, w, "armed" if armed else "disarmed", "WARN" if armed else "INFO")
        if m.failsafe != previous[2]:
            text = f"failsafe {'active' if m.failsafe else 'cleared'} (mode {mode})"
            self._event(t, w, text, "ERROR" if m.failsafe else "INFO")

    def _on_vehicle_command_ack(self, m: Any, t: int, w: int | None) -> None:
        result = RESULT_NAMES.get(m.result, str(m.result))
        text = f"command {command_label(m.command)}: {result}" + (f", {m.reason}" if m.reason else "")
        self._event(t, w, text, "INFO" if m.result in ACK_OK else "WARN")

    def _on_home_position(self, m: Any, t: int, w: int | None) -> None:
        home = (m.x, m.y, m.z)
        if m.valid_lpos and home != self._home:
            self._home = home
            self.log_home(home)
            if self._mission_offsets:
                self._log_mission_about_home()

    def _on_mission(self, m: Any, t: int, w: int | None) -> None:
        # Items are about home; one without a position (a takeoff or land where the vehicle is) is not drawn.
        self._mission_offsets = [
            (i.north, i.east, i.down) for i in m.items if math.isfinite(i.north) and math.isfinite(i.east)
        ]
        self._log_mission_about_home()

    def _log_mission_about_home(self) -> None:
        hx, hy, hz = self._home
        waypoints = [(hx + n, hy + e, hz + (d if math.isfinite(d) else 0.0)) for n, e, d in self._mission_offsets]
        self.log_mission(waypoints, home=self._home)
