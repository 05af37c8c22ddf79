"""Topics are named by handle: a misspelled one fails here, before any flight, and the facts that hang on a topic
(who may publish it, whether it may be dropped, which module's loss its silence means) come from the catalogue."""

from __future__ import annotations

import ast
import inspect
from pathlib import Path

import pytest

from stack.commander.control_chain import CHAIN, FW_CHAIN, OUTPUTS
from stack.msg.registry import ORB_ID, TOPICS
from stack.msg.topic import FromTools, Topic
from stack.runtime.module import Module, Trigger
from stack.runtime.spec import MODULES, load_module_class
from tests.support.bench import ModuleBench

ROOT = Path(__file__).resolve().parents[2]


def _handle_references() -> list[tuple[str, int, str]]:
    found = []
    for path in sorted([*ROOT.joinpath("stack").rglob("*.py"), *ROOT.joinpath("tests").rglob("*.py")]):
        for node in ast.walk(ast.parse(path.read_text(), str(path))):
            if isinstance(node, ast.Attribute) and isinstance(node.value, ast.Name) and node.value.id == "ORB_ID":
                found.append((str(path.relative_to(ROOT)), node.lineno, node.attr))
    return found


def test_every_handle_named_in_the_code_is_in_the_catalogue() -> None:
    references = _handle_references()
    assert len(references) > 500  # the modules, scenarios and tests name their topics this way
    unknown = [f"{path}:{line}: ORB_ID.{name}" for path, line, name in references if name not in TOPICS]
    assert unknown == []


def test_each_handle_is_named_for_the_attribute_that_holds_it_and_carries_its_type() -> None:
    assert all(isinstance(t, Topic) and t.name == name for name, t in TOPICS.items())
    assert ORB_ID.vehicle_attitude.type.__name__ == "VehicleAttitude"
    assert ORB_ID.vehicle_gps_position.type is ORB_ID.sensor_gps.type  # one type may serve several topics
    assert repr(ORB_ID.sensor_gyro) == "ORB_ID.sensor_gyro"


def test_a_module_naming_a_topic_by_string_is_refused_when_it_is_built() -> None:
    class ByString(Module):
        NAME = "by_string"

        def __init__(self, rt) -> None:
            super().__init__(rt)
            self.subscribe("vehicle_attitude")  # type: ignore[arg-type]

    with pytest.raises(TypeError, match="named by its handle"):
        ModuleBench(ByString)
    with pytest.raises(TypeError, match="named by its handle"):
        Trigger("sensor_gyro")  # type: ignore[arg-type]


def test_a_module_advertising_a_topic_it_does_not_declare_is_refused_when_it_is_built() -> None:
    class Undeclared(Module):
        NAME = "undeclared"
        PUBLISHES = (ORB_ID.vehicle_rates_setpoint,)

        def __init__(self, rt) -> None:
            super().__init__(rt)
            self.advertise(ORB_ID.vehicle_rates_setpoint)
            self.advertise(ORB_ID.vehicle_attitude)

    with pytest.raises(ValueError, match=r"vehicle_attitude, which Undeclared\.PUBLISHES does not declare"):
        ModuleBench(Undeclared)


def _advertised_handles(cls: type[Module]) -> set[str]:
    """The topics the source of ``cls``'s file advertises by handle: ``advertise(ORB_ID.x)``, or in a loop over a
    tuple of handles."""
    found = set()
    for node in ast.walk(ast.parse(inspect.getsource(inspect.getmodule(cls)))):
        calls = [n for n in ast.walk(node) if isinstance(n, ast.Call) and getattr(n.func, "attr", "") == "advertise"]
        if isinstance(node, ast.Call) and node in calls and node.args:
            handles = [node.args[0]]
        elif isinstance(node, ast.For) and isinstance(node.iter, ast.Tuple) and calls:
            handles = list(node.iter.elts)
        else:
            continue
        found |= {h.attr for h in handles if isinstance(h, ast.Attribute) and getattr(h.value, "id", "") == "ORB_ID"}
    return found


@pytest.mark.parametrize("module", sorted(MODULES))
def test_each_module_declares_every_topic_it_advertises(module: str) -> None:
    cls = load_module_class(module)
    assert _advertised_handles(cls) <= {t.name for t in cls.PUBLISHES}


def test_a_flight_script_publishes_what_its_scenario_names() -> None:
    scenario = load_module_class("scenario")
    assert scenario.publishes({"name": "attitude_step"}) == {
        "vehicle_command", "vehicle_attitude_setpoint", "offboard_control_mode", "telemetry_status", "parameter_update",
    }  # fmt: skip
    assert scenario.publishes({"name": "no_such_scenario"}) == {"vehicle_command", "parameter_update"}


def test_what_may_be_dropped_and_who_may_publish_come_from_the_catalogue() -> None:
    telemetry = {name for name, t in TOPICS.items() if t.telemetry}
    assert telemetry == {
        "rate_ctrl_status", "vehicle_local_position_setpoint", "sim_groundtruth", "actuator_outputs", "parameter_update"
    }  # fmt: skip
    assert ORB_ID.vehicle_command.from_tools is FromTools.ALWAYS
    assert ORB_ID.trajectory_setpoint.from_tools is FromTools.IN_OFFBOARD
    assert ORB_ID.vehicle_local_position.from_tools is FromTools.NEVER


QUAD_X = {"CA_ROTOR_COUNT": 4} | {
    f"CA_ROTOR{i}_P{axis}": v
    for i, xy in enumerate(((1, 1), (-1, -1), (1, -1), (-1, 1)))
    for axis, v in zip("XY", xy, strict=True)
}
SETUP: dict[str, tuple[dict, dict]] = {
    "control_allocator": (QUAD_X, {}),
    "roll_pitch_yawrate_thrust_controller": ({}, {"vehicle": "firefly"}),
}
"""What a module needs to be built beyond its defaults (a profile gives it)."""


@pytest.mark.parametrize("link", sorted({(link.module, link.output.name) for link in CHAIN + FW_CHAIN}))
def test_each_control_chain_module_publishes_the_output_it_is_watched_on(link: tuple[str, str]) -> None:
    module, output = link
    assert module in MODULES
    bench = ModuleBench(load_module_class(module), *SETUP.get(module, ({}, {})))
    assert (output, 0) in bench.outputs
    assert TOPICS[output] in OUTPUTS
