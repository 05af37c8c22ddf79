"""rerun_bridge: live Rerun plots of a running stack, as one more (passive) module.

It never holds the stack back: it is PASSIVE (outside the lockstep, on the wall clock). On the
same-host fast path (:mod:`stack.fastpath`) it reads the rings of the topics it draws directly, and a
ring that laps it costs it its oldest samples, never the stack any time. Over Zenoh its subscriptions
are drop-oldest ring buffers filled by Zenoh's own threads, so a slow Python side loses its oldest
samples instead of filling a queue that would block lockstep publishers (they use blocking congestion
control). It subscribes only to the topics it draws, since every subscriber costs each publisher one
more send; its CPU use still competes with the stack's (see benchmarks/bench_viz.py).

Every tick (25 Hz wall, often enough to read the fast path's rings before they wrap at ten times real
time) it takes what arrived and feeds it to :class:`stack.viz.logger.FlightLogger` in timestamp
order; every fifth tick (5 Hz, the latency of Rerun's own batching) it flushes the batches: the flush
costs ~25 µs per entity, so its rate, not the message rate, sets most of the bridge's Python CPU. A
buffer found full is reported as an overrun. The ``wall_time`` of a sample is the tick that took it
(40 ms resolution). The vehicle is drawn with
the rotor geometry of whichever module serves ``CA_ROTOR*`` parameters, asked once at start.

Rerun is imported when the module is built, so processes that only read the module's declaration
(the supervisor, the CLI) never pay its ~0.5 s and ~90 MB.
"""

from __future__ import annotations

import json
import threading
import time
from operator import itemgetter
from pathlib import Path
from typing import TYPE_CHECKING, Any

import zenoh

from stack.bus import keys
from stack.runtime.inputs import InputBuffer
from stack.runtime.module import Arg, Module, Timer
from stack.viz.display import DEFAULT_GRPC_PORT, has_display

if TYPE_CHECKING:
    from stack.runtime.runner import Runtime

OVERRUN_LOG_EVERY = 100
FLUSH_EVERY_TICKS = 5


def wall_time_us() -> int:
    """Now, in µs since the UNIX epoch (the plots' ``wall_time`` timeline)."""
    return time.time_ns() // 1000


def query_rotors(session: zenoh.Session, vehicle: str) -> tuple[tuple[float, float, float], ...] | None:
    """Rotor hub positions from whichever module of the stack serves the ``CA_ROTOR*`` parameters."""
    from stack.viz.geometry import rotors_from_params

    replies = session.get(
        keys.param_all(vehicle),
        payload=json.dumps({"op": "list"}),
        consolidation=zenoh.ConsolidationMode.NONE,
        target=zenoh.QueryTarget.ALL,
        timeout=1.0,
    )
    by_module: dict[str, dict[str, object]] = {}
    for reply in replies:
        if reply.ok is None:
            continue
        answer = json.loads(reply.ok.payload.to_string())
        values = by_module.setdefault(str(answer.get("module", "")), {})
        values.update((p["name"], p["value"]) for p in answer.get("params", []))  # a module's list comes in pieces
    for values in by_module.values():
        rotors = rotors_from_params(values)
        if rotors is not None:
            return rotors
    return None


