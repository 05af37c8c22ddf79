"""Entity paths, series styles and the default blueprint of the flight plots.

The layout follows what a pilot looks at (PX4 Flight Review's plot set, arranged for a live view):
the vehicle in 3D with its status events on the left; on the right, tabs of time series — attitude
and body rates against their setpoints, control outputs, motors, position and velocity against
their setpoints and the simulator's truth, estimator errors and raw sensors. One time series view
per axis, each showing every source of that quantity (estimate, setpoint, trajectory, truth).

Timelines: ``sim_time`` (the stack's clock from message timestamps: simulated time in lockstep) and
``wall_time`` (when the data was received or recorded).

Imports Rerun: only the bridge process and the exporter load this module.
"""

from __future__ import annotations

from collections.abc import Callable

import rerun as rr
import rerun.blueprint as rrb

APPLICATION_ID = "stack"
SIM_TIME = "sim_time"
WALL_TIME = "wall_time"
DEFAULT_WINDOW_S = 30.0

AXES = ("roll", "pitch", "yaw")
NED = ("north", "east", "down")
XYZ = ("x", "y", "z")

# Sources of one quantity, in the order the legend lists them.
ESTIMATE = "estimate"
SETPOINT = "setpoint"
TRAJECTORY = "trajectory"
TRUTH = "truth"
SOURCE_COLORS: dict[str, tuple[int, int, int]] = {
    ESTIMATE: (31, 119, 180),
    SETPOINT: (255, 127, 14),
    TRAJECTORY: (148, 103, 189),
    TRUTH: (44, 160, 44),
}
XYZ_COLORS = ((214, 39, 40), (44, 160, 44), (31, 119, 180))
PALETTE = (
    (31, 119, 180),
    (255, 127, 14),
    (44, 160, 44),
    (214, 39, 40),
    (148, 103, 189),
    (140, 86, 75),
    (227, 119, 194),
    (127, 127, 127),
    (188, 189, 34),
    (23, 190, 207),
    (0, 0, 0),
    (255, 215, 0),
)

# -- entity paths ----------------------------------------------------------------------------------

WORLD = "/world"
VEHICLE = "/world/vehicle"
VEHICLE_BODY = "/world/vehicle/body"
VEHICLE_ARMS = "/world/vehicle/arms"
VEHICLE_ROTORS = "/world/vehicle/rotors"
VEHICLE_FRONT = "/world/vehicle/front"
TRAIL = "/world/trail"
TRAIL_ESTIMATE = "/world/trail/estimate"
TRAIL_TRUTH = "/world/trail/truth"
SETPOINT_MARKER = "/world/setpoint"
MISSION_WAYPOINTS = "/world/mission/waypoints"
MISSION_PATH = "/world/mission/path"
HOME = "/world/home"
EVENTS = "/events"

TORQUE = "/control/torque"
THRUST = "/control/thrust"
UNALLOCATED_TORQUE = "/control/unallocated_torque"
MOTOR_COMMANDS = "/motors/command"
MOTOR_OUTPUTS = "/motors/output"
MOTOR_SATURATION = "/motors/saturation"
POSITION_ERROR = "/estimator/position_error"
VELOCITY_ERROR = "/estimator/velocity_error"
ATTITUDE_ERROR = "/estimator/attitude_error"
ACCURACY = "/estimator/accuracy"
GPS_LATITUDE = "/sensors/gps/latitude"
GPS_LONGITUDE = "/sensors/gps/longitude"
GPS_ALTITUDE = "/sensors/gps/altitude"
BARO_PRESSURE = "/sensors/baro/pressure"


def attitude_path(axis: str, source: str) -> str:
    """Roll, pitch or yaw angle [deg]."""
    return f"/attitude/{axis}/{source}"


def rates_path(axis: str, source: str) -> str:
    """Body rate about the roll, pitch or yaw axis [deg/s]."""
    return f"/rates/{axis}/{source}"


def position_path(axis: str, source: str) -> str:
    """Local NED position component [m]."""
    return f"/position/{axis}/{source}"


def velocity_path(axis: str, source: str) -> str:
    """Local NED velocity component [m/s]."""
    return f"/velocity/{axis}/{source}"


# -- styles ----------------------------------------------------------------------------------------


