"""MAVSDK-Python 4 (the MAVSDK C++ core in-process) flies the default lockstep stack over its API link, end to end:
connect, health and ``is_armable``, telemetry, parameters (a float and an integer), arm, takeoff, goto, a
4-waypoint mission with a speed to completion (MISSION_CURRENT's mission_state), return, land, disarm.

MAVSDK's waits are wall-clock ones; the lockstep simulation runs several times faster, so the timeouts below are
generous margins, not flight times. The test process opens no Zenoh session: it reads the stack through the CLI.
"""

from __future__ import annotations

import asyncio
import math
from collections.abc import AsyncIterator, Callable, Iterator
from typing import Any, TypeVar

import pytest
from mavsdk.asyncio import Autopilot, ComponentType, Configuration, Mavsdk
from mavsdk.asyncio.plugins.action import ActionAsync
from mavsdk.asyncio.plugins.mission import MissionAsync
from mavsdk.asyncio.plugins.param import ParamAsync
from mavsdk.asyncio.plugins.telemetry import TelemetryAsync
from mavsdk.plugins.mission import MissionItem, MissionPlan
from mavsdk.plugins.telemetry import FlightMode

from stack.mathlib.geo import MapProjection
from tests.mavlink.peer import Link, links_profile, udp_port
from tests.support.harness import RunningStack, wait_no_processes

T = TypeVar("T")
SQUARE_M = 20.0
MISSION_SPEED = 4.0


@pytest.fixture(scope="module")
def stack(tmp_path_factory: pytest.TempPathFactory) -> Iterator[tuple[RunningStack, int]]:
    home = tmp_path_factory.mktemp("mavsdk")
    api = Link("mavlink_api", udp_port(), udp_port())
    running = RunningStack(home, links_profile(home / "mavsdk.toml", [api]), "--quiet")
    try:
        running.wait_up(120)
        yield running, api.remote
    finally:
        code = running.stop()
    assert code == 0, running.output
    assert "Traceback" not in running.output
    assert not wait_no_processes(home)


async def until(stream: AsyncIterator[T], check: Callable[[T], bool], timeout: float, what: str) -> T:
    async def first() -> T:
        async for value in stream:
            if check(value):
                return value
        raise AssertionError(f"{what}: the stream ended")

    try:
        return await asyncio.wait_for(first(), timeout)
    except TimeoutError:
        raise AssertionError(f"{what}: not within {timeout:g} s") from None


def offset(origin: Any, north: float, east: float) -> tuple[float, float]:
    return MapProjection(origin.latitude_deg, origin.longitude_deg).reproject(north, east)


def distance(origin: Any, position: Any) -> float:
    north, east = MapProjection(origin.latitude_deg, origin.longitude_deg).project(
        position.latitude_deg, position.longitude_deg
    )
    return math.hypot(north, east)


