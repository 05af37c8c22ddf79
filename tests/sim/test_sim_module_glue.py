"""The simulator module on a bench: the motor commands it gives the plant, the failures it injects, parameter
changes reaching the plant, what it publishes and stamps (PX4 src/modules/simulation/simulator_sih/sih.cpp)."""

import math

from stack.msg.actuators import ActuatorOutputs
from stack.msg.registry import ORB_ID
from stack.msg.system import ActuatorArmed, VehicleCommand
from stack.sim.module import SimulatorModule
from stack.sim.simulator import Simulator
from tests.support.bench import ModuleBench, stand_in

PERIOD_S = 0.004
SPINNING = ActuatorOutputs(noutputs=4, output=(0.5, 0.6, math.nan, 0.8, 0.9) + (0.0,) * 11)


def gps_failure(**fields) -> VehicleCommand:
    return VehicleCommand(command=VehicleCommand.VEHICLE_CMD_INJECT_FAILURE,
                          param1=VehicleCommand.FAILURE_UNIT_SENSOR_GPS, param2=VehicleCommand.FAILURE_TYPE_OFF,
                          **fields)


def test_the_plants_topics_airspeed_only_for_a_plane():
    quad = ModuleBench(SimulatorModule)
    assert set(quad.inputs) == {
        (t.name, 0) for t in (ORB_ID.actuator_outputs_sim, ORB_ID.actuator_armed, ORB_ID.vehicle_command)
    }
    assert (ORB_ID.airspeed.name, 0) not in quad.outputs and (ORB_ID.sim_groundtruth.name, 0) in quad.outputs
    plane = ModuleBench(SimulatorModule, args={"vehicle": "sih_plane"})
    assert (ORB_ID.airspeed.name, 0) in plane.outputs


def test_motor_commands_its_inputs_with_nan_as_zero_and_none_while_stopped():
    bench = ModuleBench(SimulatorModule)
    assert bench.module.motor_commands() == (0.0,) * 4  # nothing from the allocator yet
    bench.put(ORB_ID.actuator_outputs_sim, SPINNING)
    assert bench.module.motor_commands() == (0.5, 0.6, 0.0, 0.8)  # no armed state known: the outputs as sent
    for stop in (dict(armed=False), dict(armed=True, lockdown=True), dict(armed=True, kill=True),
                 dict(armed=True, termination=True)):
        bench.put(ORB_ID.actuator_armed, ActuatorArmed(**stop))
        assert bench.module.motor_commands() == (0.0,) * 4
    bench.put(ORB_ID.actuator_armed, ActuatorArmed(armed=True))
    assert bench.module.motor_commands() == (0.5, 0.6, 0.0, 0.8)


def test_a_gps_failure_is_injected_only_when_enabled_and_addressed_here(monkeypatch):
    gps = stand_in(monkeypatch, Simulator, "set_gps_enabled", through=True)
    bench = ModuleBench(SimulatorModule)
    gps.clear()
    bench.put(ORB_ID.vehicle_command, gps_failure())
    bench.run(None, PERIOD_S)  # SYS_FAILURE_EN 0
    bench.set_param("SYS_FAILURE_EN", 1)
    bench.put(ORB_ID.vehicle_command, gps_failure(target_system=7))
    bench.run(None, PERIOD_S)
    assert gps == []
    bench.put(ORB_ID.vehicle_command, gps_failure())
    bench.run(None, PERIOD_S)
    assert gps == [(False,)]


def test_fewer_than_four_satellites_turn_the_gps_off(monkeypatch):
    gps = stand_in(monkeypatch, Simulator, "set_gps_enabled", through=True)
    bench = ModuleBench(SimulatorModule)
    assert gps == [(True,)]
    bench.set_param("SIM_GPS_USED", 3)
    assert gps[-1] == (False,)


def test_each_step_publishes_the_imu_and_the_truth_stamped_on_the_stacks_clock():
    bench = ModuleBench(SimulatorModule)
    bench.now = 1_000_000
    bench.run(None, PERIOD_S)
    accel, gyro = bench.sent(ORB_ID.sensor_accel)[-1], bench.sent(ORB_ID.sensor_gyro)[-1]
    assert accel.timestamp_sample == gyro.timestamp_sample == bench.now
    assert accel.z < -9.0  # standing: the accelerometer reads gravity up
    assert len(bench.sent(ORB_ID.sim_groundtruth)) == 1 and len(bench.sent(ORB_ID.battery_status)) == 1


def test_a_plant_started_while_the_stack_is_armed_keeps_its_motors_stopped_until_the_stack_disarms(caplog):
    """Its host lost in a flight and started again: a new vehicle on the ground, which the stack's loops, still
    flying the one they knew, must not spin up."""
    bench = ModuleBench(SimulatorModule)
    bench.put(ORB_ID.actuator_outputs_sim, SPINNING)
    with caplog.at_level("WARNING"):
        bench.put(ORB_ID.actuator_armed, ActuatorArmed(armed=True))
        assert bench.module.motor_commands() == (0.0,) * 4
        assert bench.module.motor_commands() == (0.0,) * 4
    assert [r.getMessage() for r in caplog.records if r.name == "simulator"] == [
        "the stack was armed before this plant started: its motors stay stopped until it disarms"
    ]
    bench.put(ORB_ID.actuator_armed, ActuatorArmed(armed=False))
    assert bench.module.motor_commands() == (0.0,) * 4
    bench.put(ORB_ID.actuator_armed, ActuatorArmed(armed=True))
    assert bench.module.motor_commands() == (0.5, 0.6, 0.0, 0.8)


IDLE = ActuatorOutputs(noutputs=4, output=(0.1,) * 4 + (0.0,) * 12)


def test_a_silent_armed_stack_hands_the_motors_to_the_plant_and_back_when_its_commands_return(caplog):
    bench = ModuleBench(SimulatorModule, params={"COM_OBL_RC_ACT": 4, "COM_OF_LOSS_T": 0.5})
    bench.put(ORB_ID.actuator_armed, ActuatorArmed(armed=False))
    bench.run(None, PERIOD_S)
    bench.put(ORB_ID.actuator_armed, ActuatorArmed(armed=True))
    for _ in range(50):
        bench.put(ORB_ID.actuator_outputs_sim, IDLE)
        bench.run(None, PERIOD_S)
    assert bench.module.status()["motor_control"] == "stack"
    with caplog.at_level("INFO"):
        for _ in range(round(0.5 / PERIOD_S) + 1):
            bench.run(None, PERIOD_S)
        assert bench.module.status()["motor_control"] == "failsafe"
        assert bench.module.status()["plant_mode"] == "AUTO.LAND"
        bench.put(ORB_ID.actuator_outputs_sim, IDLE)
        bench.run(None, PERIOD_S)
        assert bench.module.status()["motor_control"] == "stack"
    assert [(r.levelname, r.getMessage()[:40]) for r in caplog.records if r.name == "simulator"] == [
        ("WARNING", "no motor commands from the flight stack "),
        ("INFO", "motor commands from the flight stack aga"),
    ]


def test_a_plane_has_no_takeover():
    bench = ModuleBench(SimulatorModule, args={"vehicle": "sih_plane"})
    assert bench.module.takeover is None and set(bench.module.status()) == {"catch_up_steps", "skipped_steps"}
