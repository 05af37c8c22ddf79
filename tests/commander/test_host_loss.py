"""A vehicle over several hosts: the commander names a lost host and never terminates on what it took away."""

from __future__ import annotations

import pytest

from stack.bus.host_beats import STOPPING, HostWatch, beat_host, beat_key
from stack.commander import commands as C
from stack.commander.control_chain import OUTPUTS
from stack.commander.events import event_severity
from stack.commander.host_loss import CONVERGE_LIMIT_US, DEATH_GRACE_US, RETURN_GRACE_US
from stack.msg.system import MavlinkLog
from stack.msg.system import VehicleStatus as NS
from tests.commander.helpers import Clock, local_position, make_clock

PLACEMENT = {
    "sim": ["simulator", "attitude_estimator_q", "local_position_estimator"],
    "control": ["commander", "mc_att_control", "mc_rate_control", "control_allocator"],
    "ground": ["mavlink_gcs"],
}
LEASE_MS = 750


def test_a_host_is_late_after_three_missed_beats_lost_after_the_lease_and_back_with_its_next_beat():
    watch = HostWatch(PLACEMENT, "control", LEASE_MS)
    assert watch.update(10_000_000) == [] and watch.late(10_000_000) == []  # never heard: not started yet
    watch.beat("sim", 0)
    watch.beat("ground", 0)
    assert watch.late(300_000) == []
    assert watch.late(300_001) == ["sim", "ground"]
    assert watch.update(750_000) == []
    watch.beat("ground", 700_000)
    (change,) = watch.update(750_001)
    assert (change.host, change.lost, change.modules) == ("sim", True, tuple(PLACEMENT["sim"]))
    assert change.describe() == (
        "Lost host sim (no beat for 0.75 s): simulator, attitude_estimator_q, local_position_estimator"
    )
    assert watch.lost == ["sim"] and watch.update(800_000) == []
    watch.beat("sim", 5_000_000)
    watch.beat("ground", 5_000_000)
    (back,) = watch.update(5_000_000)
    assert (back.host, back.lost, back.describe()) == ("sim", False, "Host sim back after 5.0 s")
    assert watch.lost == []


def test_a_host_whose_supervisor_says_it_stops_is_lost_at_once_and_back_when_it_beats_again():
    watch = HostWatch(PLACEMENT, "control", LEASE_MS)
    watch.beat("ground", 0)
    watch.beat("ground", 100_000, STOPPING)
    (change,) = watch.update(110_000)
    assert change.lost and change.describe() == "Lost host ground (its supervisor stopped): mavlink_gcs"
    assert watch.late(110_000) == ["ground"]
    watch.beat("ground", 9_000_000)
    (back,) = watch.update(9_000_000)
    assert not back.lost and watch.lost == [] and watch.late(9_000_000) == []


def test_beats_of_hosts_outside_the_profile_and_the_watchers_own_are_ignored_and_counted():
    watch = HostWatch(PLACEMENT, "control", LEASE_MS)
    watch.beat("intruder", 0)
    watch.beat("control", 0)
    assert watch.foreign == 2
    assert watch.update(10_000_000) == []


@pytest.mark.parametrize(
    ("key", "host"),
    [
        ("stack/v1/@supervisor/sim/beat", "sim"),
        ("stack/v2/@supervisor/sim/beat", None),
        ("stack/v1/@supervisor/sim/status", None),
        ("stack/v1/@supervisor/sim/beat/x", None),
    ],
)
def test_a_beat_key_names_its_host(key, host):
    assert beat_host(key, "v1") == host
    assert beat_key("v1", "sim") == "stack/v1/@supervisor/sim/beat"


