"""The scenario module on a bench, flying a small scenario of the test's own: what it reads and publishes, how it
steps the script on its clock, records data and acknowledgements, and how it judges the flight and writes the
result (the script API itself: stack/scenario/script.py; the real scenarios fly in the other tests here)."""

import json
import math

import pytest

from stack.msg.estimation import VehicleLocalPosition
from stack.msg.registry import ORB_ID
from stack.msg.setpoints import TrajectorySetpoint
from stack.msg.system import VehicleCommand, VehicleCommandAck, VehicleStatus
from stack.scenario import module as scenario_module
from stack.scenario.catalogue import Check, Scenario
from stack.scenario.module import ScenarioModule
from tests.support.bench import ModuleBench

DT = 0.01  # the module's 100 Hz timer
ARM = VehicleCommand.VEHICLE_CMD_COMPONENT_ARM_DISARM


def script(ctx):
    ctx.log("started")
    yield ctx.wait(0.03)
    ctx.publish(ORB_ID.trajectory_setpoint, TrajectorySetpoint(position=(0.0, 0.0, -2.0)))
    yield from ctx.command(ARM, param1=1)
    yield ctx.until(lambda: ctx.latest.get(ORB_ID.vehicle_status) is not None, timeout=0.5, what="a status")
    ctx.state["pid"] = ctx.pid("commander")


def evaluate(ctx):
    series = ctx.series[ORB_ID.vehicle_local_position]
    return {"samples": len(series.values), "first_t_s": series.times[0], "nothing": math.nan}


FLIGHT = Scenario(
    name="bench_flight",
    description="arm, then wait for a status",
    script=script,
    evaluate=evaluate,
    checks=(Check("samples", 3, at_least=True), Check("first_t_s", 1.0)),
    record=(ORB_ID.vehicle_local_position,),
    watch=(ORB_ID.vehicle_status,),
    publish=(ORB_ID.trajectory_setpoint,),
    timeout_s=0.5,
    options={"speed": "slow", "size": "small"},
)


@pytest.fixture
def flight(monkeypatch, tmp_path):
    """A bench flying FLIGHT (or the scenario given), writing its result to tmp_path."""

    def make(scenario=FLIGHT, **args):
        monkeypatch.setattr(scenario_module, "get_scenario", lambda name: {scenario.name: scenario}[name])
        return ModuleBench(ScenarioModule, args={"name": scenario.name, "result": str(tmp_path / "r.json"), **args})

    return make


def result(tmp_path) -> dict:
    return json.loads((tmp_path / "r.json").read_text())


def fly_until_the_command(bench: ModuleBench) -> None:
    for _ in range(4):
        bench.run(None, DT)


def ack(result=VehicleCommandAck.VEHICLE_CMD_RESULT_ACCEPTED, reason="") -> VehicleCommandAck:
    return VehicleCommandAck(command=ARM, result=result, reason=reason)


def test_reads_what_the_scenario_records_and_watches_and_publishes_commands_and_its_setpoints(flight):
    bench = flight()
    assert set(bench.inputs) == {
        (t.name, 0) for t in (ORB_ID.vehicle_local_position, ORB_ID.vehicle_status, ORB_ID.vehicle_command_ack)
    }
    assert set(bench.outputs) == {(ORB_ID.vehicle_command.name, 0), (ORB_ID.trajectory_setpoint.name, 0)}


