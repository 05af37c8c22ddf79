"""`stack topic echo` and `pub` against a running stack (the test chain, in real time): --rate, several
--field paths, a slow reader's drops counted, and a publication on every topic of the registry."""

import fcntl
import itertools
import json
import struct
import subprocess
import sys
import termios
import time
from typing import IO

import pytest

from stack.cli.topic import schema_rows
from stack.msg.registry import TOPICS
from tests.cli.test_message_json import example
from tests.support.harness import REPO, RunningStack, chain_profile, eventually, stack_env, wait_no_processes

GYRO_HZ = 250


@pytest.fixture(scope="module")
def stack(tmp_path_factory):
    tmp = tmp_path_factory.mktemp("topic")
    running = RunningStack(tmp / "home", chain_profile(tmp / "chain.toml", lockstep=False), "--quiet")
    running.wait_up()
    yield running
    assert running.stop() == 0
    assert not wait_no_processes(tmp / "home")


PIPE_CAPACITY = 65536  # Linux's default


def unread(pipe: IO[str]) -> int:
    """Bytes written to the pipe and not read yet."""
    return struct.unpack("i", fcntl.ioctl(pipe.fileno(), termios.FIONREAD, b"\0\0\0\0"))[0]


def background_cli(stack: RunningStack, *args: str) -> subprocess.Popen[str]:
    return subprocess.Popen(
        [sys.executable, "-m", "stack", *args],
        env=stack_env(stack.home),
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        cwd=REPO,
    )


def test_echo_rate_prints_at_most_that_many_messages_a_second(stack):
    out = stack.cli("topic", "echo", "sensor_gyro", "-n", "4", "--rate", "2", "--field", "timestamp")
    assert out.returncode == 0, out.stderr
    stamps = [int(line) for line in out.stdout.splitlines()]
    # 250 messages a second arrive; one every 0.5 s is shown (the stack runs on the wall clock).
    assert len(stamps) == 4 and all(b - a > 0.25e6 for a, b in itertools.pairwise(stamps))
    bad = stack.cli("topic", "echo", "sensor_gyro", "--rate", "-1")
    assert bad.returncode == 2
    assert "Invalid value for '--rate' / '-r': -1 is not a finite number in the range x>=0." in bad.stderr


def test_echo_several_fields(stack):
    out = stack.cli("topic", "echo", "sensor_gyro", "-n", "2", "--field", "x,y", "-f", "clip_counter.2", "--json")
    assert out.returncode == 0, out.stderr
    for line in out.stdout.splitlines():
        row = json.loads(line)
        assert list(row) == ["x", "y", "clip_counter.2"] and row["y"] == pytest.approx(2.0 * row["x"])
    text = stack.cli("topic", "echo", "sensor_gyro", "-n", "1", "-f", "x", "-f", "samples").stdout
    assert text.startswith("x: ") and text.strip().endswith("samples: 1")
    deep = stack.cli("topic", "echo", "sensor_gyro", "-n", "1", "-f", "clip_counter.3")
    assert deep.returncode == 1 and deep.stderr.strip() == "error: SensorGyro: 'clip_counter.3': index must be 0…2"


def test_a_slow_reader_loses_the_oldest_messages_and_is_told(stack):
    echo = background_cli(stack, "topic", "echo", "sensor_gyro", "--queue", "10", "-n", "500")
    try:
        # Nobody reads its output: the pipe fills and the printer blocks; then the 250 Hz gyro overflows the queue
        # of 10 within 0.1 s.
        eventually(lambda: unread(echo.stdout) >= PIPE_CAPACITY - 4096, what="a full pipe")
        time.sleep(0.5)
        first = echo.stdout.readline()
        _, err = echo.communicate(timeout=60)  # then it reads on until the echo has shown its 500 and ends
    finally:
        echo.kill()
    assert first.startswith("TOPIC: sensor_gyro instance 0 #1")
    drops = [line for line in err.splitlines() if line.endswith("sensor_gyro messages dropped: output too slow]")]
    assert drops, err
    summary = [line for line in err.splitlines() if line.startswith("sensor_gyro: ") and "dropped" in line]
    assert len(summary) == 1 and summary[0].endswith(" dropped (output too slow)"), err
    dropped = int(summary[0].split(", ")[1].split()[0])
    assert dropped >= sum(int(line[1:].split()[0]) for line in drops) > 0


# Every topic's JSON parsing is tested in-process (tests/cli/test_message_json.py); these run the whole
# command on a plain struct, one with fixed arrays and one with a list of structs.
PUB_TOPICS = ("vehicle_command", "actuator_motors", "mission")


@pytest.mark.parametrize("topic", sorted(TOPICS))
def test_every_topics_schema_is_json(topic):
    """`stack topic info --json` shows each field's default, a required field's as null."""
    rows = schema_rows(TOPICS[topic].type)
    assert json.loads(json.dumps(rows, allow_nan=False)) == rows
    assert [row["name"] for row in rows] == list(TOPICS[topic].type.__struct_fields__)


def test_pub_runs_on_a_live_stack(stack):
    before = len(stack.subscribers("mission"))
    listener = background_cli(stack, "topic", "echo", "mission", "-n", "1", "--json", "--timeout", "60")
    eventually(lambda: len(stack.subscribers("mission")) > before, what="the listener's subscription")
    for topic in PUB_TOPICS:
        values = example(topic)
        if topic == "mission":
            values = json.dumps({**json.loads(values), "mission_id": 42, "source": "cli test"})
        out = stack.cli("topic", "pub", topic, values, "--wait", "0")
        assert out.returncode == 0 and out.stdout.strip() == f"published 1 message on {topic}", (topic, out.stderr)
    received, err = listener.communicate(timeout=60)
    assert listener.returncode == 0, err
    mission = json.loads(received)
    assert (mission["mission_id"], mission["source"], len(mission["items"])) == (42, "cli test", 1)
    assert mission["items"][0]["command"] == 16


def test_pub_refuses_bad_input_in_one_line(stack):
    for values, why in (
        ("-1", "error: expected a JSON object of field values"),
        ('{"items": [{"comand": 16}]}', "error: Mission: Object contains unknown field `comand` - at `items[0]`"),
    ):
        out = stack.cli("topic", "pub", "mission", values)
        assert out.returncode == 2 and out.stderr.strip().startswith(why), out.stderr
        assert len(out.stderr.strip().splitlines()) == 1
