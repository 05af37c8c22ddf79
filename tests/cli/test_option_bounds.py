"""A number on the command line outside what its option means (a negative count, a window of 0 seconds, NaN, a
port past 65535) is a usage error naming the option, before the command does anything: no traceback, no silent
exit, no message published.
"""

from __future__ import annotations

import pytest
import typer
from typer.testing import CliRunner

from stack.cli.app import app
from stack.cli.common import output_directory, output_file

# Numbers any value of which means something, or which the command checks itself with its own message: seeds,
# coordinates and angles (cmd goto and takeoff refuse NaN, the commander the rest), the first mission item (the
# commander's range), the simulated link's faults (the fault model's ranges), and a swarm's hidden bookkeeping.
CHECKED_ELSEWHERE = {
    ("fly", "--seed"),
    ("pixhawk-sim", "--seed"),
    ("pixhawk-sim", "--drop"),
    ("pixhawk-sim", "--corrupt"),
    ("pixhawk-sim", "--latency-ms"),
    ("pixhawk-sim", "--jitter-ms"),
    ("fly", "--swarm-vehicle"),
    ("fly", "--swarm-size"),
    ("up", "--swarm-vehicle"),
    ("up", "--swarm-size"),
    ("cmd takeoff", "--alt"),
    ("cmd takeoff", "--yaw"),
    ("cmd goto", "north"),
    ("cmd goto", "east"),
    ("cmd goto", "down"),
    ("cmd goto", "--lat"),
    ("cmd goto", "--lon"),
    ("cmd goto", "--alt"),
    ("cmd goto", "--yaw"),
    ("cmd goto", "--speed"),
    ("cmd mission", "--first"),
}


def numeric_options() -> list[tuple[str, str, object]]:
    """(command path, the option's first name, the Click parameter) of every int or float parameter."""
    found = []

    def walk(command: object, path: str) -> None:
        for name, sub in getattr(command, "commands", {}).items():
            walk(sub, f"{path} {name}".strip())
        for param in getattr(command, "params", ()):
            kind = type(param.type).__name__
            if kind in ("IntParamType", "FloatParamType", "IntRange", "FloatRange"):
                found.append((path, param.opts[0], param))

    walk(typer.main.get_command(app), "")
    return found


def test_every_number_on_the_command_line_is_bounded():
    unbounded = [
        (path, opt)
        for path, opt, param in numeric_options()
        if (path, opt) not in CHECKED_ELSEWHERE
        and param.callback is None
        and type(param.type).__name__ not in ("IntRange", "FloatRange")
    ]
    assert unbounded == []
    # A float's range alone lets NaN through: each checks it itself.
    ranges_only = [
        (path, opt)
        for path, opt, param in numeric_options()
        if type(param.type).__name__ == "FloatRange" and param.callback is None
    ]
    assert ranges_only == []