class RerunBridgeModule(Module):
    NAME = "rerun_bridge"
    DESCRIPTION = "Live Rerun plots: attitude, rates, control, motors, position, estimator, sensors, 3D view"
    PASSIVE = True
    TRIGGER = Timer(25.0)
    ARGS = (
        Arg("spawn", True, "Open the native Rerun viewer when a display exists (ignored with web)"),
        Arg("web", False, "Serve the Rerun web viewer and log its URL"),
        Arg("save", "", "Also write the plots to this .rrd file"),
        Arg("bind", "127.0.0.1", "Address the viewer servers listen on (loopback unless you choose otherwise)"),
        Arg("grpc_port", DEFAULT_GRPC_PORT, "Port of the viewer's data server (0: any free port)"),
        Arg("web_port", 9090, "Port of the web viewer page (0: any free port)"),
        Arg("plot_rate_hz", 50.0, "Most rows per second per plotted topic (0: every message)"),
        Arg("pose_rate_hz", 20.0, "Rate of the 3D pose, trails and setpoint marker"),
        Arg("window_s", 30.0, "Seconds of data the time series show (0: the whole flight)"),
        Arg("queue", 4096, "Per-topic ring buffer in messages; when full the oldest are dropped"),
    )

    def __init__(self, rt: Runtime) -> None:
        super().__init__(rt)
        from stack.viz.layout import default_blueprint
        from stack.viz.logger import TOPICS, FlightLogger, new_recording
        from stack.viz.viewer import PlotSinks

        args = self.args
        self.capacity = int(args["queue"])
        if self.capacity < 16 or float(args["plot_rate_hz"]) < 0.0 or float(args["window_s"]) < 0.0:
            raise ValueError("rerun_bridge: queue must be >= 16, plot_rate_hz and window_s >= 0")
        spawn = bool(args["spawn"]) and not args["web"]
        if spawn and not has_display():
            self.log.warning("no display: not opening a viewer (use web or save)")
            spawn = False
        window = float(args["window_s"]) or None
        run_name = Path(rt.spec.run_dir).name if rt.spec.run_dir else time.strftime("%Y%m%d-%H%M%S")
        rec = new_recording(f"{rt.spec.vehicle}-{run_name}")
        self.sinks = PlotSinks(
            rec,
            default_blueprint(window),
            save=str(args["save"]),
            web=bool(args["web"]),
            spawn=spawn,
            bind=str(args["bind"]),
            grpc_port=int(args["grpc_port"]),
            web_port=int(args["web_port"]),
        )
        self.topics = TOPICS
        self.logger: Any = None
        self.overruns = 0
        self.lost = 0  # samples overwritten in the fast path's rings before the bridge read them
        self._rotors: tuple[tuple[float, float, float], ...] | None = None
        self._asking: threading.Thread | None = None
        if not self.sinks.active:
            self.log.warning("nothing to plot to: no viewer, no web viewer, no file; the bridge stays idle")
            return
        if self.sinks.web_url:
            self.show_link("web viewer", self.sinks.web_url)
        elif self.sinks.viewer_url:
            self.log.info("streaming to the viewer at %s", self.sinks.viewer_url)
        if args["save"]:
            self.log.info("saving plots to %s", args["save"])
        self.logger = FlightLogger(
            rec,
            plot_rate_hz=float(args["plot_rate_hz"]),
            pose_rate_hz=float(args["pose_rate_hz"]),
            flush_period_s=0.0,
            time_origin_us=0 if rt.spec.lockstep else None,
        )
        node = rt.node
        for topic in TOPICS:
            if rt.fast is not None:
                self.subscribe(topic, queue=True, capacity=self.capacity)
                # The rings are read directly: skip what the logger would drop without decoding it.
                rt.inputs[(topic.name, 0)].every_us = self.logger.period_us(topic.name)
            else:
                sub = node.subscriber(topic.name, capacity=self.capacity, keep_last=True)
                rt.inputs[(topic.name, 0)] = InputBuffer(sub, True)
        self._ticks = 0
        # Asked beside the plotting (the answer can take a second; the flight's data must not wait).
        self._asking = threading.Thread(target=self._ask_rotors, name="rotor-query", daemon=True)
        self._asking.start()

    def _ask_rotors(self) -> None:
        self._rotors = query_rotors(self.rt.node.session, self.rt.node.vehicle)

    def run(self, msg: None, dt: float) -> None:
        if self.logger is None:
            return
        if self._asking is not None and not self._asking.is_alive():
            self._asking = None
            if self._rotors is not None:
                self.logger.set_rotors(self._rotors)
        self._feed()
        self._ticks += 1
        if self._ticks % FLUSH_EVERY_TICKS == 0:
            self.logger.flush()

    def _feed(self) -> None:
        """Log everything taken from the buffers since the last tick, oldest first."""
        pending: list[tuple[int, str, Any]] = []
        lost = sum(self.rt.inputs[(topic.name, 0)].lost for topic in self.topics)
        if lost > self.lost:
            self.log.warning("fell behind the flight: %d samples lost before they were read", lost - self.lost)
            self.lost = lost
        for topic in self.topics:
            msgs = self.take(topic)
            if not msgs:
                continue
            if len(msgs) >= self.capacity:
                self.overruns += 1
                if self.overruns % OVERRUN_LOG_EVERY == 1:
                    self.log.warning(
                        "%s: ring buffer of %d full, oldest samples dropped (%d overruns so far)",
                        topic.name,
                        self.capacity,
                        self.overruns,
                    )
            pending.extend((m.timestamp, topic.name, m) for m in msgs)
        pending.sort(key=itemgetter(0))
        wall = wall_time_us()
        log_message = self.logger.log_message
        for _, topic, m in pending:
            log_message(topic, 0, m, wall)

    def status(self) -> dict[str, float | int | str | bool]:
        """The plots' figures for the heartbeat (``stack status``): what was drawn and what fell behind."""
        lg = self.logger
        return {
            "plotted": lg.kept if lg is not None else 0,
            "messages": lg.messages if lg is not None else 0,
            "overruns": self.overruns,
            "lost": self.lost,
        }

    def close(self) -> None:
        if self.logger is not None:
            for topic in self.topics:
                self.rt.inputs[(topic.name, 0)].take_in_everything()
            self._feed()
            self.logger.flush()
            lg = self.logger
            self.log.info(
                "plotted %d of %d messages in %d flushes (%d entity chunks); %d buffer overruns, %d samples lost",
                lg.kept,
                lg.messages,
                lg.flushes,
                lg.chunks_sent,
                self.overruns,
                self.lost,
            )
        self.sinks.close()
