"""Flying scenarios, through the real CLI (``stack fly``: every module its own process) or in one process
(:mod:`stack.scenario.inprocess`: the same flight, message for message), and reading what they published."""

from __future__ import annotations

import json
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import msgspec

from stack.bus.node import stable_publisher_id
from stack.msg.registry import message_type
from stack.record.recorder import RecordedMessage, RecordingReader
from stack.runtime.membus import PublishedMessage
from stack.scenario.inprocess import fly_in_process
from tests.support.harness import refused_in_logs, run_cli, wait_no_processes

# Generous: a flight takes 10-30 s of wall time, several times that on a loaded machine.
FLY_TIMEOUT_S = 600.0
# attitude_step's limits (stack/scenario/attitude_step.py), restated so that a profile relaxing them fails: 10°
# steps rise (10–90 %) within 80 ms in roll and pitch and 200 ms
# in yaw, overshoot at most 10 %, and the attitude estimate stays within 1° RMS of the truth.
ATTITUDE_STEP_TARGETS = {
    "roll_rise_time_s": 0.08,
    "roll_overshoot_pct": 10.0,
    "pitch_rise_time_s": 0.08,
    "pitch_overshoot_pct": 10.0,
    "yaw_rise_time_s": 0.20,
    "yaw_overshoot_pct": 10.0,
    "attitude_est_error_rms_deg": 1.0,
}


@dataclass(frozen=True)
class Flight:
    returncode: int
    output: str
    report: dict
    recording: Path

    def messages(self, *topics: str) -> list[RecordedMessage]:
        with RecordingReader(self.recording) as reader:
            return list(reader.iter_messages(topics))

    def scenario_end_us(self) -> int:
        """The simulated time of the scenario's last tick (it publishes a setpoint on every tick).

        Every message stamped up to then was produced by a complete lockstep step, so it is
        deterministic; afterwards the supervisor stops the modules on the wall clock.
        """
        scenario = stable_publisher_id(self.report.get("vehicle", "v1"), "scenario")
        return [m for m in self.messages("vehicle_attitude_setpoint") if m.publisher_id == scenario][-1].pub_time_us


def fly_scenario(
    home: Path,
    scenario: str,
    seed: int,
    profile: str = "sitl_quad",
    wind: bool = False,
    transport: str = "shm",
    record: bool = True,
) -> Flight:
    """``stack fly SCENARIO --profile PROFILE --seed SEED [--wind] --lockstep-transport TRANSPORT`` with a
    report and (``record``) a recording, in STACK_HOME ``home``."""
    report, recording = home / "report.json", home / "flight.mcap"
    out = run_cli(
        home,
        *("fly", scenario, "--profile", profile, "--seed", str(seed), "--quiet"),
        *("--report", str(report), "--lockstep-transport", transport),
        *(["--record", str(recording)] if record else []),
        *(["--wind"] if wind else []),
        timeout=FLY_TIMEOUT_S,
    )
    output = out.stdout + out.stderr
    assert wait_no_processes(home) == [], f"module processes outlived the flight:\n{output}"
    assert not refused_in_logs(home), refused_in_logs(home)
    assert report.exists(), f"no report (exit code {out.returncode}):\n{output}"
    assert recording.exists() or not record, f"no recording:\n{output}"
    return Flight(out.returncode, output, json.loads(report.read_text()), recording)


class InProcessMessage(msgspec.Struct, frozen=True):
    topic: str
    instance: int
    publisher_id: int
    pub_time_us: int
    msg: Any


@dataclass(frozen=True)
class InProcessFlight:
    """A scenario flown in one process: the scenario's result (``report``: its metrics, checks, ``passed`` and
    ``error``, as in ``stack fly``'s report) and every message published (``published``, a msgpack file)."""

    report: dict
    published: Path

    def messages(self, *topics: str) -> list[InProcessMessage]:
        """The published messages of ``topics`` (all when none), decoded, in publication order."""
        raw = msgspec.msgpack.decode(self.published.read_bytes(), type=list[PublishedMessage])
        return [
            InProcessMessage(m.topic, m.instance, m.publisher_id, m.pub_time_us,
                             msgspec.msgpack.decode(m.payload, type=message_type(m.topic)))
            for m in raw
            if not topics or m.topic in topics
        ]


def fly_inprocess(
    directory: Path, scenario: str, seed: int, profile: str = "sitl_quad", wind: bool = False
) -> InProcessFlight:
    """The scenario flown in this process, its messages written to ``directory``."""
    flight = fly_in_process(scenario, profile, seed, wind=wind, record=True)
    assert not flight.refused, f"the stack's own messages were refused: {flight.refused}"
    published = directory / "published.msgpack"
    published.write_bytes(msgspec.msgpack.encode(flight.published))
    report = {**flight.result, "scenario": scenario, "profile": profile, "seed": seed, "wind": wind}
    return InProcessFlight(report, published)
