"""A commander parameter change in flight keeps the land detector's state: the vehicle, hovering, is not
reported landed (which would let the commander auto-disarm it), the parameters apply to the land detector
it has rather than to a new one starting "landed", and the flight goes on to land normally.

The takeoff_land scenario is flown in one process (:class:`stack.runtime.inprocess.InProcessStack`, the real
module classes in lockstep), and the parameters are set on the commander's own store, as ``stack param set``
does, once it has hovered for a while.
"""

from __future__ import annotations

from pathlib import Path

from stack.runtime.inprocess import InProcessStack
from stack.scenario.inprocess import flight_profile

AIRBORNE_STEPS = 750  # 3 s at 250 Hz
CHANGES = {"LNDMC_TRIG_TIME": 0.3, "MPC_THR_MIN": 0.1, "COM_DISARM_LAND": 1.0}


def test_a_commander_parameter_change_in_flight_does_not_land_the_vehicle(tmp_path: Path) -> None:
    result = tmp_path / "result.json"
    stack = InProcessStack(flight_profile("takeoff_land", result, seed=1))
    commander = stack.runtimes["commander"]
    try:
        airborne = 0
        while airborne < AIRBORNE_STEPS:
            stack.step()
            airborne = 0 if commander.module.land.detector.state.landed else airborne + 1
            assert stack.now_us < 60_000_000, "no takeoff within 60 s"
        detector = commander.module.land.detector
        for name, value in CHANGES.items():
            commander.params.set(name, value)
        for _ in range(AIRBORNE_STEPS):
            stack.step()
            assert commander.module.land.detector is detector, "the land detector was rebuilt, its state lost"
            assert not (detector.state.landed or detector.state.maybe_landed), f"landed at {stack.now_us / 1e6} s"
            assert commander.module.commander.armed
        assert {commander.params[name] for name in CHANGES} == set(CHANGES.values())
        stack.run()
    finally:
        stack.close()
    assert '"passed": true' in result.read_text()