@pytest.mark.parametrize(
    ("args", "option", "value"),
    [
        (["topic", "list", "--window", "0"], "'--window'", "0"),
        (["topic", "list", "--window", "nan"], "'--window'", "nan"),
        (["topic", "echo", "vehicle_attitude", "-n", "-1"], "'-n' / '--count'", "-1"),
        (["topic", "echo", "vehicle_attitude", "-i", "-1"], "'--instance' / '-i'", "-1"),
        (["topic", "echo", "vehicle_attitude", "--rate", "-1"], "'--rate' / '-r'", "-1"),
        (["topic", "echo", "vehicle_attitude", "--queue", "0"], "'--queue'", "0"),
        (["topic", "echo", "vehicle_attitude", "--timeout", "nan"], "'--timeout'", "nan"),
        (["topic", "hz", "vehicle_attitude", "--window", "0"], "'--window'", "0"),
        (["topic", "hz", "vehicle_attitude", "--duration", "-1"], "'--duration'", "-1"),
        (["topic", "pub", "vehicle_command", "{}", "--count", "-1"], "'--count' / '-n'", "-1"),
        (["topic", "pub", "vehicle_command", "{}", "--rate", "inf"], "'--rate' / '-r'", "inf"),
        (["topic", "pub", "vehicle_command", "{}", "--wait", "nan"], "'--wait'", "nan"),
        (["param", "save", "x.params", "--system-id", "0"], "'--system-id'", "0"),
        (["param", "save", "x.params", "--system-id", "256"], "'--system-id'", "256"),
        (["cmd", "arm", "--timeout", "nan"], "'--timeout' / '-t'", "nan"),
        (["cmd", "land", "--timeout", "0"], "'--timeout' / '-t'", "0"),
        (["cmd", "land", "--wait", "--wait-timeout", "-1"], "'--wait-timeout'", "-1"),
        (["up", "--duration", "nan"], "'--duration' / '-d'", "nan"),
        (["down", "--timeout", "-1"], "'--timeout'", "-1"),
        (["plot", "--plot-rate", "-1"], "'--plot-rate'", "-1"),
        (["plot", "--web-port", "70000"], "'--web-port'", "70000"),
        (["replay", "x.mcap", "--wait-subscribers", "nan"], "'--wait-subscribers'", "nan"),
        (["pixhawk-sim", "--baud", "0"], "'--baud'", "0"),
        (["pixhawk-sim", "--cut-at", "nan"], "'--cut-at'", "nan"),
        (["pixhawk-sim", "--control-port", "-1"], "'--control-port'", "-1"),
        (["fly", "--wind-speed", "nan"], "'--wind-speed'", "nan"),
        (["fly", "--wind-speed", "31"], "'--wind-speed'", "31"),
        (["mavlink", "inspect", "udp:127.0.0.1:1", "--seconds", "nan"], "'--seconds' / '-s'", "nan"),
        (["keys", "issue", "ks", "gcs", "--role", "ground", "--days", "0"], "'--days'", "0"),
    ],
)
def test_a_number_out_of_its_range_is_a_usage_error_naming_the_option(args, option, value):
    result = CliRunner().invoke(app, args)
    assert result.exit_code == 2, result.output
    assert f"Invalid value for {option}: {value} is not " in result.output, result.output
    assert result.exception is None or isinstance(result.exception, SystemExit)


@pytest.mark.parametrize(
    "args",
    [
        ["fly", "takeoff_land", "--report", "{missing}/report.json"],
        ["fly", "takeoff_land", "--record", "{missing}/flight.mcap"],
        ["up", "--save", "{dir}"],
        ["up", "--record", "{missing}/flight.mcap"],
        ["log", "export", "flight.mcap", "--rrd", "{missing}/flight.rrd"],
        ["pixhawk-sim", "--report", "{dir}"],
        ["plot", "--save", "{missing}/plots.rrd"],
    ],
)
def test_a_file_that_cannot_be_written_is_refused_before_anything_starts(tmp_path, args):
    args = [a.format(missing=tmp_path / "missing", dir=tmp_path) for a in args]
    result = CliRunner().invoke(app, args)
    assert result.exit_code == 2, result.output
    assert "cannot write " in result.output and (
        "No such file or directory" in result.output or "Is a directory" in result.output
    ), result.output
    assert sorted(tmp_path.iterdir()) == []  # nothing made, not even the missing directory


def test_trying_a_file_leaves_a_new_one_absent_and_an_old_one_as_it_was(tmp_path):
    new, old = tmp_path / "new.json", tmp_path / "old.json"
    old.write_text("kept")
    assert output_file(new) == new and output_file(str(old)) == str(old)
    assert not new.exists() and old.read_text() == "kept"
    assert output_file(None) is None and output_file("") == ""


def test_a_directory_that_cannot_be_written_in_is_refused_before_anything_starts(tmp_path):
    afile = tmp_path / "flight.mcap"
    afile.write_bytes(b"")
    for csv, why in ((afile, f"{afile} is not a directory"), (afile / "out", f"cannot write in {afile}: ")):
        result = CliRunner().invoke(app, ["log", "export", str(afile), "--csv", str(csv)])
        assert result.exit_code == 2 and f"Invalid value for '--csv': {why}" in result.output, result.output
    assert output_directory(tmp_path / "new" / "deeper") == tmp_path / "new" / "deeper"
    assert sorted(tmp_path.iterdir()) == [afile]  # the check makes nothing: the export makes the directory
