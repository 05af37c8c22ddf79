"""``stack plot --all``: every vehicle on the bus in one Rerun view (stack.viz.swarm_logger), live.

It reads each vehicle's local position, status and battery as a tool of its own on the bus (its subscriptions
announced, so a fast-path run puts those topics on Zenoh for it), looks for vehicles coming onto the bus every
second, and draws what arrived ten times a second, until Ctrl-C, SIGTERM or ``--duration``.
"""

from __future__ import annotations

import os
import time
from contextlib import ExitStack
from typing import Any

import typer

from stack.bus.alive import vehicles_alive
from stack.bus.node import Node
from stack.bus.topics import TopicSubscriber
from stack.cli.common import bus_configs, open_bus
from stack.msg.registry import ORB_ID
from stack.viz.logger import new_recording
from stack.viz.swarm_logger import SwarmLogger, swarm_blueprint
from stack.viz.viewer import PlotSinks

DRAW_PERIOD_S = 0.1
LOOK_PERIOD_S = 1.0
QUEUE = 1024


def plot_swarm(endpoint: str | None, sinks_args: dict[str, Any], window_s: float | None) -> None:
    """Draw every vehicle of the buses a command on every vehicle addresses until stopped (a Shutdown)."""
    tool = f"plot-{os.getpid()}"
    rec = new_recording(f"swarm-{time.strftime('%Y%m%d-%H%M%S')}")
    with ExitStack() as stack:
        sessions = []
        for bus in bus_configs(endpoint):
            session = open_bus(bus, tool)
            stack.callback(session.close)
            sessions.append((bus, session))
        sinks = PlotSinks(rec, swarm_blueprint(window_s), **sinks_args)
        stack.callback(sinks.close)
        if sinks.web_url:
            typer.echo(f"web viewer: {sinks.web_url}")
        logger = SwarmLogger(rec)
        watched: dict[str, list[TopicSubscriber]] = {}
        looked = 0.0
        while True:
            if time.monotonic() - looked > LOOK_PERIOD_S:
                looked = time.monotonic()
                for bus, session in sessions:
                    for vehicle in sorted(vehicles_alive(session, timeout=0.5) - set(watched)):
                        node = stack.enter_context(Node(bus, vehicle, tool, stable_id=False, session=session))
                        watched[vehicle] = [
                            node.subscriber(t.name, callback=True, capacity=QUEUE)
                            for t in (ORB_ID.vehicle_local_position, ORB_ID.vehicle_status, ORB_ID.battery_status)
                        ]
                        typer.echo(f"plotting {vehicle}")
            for vehicle, (position, status, battery) in watched.items():
                while (got := position.poll()) is not None:
                    logger.log_position(vehicle, got.msg)
                while (got := status.poll()) is not None:
                    logger.log_status(vehicle, got.msg)
                while (got := battery.poll()) is not None:
                    logger.log_battery(vehicle, got.msg)
            time.sleep(DRAW_PERIOD_S)