class SplitVehicle:
    """A commander on host ``control`` hovering at 5 m, with the hosts beating and the chain's outputs coming
    until a test stops them."""

    def __init__(self) -> None:
        self.clock: Clock = make_clock()
        commander = self.clock.commander
        commander.watch_hosts(PLACEMENT, "control", LEASE_MS, outside={"mavlink_gcs"})
        self.beating = {"sim", "ground"}
        self.estimates = True
        self.frozen_at = 0
        self.step()
        self.clock.send(C.arm_command())
        self.clock.send(C.set_mode_command("hold"))
        self.clock.fly_to((0.0, 0.0, -5.0))
        self.step(0.2)
        assert self.status.nav_state == NS.NAVIGATION_STATE_AUTO_LOITER

    @property
    def status(self) -> NS:
        return self.clock.status

    def lose(self, host: str) -> None:
        """The host's beats stop; with the simulator's host go the sensors and the estimates."""
        self.beating.discard(host)
        if host == "sim":
            self.estimates = False
            self.frozen_at = self.clock.t
            t = self.frozen_at
            self.clock.overrides = {
                f: t
                for f in (
                    "attitude_timestamp_us",
                    "angular_velocity_timestamp_us",
                    "gyro_timestamp_us",
                    "accel_timestamp_us",
                    "baro_timestamp_us",
                    "mag_timestamp_us",
                    "gps_timestamp_us",
                )
            }
            self.clock.overrides["local_position"] = local_position(t, *self.clock.position)

    def regain(self, host: str) -> None:
        self.beating.add(host)
        if host == "sim":
            self.estimates = True
            self.clock.overrides = {}

    def step(self, seconds: float = 0.0) -> None:
        clock = self.clock
        end = clock.t + max(round(seconds * 1e6), clock.period)
        while clock.t < end:
            hosts = clock.commander.hosts
            assert hosts is not None
            for host in self.beating:
                hosts.beat(host, clock.t)
            if self.estimates:
                for topic in OUTPUTS:
                    clock.commander.chain.output_seen(topic, clock.t)
            clock.step()


def test_losing_the_simulators_host_in_the_air_lands_and_never_terminates():
    vehicle = SplitVehicle()
    vehicle.lose("sim")
    for _ in range(300):  # 3 s: the estimates time out after 1 s, the chain after 0.5 s
        vehicle.step()
        assert vehicle.status.nav_state != NS.NAVIGATION_STATE_TERMINATION
        assert not vehicle.clock.last.actuator_armed.termination
    status = vehicle.status
    assert status.lost_hosts == ["sim"]
    assert status.nav_state == NS.NAVIGATION_STATE_AUTO_LAND
    assert (vehicle.clock.last.failsafe_action, vehicle.clock.last.failsafe_cause) == ("land", "host_loss")
    assert status.control_lost_modules == []
    lost = next(e for e in vehicle.clock.events if e.startswith("Lost host sim"))
    assert lost.endswith("simulator, attitude_estimator_q, local_position_estimator")
    assert event_severity(lost, refused=False) == MavlinkLog.SEVERITY_CRITICAL


def test_without_the_hosts_beats_the_same_loss_terminates():
    """What the beats change: the chain's and the estimates' own checks terminate a vehicle that loses them."""
    clock = make_clock()
    clock.step()
    clock.send(C.arm_command())
    clock.send(C.set_mode_command("hold"))
    clock.fly_to((0.0, 0.0, -5.0))
    t = clock.t
    clock.overrides = {"attitude_timestamp_us": t, "angular_velocity_timestamp_us": t, "gyro_timestamp_us": t}
    clock.step(1.5)
    assert clock.status.nav_state == NS.NAVIGATION_STATE_TERMINATION


def test_the_host_back_keeps_landing_and_once_landed_the_vehicle_disarms_and_may_arm_again():
    vehicle = SplitVehicle()
    vehicle.lose("sim")
    vehicle.step(2.0)
    vehicle.regain("sim")
    vehicle.step(0.05)
    assert "Host sim back after" in " ".join(vehicle.clock.events)
    assert vehicle.status.lost_hosts == []
    vehicle.step(RETURN_GRACE_US / 1e6 + 0.5)
    assert vehicle.status.nav_state == NS.NAVIGATION_STATE_AUTO_LAND
    vehicle.clock.position, vehicle.clock.landed = (0.0, 0.0, 0.0), True
    vehicle.step(3.0)
    assert vehicle.status.arming_state == NS.ARMING_STATE_DISARMED
    ack = vehicle.clock.send(C.arm_command())
    assert ack.result == 0, ack.reason


def test_a_host_late_for_less_than_the_lease_is_no_failsafe():
    vehicle = SplitVehicle()
    vehicle.beating.discard("sim")
    vehicle.step(0.5)
    vehicle.beating.add("sim")
    vehicle.step(0.5)
    assert vehicle.status.nav_state == NS.NAVIGATION_STATE_AUTO_LOITER
    assert not [e for e in vehicle.clock.events if "host" in e.lower()]


