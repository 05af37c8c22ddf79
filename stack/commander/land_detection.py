"""PX4's land detector as the commander runs it: at 50 Hz, for the vehicle's type, published on change or at 1 Hz.

PX4's ``src/modules/land_detector`` runs every LAND_DETECTOR_UPDATE_INTERVAL (20 ms, ``LandDetector.h``) with the
detector of the vehicle's type (``MulticopterLandDetector``, ``FixedwingLandDetector``) and publishes
``vehicle_land_detected`` when one of its flags changes, or a second after the last publication
(``LandDetector.cpp``). The commander ticks at 100 Hz, so the detector runs on the first tick of each 20 ms
interval. The vehicle type can change only while disarmed (hence landed); the new type's detector takes over.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping

from stack.commander.fw_land_detector import FixedwingLandDetector, FixedwingLandDetectorInputs
from stack.commander.land_detector import PERIOD_US, LandDetectorInputs, LandDetectorState, MulticopterLandDetector
from stack.msg.system import VehicleLandDetected

REPUBLISH_US = 1_000_000


class LandDetection:
    """The detector of the vehicle's type, its 50 Hz schedule and when its result is published."""

    def __init__(self, params: Mapping[str, object], fixed_wing: bool) -> None:
        self._params = params
        self.detector = self._new_detector(fixed_wing)
        self._due = 0
        self._published: tuple[bool, ...] | None = None
        self._published_at = 0

    @property
    def state(self) -> LandDetectorState:
        return self.detector.state

    def set_params(self, params: Mapping[str, object]) -> None:
        self._params = params
        self.detector.set_params(params)

    def resume_in_air(self) -> None:
        """After a restart in flight (the commander resumed armed): start from in the air, not landed."""
        self.detector.resume_in_air()

    def republish(self) -> None:
        """Publish the result at the next run, changed or not (a late subscriber learns it at once)."""
        self._published = None

    def update(
        self,
        now: int,
        fixed_wing: bool,
        multicopter_inputs: Callable[[], LandDetectorInputs],
        fixedwing_inputs: Callable[[], FixedwingLandDetectorInputs],
    ) -> VehicleLandDetected | None:
        """On the first call of each 20 ms interval, run the detector; what to publish, or None."""
        if now < self._due:
            return None
        self._due = now - now % PERIOD_US + PERIOD_US
        if fixed_wing != isinstance(self.detector, FixedwingLandDetector):
            self.detector = self._new_detector(fixed_wing)
        if isinstance(self.detector, FixedwingLandDetector):
            state = self.detector.update(now, fixedwing_inputs())
        else:
            state = self.detector.update(now, multicopter_inputs())
        flags = (
            state.landed,
            state.freefall,
            state.maybe_landed,
            state.ground_contact,
            state.in_ground_effect,
            state.at_rest,
        )
        if flags == self._published and now - self._published_at < REPUBLISH_US:
            return None
        self._published = flags
        self._published_at = now
        return VehicleLandDetected(timestamp=now, **state._asdict())

    def _new_detector(self, fixed_wing: bool) -> MulticopterLandDetector | FixedwingLandDetector:
        return FixedwingLandDetector(self._params) if fixed_wing else MulticopterLandDetector(self._params)
