"""`stack --version`, and -h as well as --help on every command; negative numbers are values, not options."""

import re

import pytest

import stack
from stack.cli.app import cli
from tests.cli.test_cmd import NOWHERE
from tests.support.harness import run_cli


def commands(group: object, prefix: tuple[str, ...] = ()) -> list[tuple[str, ...]]:
    """Every command path under a Click group (typer's own vendored Click or Click itself: a group is what
    has subcommands)."""
    found = [prefix]
    for name, command in group.commands.items():  # type: ignore[attr-defined]
        if hasattr(command, "commands"):
            found += commands(command, (*prefix, name))
        else:
            found.append((*prefix, name))
    return found


def test_version(tmp_path):
    out = run_cli(tmp_path, "--version")
    assert out.returncode == 0 and out.stdout.strip() == f"stack {stack.__version__}"


def help_screen(args: list[str], capsys: pytest.CaptureFixture[str]) -> str:
    """What ``stack ARGS`` prints, run as the ``stack`` script runs the command."""
    assert cli().main(args=args, prog_name="stack", standalone_mode=False) in (0, None)
    return capsys.readouterr().out


@pytest.mark.parametrize("path", commands(cli()), ids=" ".join)
def test_every_command_takes_dash_h(path, capsys, monkeypatch):
    monkeypatch.setenv("COLUMNS", "120")
    short = help_screen([*path, "-h"], capsys)
    assert "Usage:" in short, short
    assert short == help_screen([*path, "--help"], capsys)
    # Plain help: a flag takes no value, so nothing stands beside it; a value's placeholder is its name, not its
    # Python type; no boxes.
    assert not re.search(r"<(bool|str|int|float|path)", short) and "╭" not in short, short


@pytest.mark.parametrize(
    "args",
    [("param", "set", "MPC_THR_MIN", "-1"), ("cmd", "goto", "-5", "3", "-10"), ("cmd", "takeoff", "--alt", "-5")],
)
def test_negative_numbers_are_values(tmp_path, args):
    out = run_cli(tmp_path, *args, "--endpoint", NOWHERE)
    # They reach for the bus (none there), not refused as unknown options.
    assert out.returncode == 1 and out.stderr.startswith("error: cannot reach the stack at"), out.stderr
