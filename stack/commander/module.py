"""The commander module: arming, modes, commands and failsafes every 10 ms, land detection every 20 ms.

Like PX4's ``src/modules/commander/Commander.cpp`` it runs at 100 Hz (COMMANDER_MONITORING_INTERVAL),
answers every ``vehicle_command`` with a ``vehicle_command_ack`` and publishes ``actuator_armed``,
``vehicle_status`` and ``vehicle_control_mode`` (the flags the controllers obey) on change and at 2 Hz,
plus ``home_position``. In Offboard the control flags follow the offboard controller's
``offboard_control_mode``, which must keep arriving (COM_OF_LOSS_T) or the switch is refused. With an external
autopilot as the plant (COM_EXT_AP, the ``pixhawk`` module) it reads ``external_autopilot_status`` and
publishes the acknowledgements it held back until that autopilot armed or refused. Its events (arming, mode
changes, failsafes) and the reasons of the commands it refuses go out on ``mavlink_log`` for the operator, as
PX4's commander does with ``mavlink_log_*``: ground-station links send them as STATUSTEXT.

PX4's land detector runs in the same process on every second tick (:mod:`stack.commander.land_detection`):
the multicopter detector, or the fixed-wing one (:mod:`stack.commander.fw_land_detector`, on
``airspeed_validated``) when MAV_TYPE makes the vehicle a plane. In PX4 both read the 250 Hz attitude and IMU
topics in-process for free; here they read the estimator's 10 Hz ``estimator_status`` and
``vehicle_imu_status`` summaries.
"""

from __future__ import annotations

import math

import msgspec

from stack.commander import control_chain, fw_land_detector, land_detector, offboard
from stack.commander.events import event_severity
from stack.commander.fw_land_detector import FixedwingLandDetectorInputs
from stack.commander.health import CommanderInputs
from stack.commander.home import HomePosition as Home
from stack.commander.land_detection import LandDetection
from stack.commander.land_detector import LandDetectorInputs
from stack.commander.modes import FIXED_WING
from stack.commander.state_machine import PARAMS as COMMANDER_PARAMS
from stack.commander.state_machine import Commander
from stack.commander.state_machine import NavigationRequest as Navigation
from stack.msg.navigation import NavigationRequest
from stack.msg.registry import ORB_ID
from stack.msg.system import (
    HomePosition,
    MavlinkLog,
    VehicleCommand,
    VehicleCommandAck,
    VehicleControlMode,
    VehicleStatus,
    command_label,
)
from stack.params.binding import combine
from stack.runtime.module import Module, Timer
from stack.runtime.priority import COMMANDER

NS = VehicleStatus
RATE_HZ = 100.0
REPUBLISH_US = 500_000


def navigation_request(nav: Navigation) -> NavigationRequest:
    north, east, down, yaw = nav.reposition if nav.reposition is not None else (math.nan,) * 4
    return NavigationRequest(
        takeoff_altitude=nav.takeoff_altitude,
        takeoff_yaw=nav.takeoff_yaw,
        reposition=(north, east, down),
        reposition_yaw=yaw,
        reposition_speed=nav.reposition_speed,
        reposition_counter=nav.reposition_counter,
        mission_start_index=nav.mission_start_index,
        mission_start_counter=nav.mission_start_counter,
    )


def home_position_message(home: Home, update_count: int, now: int) -> HomePosition:
    global_valid = home.global_valid
    return HomePosition(
        timestamp=now,
        lat=home.lat,
        lon=home.lon,
        alt=home.alt,
        x=home.x,
        y=home.y,
        z=home.z,
        yaw=home.yaw,
        valid_alt=math.isfinite(home.alt),
        valid_hpos=global_valid,
        valid_lpos=True,
        update_count=update_count,
    )