def series_styles(motor_count: int) -> list[tuple[str, rr.SeriesLines]]:
    """The static line style (colour, legend name) of every time series the logger writes."""
    styles: list[tuple[str, rr.SeriesLines]] = []

    def sources(path_of: Callable[[str, str], str], axes: tuple[str, ...], which: tuple[str, ...]) -> None:
        for axis in axes:
            for source in which:
                styles.append((path_of(axis, source), rr.SeriesLines(colors=[SOURCE_COLORS[source]], names=[source])))

    sources(attitude_path, AXES, (ESTIMATE, SETPOINT, TRUTH))
    sources(rates_path, AXES, (ESTIMATE, SETPOINT, TRUTH))
    sources(position_path, NED, (ESTIMATE, SETPOINT, TRAJECTORY, TRUTH))
    sources(velocity_path, NED, (ESTIMATE, SETPOINT, TRAJECTORY, TRUTH))
    xyz = rr.SeriesLines(colors=list(XYZ_COLORS), names=list(XYZ))
    ned = rr.SeriesLines(colors=list(XYZ_COLORS), names=list(NED))
    for path in (TORQUE, THRUST, UNALLOCATED_TORQUE):
        styles.append((path, xyz))
    styles.append((POSITION_ERROR, ned))
    styles.append((VELOCITY_ERROR, ned))
    motors = rr.SeriesLines(
        colors=[PALETTE[i % len(PALETTE)] for i in range(motor_count)],
        names=[f"motor {i + 1}" for i in range(motor_count)],
    )
    for path in (MOTOR_COMMANDS, MOTOR_OUTPUTS, MOTOR_SATURATION):
        styles.append((path, motors))
    styles.append((ATTITUDE_ERROR, rr.SeriesLines(colors=[PALETTE[3]], names=["rotation angle"])))
    styles.append((ACCURACY, rr.SeriesLines(colors=[PALETTE[0], PALETTE[1]], names=["eph", "epv"])))
    for path, name in (
        (GPS_LATITUDE, "latitude"),
        (GPS_LONGITUDE, "longitude"),
        (GPS_ALTITUDE, "altitude MSL"),
        (BARO_PRESSURE, "pressure"),
    ):
        styles.append((path, rr.SeriesLines(colors=[PALETTE[0]], names=[name])))
    return styles


# -- blueprint -------------------------------------------------------------------------------------


def _series(origin: str, name: str, window: rrb.VisibleTimeRange | None) -> rrb.TimeSeriesView:
    return rrb.TimeSeriesView(origin=origin, name=name, time_ranges=window)


def _tab(name: str, window: rrb.VisibleTimeRange | None, *views: tuple[str, str]) -> rrb.Vertical:
    """A tab of stacked time series views, each given as (origin, title)."""
    return rrb.Vertical(*(_series(origin, title, window) for origin, title in views), name=name)


def default_blueprint(window_s: float | None = DEFAULT_WINDOW_S) -> rrb.Blueprint:
    """The default layout.

    ``window_s``: the time series show the last N seconds of ``sim_time`` up to the time cursor (a
    scrolling window while live); None shows the whole flight. The trails always show the whole
    flight up to the cursor.
    """
    window = None
    if window_s is not None:
        window = rrb.VisibleTimeRange(
            SIM_TIME,
            start=rrb.TimeRangeBoundary.cursor_relative(seconds=-window_s),
            end=rrb.TimeRangeBoundary.cursor_relative(),
        )
    up_to_cursor = rrb.VisibleTimeRanges(
        timeline=SIM_TIME, start=rrb.TimeRangeBoundary.infinite(), end=rrb.TimeRangeBoundary.cursor_relative()
    )
    scene = rrb.Spatial3DView(
        origin=WORLD, name="vehicle (NED)", overrides={TRAIL_ESTIMATE: up_to_cursor, TRAIL_TRUTH: up_to_cursor}
    )
    status = rrb.TextLogView(origin=EVENTS, name="status")
    plots = rrb.Tabs(
        _tab("attitude", window, *((f"/attitude/{a}", f"{a} [deg]") for a in AXES)),
        _tab("rates", window, *((f"/rates/{a}", f"{a} rate [deg/s]") for a in AXES)),
        _tab(
            "control",
            window,
            (TORQUE, "torque setpoint [normalised]"),
            (THRUST, "thrust setpoint [normalised]"),
            (UNALLOCATED_TORQUE, "unallocated torque (mixer saturation)"),
        ),
        _tab(
            "motors",
            window,
            (MOTOR_COMMANDS, "motor commands"),
            (MOTOR_OUTPUTS, "motor outputs (simulator) [0, 1]"),
            (MOTOR_SATURATION, "motor saturation (+2 upper, -2 lower)"),
        ),
        _tab("position", window, *((f"/position/{a}", f"{a} [m]") for a in NED)),
        _tab("velocity", window, *((f"/velocity/{a}", f"v {a} [m/s]") for a in NED)),
        _tab(
            "estimator",
            window,
            (POSITION_ERROR, "position error, estimate - truth [m]"),
            (VELOCITY_ERROR, "velocity error, estimate - truth [m/s]"),
            (ATTITUDE_ERROR, "attitude error, estimate vs truth [deg]"),
            (ACCURACY, "reported accuracy [m]"),
        ),
        _tab(
            "sensors",
            window,
            (GPS_LATITUDE, "GPS latitude [deg]"),
            (GPS_LONGITUDE, "GPS longitude [deg]"),
            (GPS_ALTITUDE, "GPS altitude MSL [m]"),
            (BARO_PRESSURE, "barometer [Pa]"),
        ),
        name="plots",
    )
    return rrb.Blueprint(
        rrb.Horizontal(rrb.Vertical(scene, status, row_shares=[3, 1]), plots, column_shares=[2, 3]),
        rrb.TimePanel(timeline=SIM_TIME),
    )
