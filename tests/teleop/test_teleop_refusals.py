"""`stack teleop` refuses what it cannot fly with, in one line and before it touches the terminal: no stack, no
terminal, a missing device, a bad mapping file."""

from __future__ import annotations

from pathlib import Path

from tests.support.harness import run_cli
from tests.teleop.terminal import Teleop


def test_no_stack_running(tmp_path: Path) -> None:
    t = Teleop(tmp_path)
    try:
        assert t.exit_code() == 1
        assert t.terminal_restored()
        assert t.output.strip() == "error: no running stack found (start one with `stack up`, or pass --endpoint)"
    finally:
        t.close()


def test_no_terminal_no_device_a_bad_mapping(tmp_path: Path) -> None:
    out = run_cli(tmp_path, "teleop")  # stdin is not a terminal
    assert (out.returncode, out.stderr.strip()) == (
        2,
        "error: stack teleop reads the keyboard of a terminal: run it in one, or give --joystick",
    )
    out = run_cli(tmp_path, "teleop", "--joystick", str(tmp_path / "js7"))
    assert out.returncode == 2
    assert (
        out.stderr.strip()
        == f"error: cannot open the joystick {tmp_path / 'js7'}: No such file or directory (is the gamepad plugged in?)"
    )
    mapping = tmp_path / "pad.toml"
    mapping.write_text("[axes]\nroll = { axis = 300 }\n")
    out = run_cli(tmp_path, "teleop", "--joystick", "/dev/null", "--mapping", str(mapping))
    assert out.returncode == 2
    assert out.stderr.strip() == f"error: {mapping}: axes.roll.axis: expected an axis number 0..255, got 300"
    out = run_cli(tmp_path, "teleop", "--mapping", str(mapping))
    assert (out.returncode, out.stderr.strip()) == (2, "error: --mapping is the mapping of a --joystick; give both")