class CommanderModule(Module):
    NAME = "commander"
    WORK_QUEUE = COMMANDER
    DESCRIPTION = "Arming, flight modes, commands and failsafes (PX4 commander)"
    TRIGGER = Timer(RATE_HZ)
    DT_RANGE = (0.001, 0.1)
    PARAMS = combine(COMMANDER_PARAMS, offboard.PARAMS, land_detector.PARAMS, fw_land_detector.PARAMS)
    PUBLISHES = (
        ORB_ID.actuator_armed,
        ORB_ID.vehicle_status,
        ORB_ID.vehicle_control_mode,
        ORB_ID.vehicle_command_ack,
        ORB_ID.home_position,
        ORB_ID.vehicle_land_detected,
        ORB_ID.navigation_request,
        ORB_ID.mavlink_log,
    )

    def __init__(self, rt) -> None:
        super().__init__(rt)
        self.subscribe(ORB_ID.vehicle_command, queue=True)
        for topic in (
            ORB_ID.estimator_status,
            ORB_ID.vehicle_imu_status,
            ORB_ID.vehicle_local_position,
            ORB_ID.sensor_baro,
            ORB_ID.sensor_mag,
            ORB_ID.sensor_gps,
            ORB_ID.battery_status,
            ORB_ID.telemetry_status,
            ORB_ID.manual_control_setpoint,
            ORB_ID.offboard_control_mode,
            ORB_ID.vehicle_thrust_setpoint,
            ORB_ID.trajectory_setpoint,
            ORB_ID.hover_thrust_estimate,
            ORB_ID.takeoff_status,
            ORB_ID.mission_result,
            ORB_ID.external_autopilot_status,
            ORB_ID.airspeed,
        ):
            self.subscribe(topic)
        for topic in control_chain.OUTPUTS:
            if topic not in (ORB_ID.vehicle_local_position, ORB_ID.trajectory_setpoint):
                self.subscribe(topic)
        for topic in self.PUBLISHES:
            self.advertise(topic)
        self.commander = Commander(self.params.values())
        self.land = LandDetection(self.params.values(), self.commander.vehicle_type == FIXED_WING)
        self._last_publish = 0
        self._home: Home | None = None
        self._home_count = 0
        self._navigation: Navigation | None = None
        self._last_gcs = 0
        self._last_manual_control = 0
        self._offboard_flags: dict[str, bool] | None = None
        self._refusals: list[str] = []
        self._lockstep = rt.spec.lockstep
        self._failsafe = {"failsafe_action": "none", "failsafe_cause": ""}
        self._republish_now = False
        self._module_pids: dict[str, int] = {}
        if not self._lockstep:
            self.commander.chain.silence_us = control_chain.REALTIME_SILENCE_US
        spec = rt.spec
        if spec.placement and not self._lockstep:
            # In lockstep a lost host stops simulated time itself; in real time its beats say it is gone.
            self.commander.watch_hosts(spec.placement, spec.host, spec.host_lease_ms, spec.outside)
            self.watch_hosts(self._on_host_beat)
        self.watch_modules(self._on_module)
        kept = self.kept_state()
        if kept is not None:
            try:
                self.commander.resume(kept, self.now_us())
            except ValueError as e:
                self.log.warning("restarted, but cannot resume (%s): starting afresh", e)
            else:
                if self.commander.armed:
                    self.land.resume_in_air()

    def _on_module(self, module: str, pid: int, alive: bool) -> None:
        if alive:
            self.commander.chain.module_alive(module)
            restarted = self._module_pids.get(module, pid) != pid
            self._module_pids[module] = pid
            if restarted:
                # A restarted module learns the vehicle's state at once. (Only a restart: modules first seen
                # arrive on Zenoh's thread whenever it delivers them, and a lockstep flight must not depend on it.)
                self._republish_now = True
                self.land.republish()
        elif not self._lockstep:
            # In lockstep a dead module's silence is measured in simulated time, which stands still while the
            # supervisor restarts it; in real time its liveliness token says at once that it is gone.
            self.commander.chain.module_died(module)
            if self.commander.hosts is not None:
                self.commander.hosts.module_died(module, self.now_us())

    def _on_host_beat(self, host: str, payload: bytes) -> None:
        hosts = self.commander.hosts
        if hosts is not None:
            hosts.beat(host, self.now_us(), payload)

    def on_params_changed(self, changed: set[str]) -> None:
        self.commander.set_params(self.params.values())
        self.land.set_params(self.params.values())

    def run(self, msg: None, dt: float) -> None:
        now = self.now_us()
        for topic in control_chain.OUTPUTS:
            if self.update(topic) is not None:
                self.commander.chain.output_seen(topic, now)
        fixed_wing = self.commander.vehicle_type == FIXED_WING
        landing = self.land.update(now, fixed_wing, self._land_inputs, self._fw_land_inputs)
        if landing is not None:
            self.publish(ORB_ID.vehicle_land_detected, landing)
        inputs = self._inputs(now)
        commands = self.take(ORB_ID.vehicle_command)
        if commands:
            self.commander.set_inputs(now, inputs)
            for cmd in commands:
                self._handle(cmd, now)
        out = self.commander.update(now, inputs)
        self._failsafe = {"failsafe_action": out.failsafe_action, "failsafe_cause": out.failsafe_cause}
        for ack in out.acks:
            self._acknowledge(ack)
        self._tell_operator(out.events, now)
        control = out.vehicle_control_mode
        changed = out.changed
        if self.commander.nav_state == NS.NAVIGATION_STATE_OFFBOARD:
            flags = offboard.control_flags_now(
                self.latest(ORB_ID.offboard_control_mode), now, float(self.params["COM_OF_LOSS_T"])
            )
            if flags != self._offboard_flags:
                changed = True
                self._offboard_flags = flags
            if flags is not None:
                control = msgspec.structs.replace(
                    VehicleControlMode(flag_armed=control.flag_armed, source_id=control.source_id), **flags
                )
        navigation = out.navigation
        home_changed = out.home != self._home
        if home_changed:
            self._home = out.home
            self._home_count += 1
        # Late subscribers (a CLI, a restarted module) learn the state within REPUBLISH_US.
        if self.commander.chain.late:
            self._republish_now = True
            self.land.republish()
        republish = self._republish_now or now - self._last_publish >= REPUBLISH_US
        if changed or home_changed or navigation != self._navigation or republish:
            self._republish_now = False
            self._last_publish = now
            self.keep_state(self.commander.kept_state())
            self._navigation = navigation
            # PX4 publishes actuator_armed before vehicle_status; the navigator reads its request with the mode.
            self.publish(ORB_ID.actuator_armed, msgspec.structs.replace(out.actuator_armed, timestamp=now))
            self.publish(
                ORB_ID.navigation_request, msgspec.structs.replace(navigation_request(navigation), timestamp=now)
            )
            self.publish(ORB_ID.vehicle_status, msgspec.structs.replace(out.vehicle_status, timestamp=now))
            self.publish(ORB_ID.vehicle_control_mode, msgspec.structs.replace(control, timestamp=now))
            if self._home is not None:
                self.publish(ORB_ID.home_position, home_position_message(self._home, self._home_count, now))

    def status(self) -> dict[str, float | int | str | bool]:
        """The failsafe in force and why, for `stack status` (PX4's `commander status`)."""
        return dict(self._failsafe)

    def _handle(self, cmd: VehicleCommand, now: int) -> None:
        if not self.commander.addressed_to_me(cmd):
            self.commander.ignored_commands += 1
            return
        ack = offboard.refusal(cmd, self.latest(ORB_ID.offboard_control_mode), now, float(self.params["COM_OF_LOSS_T"]))
        if ack is None:
            ack = self.commander.handle_command(cmd, now)
        if ack is not None:
            self._acknowledge(ack)

    def _acknowledge(self, ack: VehicleCommandAck) -> None:
        if ack.result != VehicleCommandAck.VEHICLE_CMD_RESULT_ACCEPTED:
            self.log.warning("command %s refused: %s", command_label(ack.command), ack.reason)
            if ack.reason:
                self._refusals.append(ack.reason)
        self.publish(ORB_ID.vehicle_command_ack, ack)

    def _tell_operator(self, events: tuple[str, ...], now: int) -> None:
        """Each event, and each refusal's reason (most are events too), once on ``mavlink_log``."""
        refusals, self._refusals = self._refusals, []
        for event in events:
            self.log.info("%s", event)
        for text in (*events, *(r for r in dict.fromkeys(refusals) if r not in events)):
            severity = event_severity(text, text in refusals)
            self.publish(ORB_ID.mavlink_log, MavlinkLog(timestamp=now, text=text, severity=severity))

    def _inputs(self, now: int) -> CommanderInputs:
        latest = self.latest
        est = latest(ORB_ID.estimator_status)
        imu = latest(ORB_ID.vehicle_imu_status)
        baro = latest(ORB_ID.sensor_baro)
        mag = latest(ORB_ID.sensor_mag)
        gps = latest(ORB_ID.sensor_gps)
        battery = latest(ORB_ID.battery_status)
        telemetry = latest(ORB_ID.telemetry_status)
        mission = latest(ORB_ID.mission_result)
        land = self.land.state
        if telemetry is not None and telemetry.heartbeat_type_gcs:
            # Only a ground station's heartbeat is the data link (PX4 Commander::dataLinkCheck); an onboard
            # controller's is not, and its going never calls for NAV_DLL_ACT.
            self._last_gcs = max(self._last_gcs, telemetry.timestamp)
        fresh_sticks = self.update(ORB_ID.manual_control_setpoint)
        if fresh_sticks is not None and fresh_sticks.valid:
            # their age from when they came, on this clock: a source outside the lockstep (a ground station)
            # stamps them with the latest simulated time it saw, which lags
            self._last_manual_control = now
        sticks = latest(ORB_ID.manual_control_setpoint)
        airspeed = latest(ORB_ID.airspeed)
        validated = latest(ORB_ID.airspeed_validated)
        return CommanderInputs(
            attitude_timestamp_us=est.attitude_timestamp if est is not None and est.attitude_valid else 0,
            attitude_q=est.q if est is not None else (1.0, 0.0, 0.0, 0.0),
            angular_velocity_timestamp_us=est.angular_velocity_timestamp if est is not None else 0,
            local_position=latest(ORB_ID.vehicle_local_position),
            gyro_timestamp_us=imu.timestamp if imu is not None and imu.gyro_rate_hz > 0.0 else 0,
            accel_timestamp_us=imu.timestamp if imu is not None and imu.accel_rate_hz > 0.0 else 0,
            baro_timestamp_us=baro.timestamp if baro is not None else 0,
            mag_timestamp_us=mag.timestamp if mag is not None else 0,
            gps_timestamp_us=gps.timestamp if gps is not None else 0,
            gps_fix_type=gps.fix_type if gps is not None else 0,
            landed=land.landed,
            maybe_landed=land.maybe_landed,
            battery_warning=battery.warning if battery is not None else 0,
            last_gcs_heartbeat_us=self._last_gcs,
            last_manual_control_us=self._last_manual_control,
            manual_control_valid=sticks is not None and sticks.valid,
            mission_count=mission.seq_total if mission is not None and mission.valid else 0,
            mission_finished=mission is not None and mission.valid and mission.finished,
            external_autopilot=latest(ORB_ID.external_autopilot_status),
            airspeed_timestamp_us=airspeed.timestamp if airspeed is not None else 0,
            airspeed_validated_timestamp_us=validated.timestamp if validated is not None else 0,
            calibrated_airspeed=validated.calibrated_airspeed_m_s if validated is not None else math.nan,
        )

    def _land_inputs(self) -> LandDetectorInputs:
        latest = self.latest
        return land_detector.multicopter_inputs(
            self.commander.armed,
            self.commander.nav_state,
            latest(ORB_ID.vehicle_local_position),
            latest(ORB_ID.vehicle_imu_status),
            latest(ORB_ID.vehicle_thrust_setpoint),
            latest(ORB_ID.trajectory_setpoint),
            latest(ORB_ID.hover_thrust_estimate),
            latest(ORB_ID.takeoff_status),
        )

    def _fw_land_inputs(self) -> FixedwingLandDetectorInputs:
        latest = self.latest
        return fw_land_detector.fixedwing_inputs(
            self.commander.armed,
            self.commander.nav_state,
            latest(ORB_ID.vehicle_local_position),
            latest(ORB_ID.airspeed_validated),
            latest(ORB_ID.vehicle_imu_status),
            latest(ORB_ID.vehicle_thrust_setpoint),
        )
