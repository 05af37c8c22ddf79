"""The scenario module: runs a flight script against the stack over the bus and judges the flight.

``stack fly`` adds it to a profile. It is an ordinary lockstep member on a 100 Hz timer (so the
script acts at exact simulated times and runs are deterministic); it records what the scenario
needs, steps the script, and when the script ends computes the metrics and writes the result file.
"""

from __future__ import annotations

import json
import math
import time
from collections.abc import Mapping
from pathlib import Path
from typing import TYPE_CHECKING, Any

from stack.bus import keys
from stack.msg.registry import ORB_ID
from stack.msg.topic import Topic
from stack.params.param import ParamValue
from stack.runtime.module import Arg, Module, Timer
from stack.scenario.catalogue import get_scenario
from stack.scenario.script import ScenarioError, ScriptContext
from stack.scenario.swarm_track import swarm_role, swarm_track

if TYPE_CHECKING:
    from stack.runtime.runner import Runtime


class ScenarioModule(Module):
    NAME = "scenario"
    DESCRIPTION = "Runs a scripted flight over the bus and writes its metrics"
    TRIGGER = Timer(100.0)
    ARGS = (
        Arg("name", "", "Scenario to fly (see `stack fly --list`)"),
        Arg("result", "", "Where to write the result JSON"),
        Arg("limits", "{}", 'JSON object overriding check limits, e.g. {"yaw_rise_time_s": 0.3}'),
        Arg("options", "{}", 'JSON object choosing the scenario\'s options, e.g. {"mission": "c172_rectangle"}'),
        Arg("swarm", "", 'A vehicle of a swarm flight: {"slot": 1, "vehicles": ["v1", "v2"], "spacing_m": 5.0}'),
    )
    PUBLISHES = (ORB_ID.vehicle_command,)

    @classmethod
    def publishes(cls, args: Mapping[str, ParamValue]) -> frozenset[str]:
        """Commands, and what its scenario's script publishes (an unknown scenario: commands only; the module
        refuses it as it starts)."""
        try:
            script = get_scenario(str(args.get("name", ""))).publish
        except KeyError:
            script = ()
        return super().publishes(args) | {t.name for t in script}

    def __init__(self, rt: Runtime) -> None:
        super().__init__(rt)
        self.scenario = get_scenario(str(self.args["name"]))
        self.limits = _json_object("limits", str(self.args["limits"]))
        bad = [name for name, value in self.limits.items() if not _is_limit(value)]
        if bad:
            raise ValueError(f"limits: {', '.join(sorted(bad))} must be finite numbers or true/false")
        for topic in self.scenario.record + self.scenario.watch:
            self.subscribe(topic, queue=topic in self.scenario.record)
        self.subscribe(ORB_ID.vehicle_command_ack, queue=True)
        for topic in (*self.PUBLISHES, *self.scenario.publish):
            self.advertise(topic)
        self._pids: dict[str, int] = {}
        self.watch_modules(self._on_module)
        self.role = swarm_role(str(self.args["swarm"])) if self.args["swarm"] else None
        self.ctx = ScriptContext(self.publish, lambda: self.now_us() * 1e-6, lambda: dict(self._pids), self.role)
        self.ctx.end_flight = self._end_now
        self.peers: tuple[Topic, ...] = ()
        if self.role is not None:
            if self.scenario.swarm is None:
                raise ValueError(f"scenario {self.scenario.name} flies one vehicle, not a swarm")
            if not self.role.leads:
                self.peers = self.scenario.swarm.peers
            for topic in self.peers:
                self.subscribe_peer(self.role.leader, topic, self.scenario.swarm.peer_delay_s)
        self.ctx.options = {**self.scenario.options, **_json_object("options", str(self.args["options"]))}
        self.script = self.scenario.script(self.ctx)
        self.waiting = None
        self.started_wall: float | None = None
        self.started_sim = 0.0

    def _on_module(self, module: str, pid: int, alive: bool) -> None:
        if alive:
            self._pids[module] = pid
        elif self._pids.get(module) == pid:
            del self._pids[module]

    def run(self, msg: None, dt: float) -> None:
        if self.started_wall is None:
            self.started_wall = time.monotonic()
            self.started_sim = self.ctx.now
        self._take_data()
        for hook in self.ctx.tick_hooks:
            hook()
        try:
            while self.waiting is None or self.waiting():
                self.waiting = next(self.script)
        except StopIteration:
            self._finish(None)
        except ScenarioError as e:
            self._finish(str(e))
        if self.ctx.now - self.started_sim > self.scenario.timeout_s:
            self._finish(f"the scenario did not finish within {self.scenario.timeout_s:g} s")

    def _take_data(self) -> None:
        ctx = self.ctx
        for topic in self.scenario.record:
            for m in self.take(topic):
                ctx.record(topic, getattr(m, "timestamp_sample", 0) * 1e-6 or m.timestamp * 1e-6, m)
                ctx.latest[topic] = m
        for topic in self.scenario.watch:
            m = self.latest(topic)
            if m is not None:
                ctx.latest[topic] = m
        ctx.take_acks(self.take(ORB_ID.vehicle_command_ack))
        self._say_events()
        if self.role is not None:
            for topic in self.peers:
                heard = self.peer(self.role.leader, topic)
                if heard is not None:
                    ctx.leader[topic] = heard

    def _say_events(self) -> None:
        for t, text in self.ctx.events:
            self.log.info("t=%.2f s: %s", t, text)
        self.ctx.events.clear()

    def _end_now(self) -> None:
        """The result as it stands, written before the flight ends abruptly (ScriptContext.kill_stack)."""
        self._say_events()
        self._write(self._result(None))

    def _finish(self, error: str | None) -> None:
        self._say_events()
        result = self._result(error)
        self._write(result)
        self.log.info("scenario %s %s", self.scenario.name, "passed" if result["passed"] else "FAILED")
        raise SystemExit(0)

    def _result(self, error: str | None) -> dict[str, Any]:
        wall = time.monotonic() - (self.started_wall or time.monotonic())
        sim = self.ctx.now - self.started_sim
        metrics: dict[str, object] = {}
        if error is None:
            try:
                metrics = self.scenario.evaluate(self.ctx)
            except ScenarioError as e:
                error = str(e)
        checks = []
        for check in self.scenario.checks:
            limit = self.limits.get(check.metric, check.limit)
            value = metrics.get(check.metric)
            ok = error is None and type(check)(check.metric, limit, check.at_least).passed(value)
            checks.append({"name": check.metric, "value": _plain(value), "limit": limit, "passed": ok})
        result = {
            "scenario": self.scenario.name,
            "passed": error is None and all(c["passed"] for c in checks),
            "error": error,
            "sim_time_s": sim,
            "wall_time_s": wall,
            "realtime_factor": sim / wall if wall > 0 else math.nan,
            "metrics": {k: _plain(v) for k, v in metrics.items()},
            "checks": checks,
        }
        if self.role is not None:
            result["track"] = swarm_track(self.ctx)
        return result

    def _write(self, result: dict[str, Any]) -> None:
        text = json.dumps(result, indent=2)
        if self.args["result"]:
            Path(str(self.args["result"])).write_text(text)
        if self.role is not None:  # for the launchers of a swarm spread over machines
            self.rt.node.session.put(keys.scenario_result_key(self.rt.spec.vehicle), text)


def _plain(value: object) -> object:
    if isinstance(value, float) and not math.isfinite(value):
        return None
    return value


def _json_object(arg: str, text: str) -> dict[str, Any]:
    """``text`` as a JSON object; ValueError (json.JSONDecodeError for bad JSON) naming ``arg`` otherwise."""
    value = json.loads(text)
    if not isinstance(value, dict):
        raise ValueError(f"{arg}: a JSON object is wanted, not {text!r}")
    return value


def _is_limit(value: object) -> bool:
    """A check's limit: a finite number, or a flag the metric must equal."""
    return isinstance(value, bool) or (isinstance(value, int | float) and math.isfinite(value))