def test_a_stalled_link_from_a_host_that_still_beats_holds_the_checks_and_never_terminates():
    """Its estimates and outputs stop arriving for 1.5 s while its beats pass (a router's messages held up behind
    others): the estimates would time out after 1 s and terminate. They come back, and the vehicle holds on."""
    vehicle = SplitVehicle()
    vehicle.lose("sim")
    vehicle.beating.add("sim")
    for _ in range(150):
        vehicle.step()
        assert vehicle.status.nav_state == NS.NAVIGATION_STATE_AUTO_LOITER
    vehicle.regain("sim")
    vehicle.step(RETURN_GRACE_US / 1e6 + 1.0)
    assert vehicle.status.nav_state == NS.NAVIGATION_STATE_AUTO_LOITER
    assert not [e for e in vehicle.clock.events if "Failsafe" in e or "host" in e.lower()]


def test_outputs_missing_from_a_host_that_still_beats_are_acted_on_once_they_could_have_converged():
    vehicle = SplitVehicle()
    vehicle.lose("sim")
    vehicle.beating.add("sim")
    vehicle.step(CONVERGE_LIMIT_US / 1e6 - 1.0)
    assert vehicle.status.nav_state == NS.NAVIGATION_STATE_AUTO_LOITER
    vehicle.step(2.0)
    assert vehicle.status.nav_state == NS.NAVIGATION_STATE_TERMINATION  # its estimators hung: PX4's answer


def test_losing_the_ground_host_only_names_it():
    vehicle = SplitVehicle()
    vehicle.lose("ground")
    vehicle.step(2.0)
    assert vehicle.status.lost_hosts == ["ground"]
    assert vehicle.status.nav_state == NS.NAVIGATION_STATE_AUTO_LOITER
    assert "Lost host ground (no beat for 0.76 s): mavlink_gcs" in vehicle.clock.events


def die(vehicle: SplitVehicle, module: str) -> None:
    """``module``'s liveliness ends, as the commander's glue reports it."""
    commander = vehicle.clock.commander
    assert commander.hosts is not None
    commander.chain.module_died(module)
    commander.hosts.module_died(module, vehicle.clock.t)


def test_modules_of_a_host_killed_die_at_once_and_the_host_loss_follows_with_no_termination():
    """A killed host's links close at once: its modules' liveliness ends before its beats are late."""
    vehicle = SplitVehicle()
    vehicle.lose("sim")
    for module in PLACEMENT["sim"]:
        die(vehicle, module)
    for _ in range(300):
        vehicle.step()
        assert vehicle.status.nav_state != NS.NAVIGATION_STATE_TERMINATION
    assert vehicle.status.lost_hosts == ["sim"]
    assert vehicle.status.nav_state == NS.NAVIGATION_STATE_AUTO_LAND


def test_a_dead_module_of_the_commanders_own_host_is_acted_on_at_once():
    vehicle = SplitVehicle()
    die(vehicle, "mc_rate_control")
    vehicle.step()
    assert vehicle.status.nav_state == NS.NAVIGATION_STATE_TERMINATION


def test_a_dead_module_of_a_host_that_still_beats_is_acted_on_once_the_grace_is_over():
    vehicle = SplitVehicle()
    die(vehicle, "attitude_estimator_q")
    vehicle.step()
    assert vehicle.status.nav_state != NS.NAVIGATION_STATE_TERMINATION  # held: its host may have gone with it
    vehicle.step(DEATH_GRACE_US / 1e6)
    assert vehicle.status.nav_state == NS.NAVIGATION_STATE_TERMINATION  # the host beats on: the module failed


def test_a_host_back_with_estimators_still_converging_is_given_time_and_no_more():
    vehicle = SplitVehicle()
    vehicle.lose("sim")
    vehicle.step(2.0)
    vehicle.beating.add("sim")  # back, its estimators started again: no valid estimate yet
    vehicle.step(RETURN_GRACE_US / 1e6 + 2.0)
    assert vehicle.status.nav_state == NS.NAVIGATION_STATE_AUTO_LAND
    vehicle.step((CONVERGE_LIMIT_US - RETURN_GRACE_US) / 1e6)
    assert vehicle.status.nav_state == NS.NAVIGATION_STATE_TERMINATION  # they never converged