def test_the_script_acts_at_its_times_and_a_passing_flight_writes_its_result(flight, tmp_path):
    bench = flight()
    bench.module_changed("commander", 4242, True)
    bench.module_changed("commander", 1, False)  # another instance's death: the running one stays
    for k in range(3):
        bench.put(ORB_ID.vehicle_local_position, VehicleLocalPosition(timestamp_sample=10_000 * k + 5_000, z=-k))
    fly_until_the_command(bench)  # the wait of 0.03 s from the first run (t = 0.01) ends at t = 0.04
    assert [m.timestamp for m in bench.sent(ORB_ID.trajectory_setpoint)] == [40_000]
    (command,) = bench.sent(ORB_ID.vehicle_command)
    assert (command.command, command.param1, command.from_external) == (ARM, 1.0, True)
    bench.put(ORB_ID.vehicle_command_ack, ack())
    bench.run(None, DT)  # acknowledged: now waiting for a status
    bench.put(ORB_ID.vehicle_local_position, VehicleLocalPosition(timestamp=60_000))  # no timestamp_sample
    bench.put(ORB_ID.vehicle_status, VehicleStatus(arming_state=2))
    with pytest.raises(SystemExit) as stop:
        bench.run(None, DT)
    assert stop.value.code == 0
    ctx = bench.module.ctx
    assert ctx.series[ORB_ID.vehicle_local_position].times == pytest.approx([0.005, 0.015, 0.025, 0.06])
    assert ctx.latest[ORB_ID.vehicle_status].arming_state == 2 and ctx.state["pid"] == 4242
    got = result(tmp_path)
    assert got["scenario"] == "bench_flight" and got["passed"] and got["error"] is None
    assert got["sim_time_s"] == pytest.approx(0.05)
    assert got["metrics"] == {"samples": 4, "first_t_s": 0.005, "nothing": None}  # NaN written as null
    assert got["checks"] == [
        {"name": "samples", "value": 4, "limit": 3, "passed": True},
        {"name": "first_t_s", "value": 0.005, "limit": 1.0, "passed": True},
    ]


def test_limits_given_as_arguments_replace_the_scenarios(flight, tmp_path):
    bench = flight(limits='{"samples": 10}')
    bench.put(ORB_ID.vehicle_local_position, VehicleLocalPosition(timestamp_sample=5_000))
    fly_until_the_command(bench)
    bench.put(ORB_ID.vehicle_command_ack, ack())
    bench.put(ORB_ID.vehicle_status, VehicleStatus())
    with pytest.raises(SystemExit):
        bench.run(None, DT)
    got = result(tmp_path)
    assert not got["passed"] and got["error"] is None
    assert [(c["name"], c["limit"], c["passed"]) for c in got["checks"]] == [
        ("samples", 10, False), ("first_t_s", 1.0, True)
    ]


def test_a_refused_command_fails_the_flight_with_the_reason_and_every_check(flight, tmp_path):
    bench = flight()
    fly_until_the_command(bench)
    bench.put(ORB_ID.vehicle_command_ack, ack(VehicleCommandAck.VEHICLE_CMD_RESULT_DENIED, "preflight checks"))
    with pytest.raises(SystemExit):
        bench.run(None, DT)
    got = result(tmp_path)
    assert not got["passed"] and got["metrics"] == {}
    assert got["error"].startswith("command ") and got["error"].endswith("refused (DENIED): preflight checks")
    assert [c["passed"] for c in got["checks"]] == [False, False]


def test_a_flight_not_over_within_the_scenarios_timeout_fails(flight, tmp_path):
    slow = Scenario(name="slow", description="", script=lambda ctx: iter([ctx.wait(10.0)]),
                    evaluate=lambda ctx: {}, checks=(), timeout_s=0.1)
    bench = flight(slow)
    for _ in range(11):
        bench.run(None, DT)  # up to 0.1 s after the first run: on time
    with pytest.raises(SystemExit):
        bench.run(None, DT)  # 0.11 s after it
    got = result(tmp_path)
    assert got["error"] == "the scenario did not finish within 0.1 s" and not got["passed"]


def test_the_scenarios_options_are_its_defaults_overridden_by_the_arguments(flight):
    assert flight(options='{"size": "large"}').module.ctx.options == {"speed": "slow", "size": "large"}


def test_malformed_limits_or_options_are_refused(flight):
    with pytest.raises(json.JSONDecodeError):
        flight(limits="{not json")
    with pytest.raises(json.JSONDecodeError):
        flight(options="[1,")
    with pytest.raises(ValueError, match="limits: a JSON object is wanted"):
        flight(limits="[1]")
    with pytest.raises(ValueError, match="options: a JSON object is wanted"):
        flight(options='"fast"')
    with pytest.raises(ValueError, match="limits: samples must be finite numbers or true/false"):
        flight(limits='{"samples": "ten"}')


def test_an_unknown_scenario_is_refused_with_the_catalogues_message():
    with pytest.raises(KeyError, match="no_such_flight"):
        ModuleBench(ScenarioModule, args={"name": "no_such_flight"})
