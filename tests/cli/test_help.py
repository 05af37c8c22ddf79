"""`stack --version`, and -h as well as --help on every command; negative numbers are values, not options."""

import pytest
import typer.main
from typer.testing import CliRunner

import stack
from stack.cli.app import app
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


@pytest.mark.parametrize("path", commands(typer.main.get_command(app)), ids=" ".join)
def test_every_command_takes_dash_h(path):
    short = CliRunner().invoke(app, [*path, "-h"], terminal_width=120)
    long = CliRunner().invoke(app, [*path, "--help"], terminal_width=120)
    assert short.exit_code == 0 and "Usage:" in short.output, short.output
    assert short.output == long.output
    # Plain help: a flag takes no value, so nothing stands beside it; no boxes.
    assert "<bool>" not in short.output and "╭" not in short.output, short.output


@pytest.mark.parametrize(
    "args",
    [("param", "set", "MPC_THR_MIN", "-1"), ("cmd", "goto", "-5", "3", "-10"), ("cmd", "takeoff", "--alt", "-5")],
)
def test_negative_numbers_are_values(tmp_path, args):
    out = run_cli(tmp_path, *args, "--endpoint", NOWHERE)
    # They reach for the bus (none there), not refused as unknown options.
    assert out.returncode == 1 and out.stderr.startswith("error: cannot reach the stack at"), out.stderr