async def fly(port: int, cli: Callable[..., Any]) -> None:
    mavsdk = Mavsdk(Configuration.create_with_component_type(ComponentType.GROUND_STATION))
    try:
        await mavsdk.add_any_connection(f"udpin://127.0.0.1:{port}")
        system = await mavsdk.first_autopilot(30.0)
        assert system is not None, "no autopilot heard"
        assert await system.autopilot_type() == Autopilot.PX4
        telemetry, action = TelemetryAsync(system), ActionAsync(system)
        mission, params = MissionAsync(system), ParamAsync(system)

        health = await until(
            telemetry.subscribe_health(),
            lambda h: h.is_armable and h.is_global_position_ok and h.is_home_position_ok,
            60.0,
            "armable, with a position and a home",
        )
        assert health.is_gyrometer_calibration_ok and health.is_accelerometer_calibration_ok
        home = await until(telemetry.subscribe_home(), lambda h: True, 10.0, "home")
        assert home.latitude_deg == pytest.approx(47.397742, abs=1e-4)
        position = await until(telemetry.subscribe_position(), lambda p: True, 10.0, "position")
        assert distance(home, position) < 1.0 and abs(position.relative_altitude_m) < 0.5
        attitude = await until(telemetry.subscribe_attitude_euler(), lambda a: True, 10.0, "attitude")
        assert abs(attitude.roll_deg) < 5.0 and abs(attitude.pitch_deg) < 5.0
        battery = await until(telemetry.subscribe_battery(), lambda b: True, 10.0, "battery")
        assert battery.remaining_percent > 50.0 and battery.voltage_v > 10.0
        assert not await until(telemetry.subscribe_in_air(), lambda a: True, 10.0, "in air")

        assert await params.get_param_float("MPC_XY_CRUISE") == pytest.approx(5.0)
        await params.set_param_float("MPC_XY_CRUISE", 6.0)
        assert await params.get_param_float("MPC_XY_CRUISE") == pytest.approx(6.0)
        assert await params.get_param_int("COM_DL_LOSS_T") == 10
        await params.set_param_int("COM_DL_LOSS_T", 12)
        assert await params.get_param_int("COM_DL_LOSS_T") == 12
        assert "MPC_XY_CRUISE = 6.0" in cli("param", "get", "MPC_XY_CRUISE")
        assert "COM_DL_LOSS_T = 12" in cli("param", "get", "COM_DL_LOSS_T")

        await action.arm()
        await action.set_takeoff_altitude(5.0)
        await action.takeoff()
        await until(telemetry.subscribe_position(), lambda p: p.relative_altitude_m > 4.0, 60.0, "takeoff")
        await until(telemetry.subscribe_flight_mode(), lambda m: m == FlightMode.HOLD, 30.0, "hold after takeoff")

        lat, lon = offset(home, 15.0, 0.0)
        await action.goto_location(lat, lon, home.absolute_altitude_m + 6.0, 90.0)
        await until(
            telemetry.subscribe_position(),
            lambda p: distance(home, p) > 13.5 and abs(p.relative_altitude_m - 6.0) < 1.0,
            60.0,
            "goto",
        )

        corners = [(SQUARE_M, 0.0), (SQUARE_M, SQUARE_M), (0.0, SQUARE_M), (0.0, 0.0)]
        items = []
        for north, east in corners:
            lat, lon = offset(home, north, east)
            items.append(
                MissionItem(
                    latitude_deg=lat,
                    longitude_deg=lon,
                    relative_altitude_m=6.0,
                    speed_m_s=MISSION_SPEED,
                    is_fly_through=True,
                    acceptance_radius_m=1.0,
                )
            )
        await mission.set_return_to_launch_after_mission(False)
        await mission.upload_mission(MissionPlan(items))
        downloaded = (await mission.download_mission()).mission_items
        assert len(downloaded) == 4
        for back, sent in zip(downloaded, items, strict=True):
            assert (back.latitude_deg, back.longitude_deg) == pytest.approx((sent.latitude_deg, sent.longitude_deg))
        assert downloaded[0].speed_m_s == pytest.approx(MISSION_SPEED)
        await mission.start_mission()
        await until(telemetry.subscribe_flight_mode(), lambda m: m == FlightMode.MISSION, 30.0, "mission mode")
        seen: list[int] = []

        def done(p: Any) -> bool:
            seen.append(p.current)
            return p.total == 4 and p.current == 4

        await until(mission.subscribe_mission_progress(), done, 120.0, "mission progress to 4/4")
        assert await mission.is_mission_finished()
        assert seen[-1] == 4 and seen == sorted(seen)
        position = await until(telemetry.subscribe_position(), lambda p: True, 10.0, "position")
        assert distance(home, position) < 3.0  # the last corner is home

        await action.set_return_to_launch_altitude(10.0)
        await action.return_to_launch()
        await until(telemetry.subscribe_flight_mode(), lambda m: m == FlightMode.RETURN_TO_LAUNCH, 30.0, "return mode")
        await action.land()
        await until(telemetry.subscribe_flight_mode(), lambda m: m == FlightMode.LAND, 30.0, "land mode")
        await until(telemetry.subscribe_in_air(), lambda in_air: not in_air, 120.0, "landed")
        await action.disarm()  # the land detector may have disarmed already: then the disarm is a no-op
        await until(telemetry.subscribe_armed(), lambda armed: not armed, 30.0, "disarmed")
        position = await until(telemetry.subscribe_position(), lambda p: True, 10.0, "position")
        assert distance(home, position) < 3.0
    finally:
        mavsdk.destroy()


def test_mavsdk_flies_the_stack_end_to_end(stack: tuple[RunningStack, int]) -> None:
    running, port = stack

    def cli(*args: str) -> str:
        out = running.cli(*args)
        assert out.returncode == 0, out.stderr
        return out.stdout

    asyncio.run(fly(port, cli))
    modules = {m["module"]: m for m in running.status()["modules"]}
    api = modules["mavlink_api"]["extra"]
    assert api["handler_errors"] == 0 and api["command_timeouts"] == 0 and api["mission_uploads"] == 1
    assert modules["mc_pos_control"]["rejected"] == 0 and modules["mavlink_api"]["restarts"] == 0
