"""The CLI against a running stack from another process: topics, parameters, status."""

import json
import os
import re
import signal

import pytest

from stack.bus.ports import free_port
from tests.support.harness import RunningStack, chain_profile, cli_in_its_own_session, run_cli, wait_no_processes


@pytest.fixture(scope="module")
def stack(tmp_path_factory):
    tmp = tmp_path_factory.mktemp("cli")
    home = tmp / "home"
    running = RunningStack(home, chain_profile(tmp / "chain.toml", lockstep=False))
    running.wait_up()
    yield running
    assert running.stop() == 0
    assert not wait_no_processes(home)


def test_topic_list_shows_types_publishers_subscribers_rates(stack):
    out = stack.cli("topic", "list", "--json")
    assert out.returncode == 0, out.stderr
    rows = {r["topic"]: r for r in json.loads(out.stdout)}
    gyro = rows["sensor_gyro"]
    assert gyro["type"] == "SensorGyro" and gyro["instance"] == 0
    assert gyro["publishers"] == ["tick_source"] and gyro["subscribers"] == ["doubler"]
    assert 200 < gyro["rate_hz"] < 300 and gyro["size_bytes"] > 20
    assert rows["vehicle_rates_setpoint"]["subscribers"] == ["doubler", "summer"]
    assert 40 < rows["vehicle_rates_setpoint"]["rate_hz"] < 60
    table = stack.cli("topic", "list").stdout
    assert "TOPIC" in table and "RATE" in table and "sensor_gyro" in table


def test_topic_echo_prints_n_messages(stack):
    out = stack.cli("topic", "echo", "vehicle_angular_velocity", "-n", "3", "--json")
    assert out.returncode == 0, out.stderr
    msgs = [json.loads(line) for line in out.stdout.splitlines()]
    assert len(msgs) == 3 and all(len(m["xyz"]) == 3 for m in msgs)
    text = stack.cli("topic", "echo", "sensor_gyro", "-n", "1").stdout
    assert text.startswith("TOPIC: sensor_gyro instance 0 #1  [SensorGyro]") and "timestamp_sample:" in text
    field = stack.cli("topic", "echo", "sensor_gyro", "-n", "2", "--field", "z")
    assert len(field.stdout.splitlines()) == 2
    bad = stack.cli("topic", "echo", "sensor_gyro", "--field", "w")
    assert bad.returncode == 1 and "has no field 'w'" in bad.stderr
    silent = stack.cli("topic", "echo", "vehicle_command", "--timeout", "0.5")
    assert silent.returncode == 1 and "without a message" in silent.stderr


def test_topic_hz_measures_rate(stack):
    out = stack.cli("topic", "hz", "sensor_gyro", "--duration", "3.5", "--json")
    assert out.returncode == 0, out.stderr
    reports = [json.loads(line) for line in out.stdout.splitlines()]
    assert len(reports) >= 2
    assert 200 < reports[-1]["rate_hz"] < 300
    assert 230 < reports[-1]["rate_by_timestamp_hz"] < 270
    assert reports[-1]["min_s"] <= reports[-1]["max_s"]


def test_topic_pub_checks_the_schema_and_publishes(stack):
    bad = stack.cli("topic", "pub", "vehicle_command", '{"command": 400, "parm1": 1}')
    assert bad.returncode == 2 and "unknown field `parm1`" in bad.stderr and "published" not in bad.stdout
    wrong = stack.cli("topic", "pub", "vehicle_command", '{"command": "arm"}')
    assert wrong.returncode == 2 and "Expected `int`, got `str`" in wrong.stderr
    ok = stack.cli("topic", "pub", "vehicle_rates_setpoint", '{"roll": 100.0, "pitch": 0.0}', "-r", "50", "-n", "10")
    assert ok.returncode == 0 and ok.stdout.splitlines() == [
        "publishing VehicleRatesSetpoint on vehicle_rates_setpoint (instance 0) at 50 Hz, 10 messages",
        "published 10 messages on vehicle_rates_setpoint",
    ]
    # A module's own output is not a tool's to publish (stack.bus.access): refused, naming who publishes it.
    owned = stack.cli("topic", "pub", "sensor_gyro", '{"x": 1.0}')
    assert owned.returncode == 2 and "published" not in owned.stdout
    assert owned.stderr.startswith("error: sensor_gyro is a topic of the vehicle's modules (published by tick_source)")


