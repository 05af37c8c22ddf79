"""Attacks on a hovering vehicle's bus, each from a process of its own (tests/support/attack.py), none of which
may move it: a forged ``vehicle_attitude`` rolled 30° at 200 Hz and a forged ``vehicle_local_position`` 10 m
up (before, the first flew the vehicle 500 m away and the second into the ground), the same attitude under the
publisher id of ``mc_rate_control``, a module of the vehicle that does not publish it, and NaN and infinity in
every float of every topic, sent by an outsider. Every sample is counted where it was refused (``stack status``).
NaN and infinity under a module's own publisher id, which the fast path never takes from outside, are refused by
every input on any transport (tests/backbone/test_input_gate.py)."""

from __future__ import annotations

import json
import subprocess
import sys
from collections.abc import Iterator

import pytest

from tests.support.harness import REPO, RunningStack, launch_profile, stack_env, takeoff_when_ready

pytestmark = pytest.mark.flight

ATTACK_S = 2.0
HOVER_M = 0.5
"""What the hover itself moves, with margin (the default profile holds a hover within ~0.1 m)."""


def hovering(home, *args: str) -> Iterator[RunningStack]:
    stack = RunningStack(home, launch_profile(home.parent / "profile"), "--quiet", *args)
    try:
        stack.wait_up()
        takeoff = takeoff_when_ready(stack, "--alt", "5")
        assert takeoff.returncode == 0, (takeoff.stdout, takeoff.stderr)
        yield stack
    finally:
        code = stack.stop()
    assert code == 0, stack.output


@pytest.fixture(scope="module")
def shm_stack(tmp_path_factory):
    yield from hovering(tmp_path_factory.mktemp("attacks") / "home")


def attack(stack: RunningStack, kind: str, *args: str) -> dict:
    out = subprocess.run(
        [sys.executable, "-m", "tests.support.attack", kind, str(ATTACK_S), *args],
        cwd=REPO,
        env=stack_env(stack.home),
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert out.returncode == 0, out.stderr
    return json.loads(out.stdout)


def counters(stack: RunningStack) -> dict[str, dict]:
    return {m["module"]: m for m in stack.status()["modules"]}


def still_holding(stack: RunningStack) -> None:
    status = json.loads(stack.cli("topic", "echo", "vehicle_status", "-n", "1", "--json").stdout)
    assert (status["nav_state"], status["arming_state"], status["failsafe"]) == (4, 2, False), status


@pytest.mark.parametrize(("kind", "pretending"), [("attitude", ""), ("position", ""), ("attitude", "mc_rate_control")])
def test_a_forged_state_moves_nothing(shm_stack: RunningStack, kind: str, pretending: str) -> None:
    before = {name: m.get("unauthorized", 0) for name, m in counters(shm_stack).items()}
    moved = attack(shm_stack, kind, *(("--as", pretending) if pretending else ()))
    assert moved["sent"] > 100
    assert moved["horizontal_m"] < HOVER_M and moved["vertical_m"] < HOVER_M, moved
    still_holding(shm_stack)
    after = counters(shm_stack)
    ignored = {name: m["unauthorized"] - before[name] for name, m in after.items() if m["unauthorized"] > before[name]}
    # Every module reading the topic ignored the forgeries (a controller triggered by it refuses them as
    # triggers from outside the lockstep run, counted apart).
    assert ignored and max(ignored.values()) >= moved["sent"] // 2, (ignored, moved)


def test_nan_and_infinity_everywhere_from_outside_move_nothing(shm_stack: RunningStack) -> None:
    moved = attack(shm_stack, "nonfinite")
    assert moved["horizontal_m"] < HOVER_M and moved["vertical_m"] < HOVER_M, moved
    still_holding(shm_stack)
    modules = counters(shm_stack).values()
    # Commands and sticks are open to tools, so their infinities meet the values check; the rest is not theirs.
    assert sum(m["invalid"] for m in modules) > 0 and sum(m["unauthorized"] for m in modules) > 0, modules