def test_ctrl_c_ends_a_publishing_stream_saying_what_was_sent(stack):
    stream = cli_in_its_own_session(stack.home, "topic", "pub", "vehicle_rates_setpoint", '{"roll": 0.1}', "-r", "20")
    assert stream.stdout is not None
    try:
        first = stream.stdout.readline()
        said = "publishing VehicleRatesSetpoint on vehicle_rates_setpoint (instance 0) at 20 Hz, until Ctrl-C\n"
        assert first == said
        os.killpg(stream.pid, signal.SIGINT)
        out, err = stream.communicate(timeout=30)
    finally:
        stream.kill()  # never left publishing if the test fails
        stream.wait()
    assert stream.returncode == 0 and "Traceback" not in err, err
    assert re.fullmatch(r"published \d+ messages? on vehicle_rates_setpoint\n", out), out


def test_topic_info_gives_the_schema(stack):
    out = stack.cli("topic", "info", "vehicle_torque_setpoint", "--json")
    info = json.loads(out.stdout)
    assert info["type"] == "VehicleTorqueSetpoint" and len(info["fingerprint"]) == 16
    assert [f["name"] for f in info["fields"]] == ["timestamp", "timestamp_sample", "xyz"]
    assert info["instances"][0]["publishers"] == ["summer"]
    assert stack.cli("topic", "info", "no_topic").returncode == 1


def test_parameters_change_while_running_and_the_module_sees_it(stack):
    listing = json.loads(stack.cli("param", "list", "--json").stdout)
    assert {(p["name"], *p["owners"]) for p in listing} == {("TEST_GAIN", "tick_source"), ("TEST_OFFSET", "doubler")}
    assert stack.cli("param", "get", "TEST_OFFSET").stdout.splitlines()[0] == "TEST_OFFSET = 0.0  (doubler)"
    refused = stack.cli("param", "set", "TEST_OFFSET", "1000")
    assert refused.returncode == 1 and "above the maximum 100" in refused.stderr
    assert stack.cli("param", "set", "TEST_OFFSET", "not-a-number").returncode == 1
    assert stack.cli("param", "set", "NO_SUCH", "1").returncode == 1
    changed = stack.cli("param", "set", "TEST_OFFSET", "50")
    assert changed.returncode == 0 and "TEST_OFFSET: 0.0 -> 50.0  (doubler)" in changed.stdout
    stack.wait_for(r"\[doubler\] INFO\s+parameters changed: TEST_OFFSET=50.0")  # its next outputs have it
    xs = [
        json.loads(v)[0]
        for v in stack.cli(
            "topic", "echo", "vehicle_angular_velocity", "-n", "5", "-f", "xyz", "--json"
        ).stdout.splitlines()
    ]
    assert all(x > 45 for x in xs)
    assert json.loads(stack.cli("param", "get", "TEST_OFFSET", "--json").stdout)["value"] == 50.0


def test_an_unreachable_endpoint_is_one_line_not_a_traceback(tmp_path):
    endpoint = f"tcp/127.0.0.1:{free_port()}"  # nobody listens there
    out = run_cli(tmp_path / "home", "topic", "list", "--endpoint", endpoint)
    assert out.returncode == 1
    assert out.stderr.startswith(f"error: cannot reach the stack at {endpoint}")
    assert "Traceback" not in out.stderr and len(out.stderr.strip().splitlines()) == 1
