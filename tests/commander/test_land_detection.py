"""The land detector as the commander runs it: at 50 Hz on a 100 Hz tick, the detector of the vehicle's type,
``vehicle_land_detected`` on change or a second after the last (PX4 src/modules/land_detector/LandDetector.cpp)."""

import pytest

from stack.commander import land_detection
from stack.commander.fw_land_detector import FixedwingLandDetector, FixedwingLandDetectorInputs
from stack.commander.land_detection import REPUBLISH_US, LandDetection
from stack.commander.land_detector import LandDetectorInputs, LandDetectorState, MulticopterLandDetector

TICK_US = 10_000  # the commander's 100 Hz
LANDED = MulticopterLandDetector().state
FLYING = LANDED._replace(landed=False, maybe_landed=False, ground_contact=False, at_rest=False)


def no_plane() -> FixedwingLandDetectorInputs:
    raise AssertionError("a multicopter ran the fixed-wing detector")


def no_multicopter() -> LandDetectorInputs:
    raise AssertionError("a plane ran the multicopter detector")


class Detector:
    """The multicopter detector's results, scripted: ``results[now]`` from that time on."""

    def __init__(self, monkeypatch: pytest.MonkeyPatch, results: dict[int, LandDetectorState]) -> None:
        self.runs: list[int] = []
        self.results = sorted(results.items())

        def update(detector: MulticopterLandDetector, now: int, inputs: LandDetectorInputs) -> LandDetectorState:
            self.runs.append(now)
            detector.state = [state for since, state in self.results if since <= now][-1]
            return detector.state

        monkeypatch.setattr(MulticopterLandDetector, "update", update)


def tick(land: LandDetection, start: int, end: int, fixed_wing: bool = False) -> list[tuple[int, bool]]:
    """The commander's ticks from ``start`` to before ``end``: (time, landed) of each publication."""
    published = []
    for now in range(start, end, TICK_US):
        msg = land.update(now, fixed_wing, LandDetectorInputs, no_plane)
        if msg is not None:
            assert msg.timestamp == now
            published.append((now, msg.landed))
    return published


def test_runs_on_the_first_tick_of_each_twenty_milliseconds(monkeypatch):
    detector = Detector(monkeypatch, {0: LANDED})
    tick(LandDetection({}, fixed_wing=False), TICK_US, 110_000)
    assert detector.runs == [10_000, 20_000, 40_000, 60_000, 80_000, 100_000]


def test_published_at_the_first_run_then_a_second_later_while_nothing_changes(monkeypatch):
    Detector(monkeypatch, {0: LANDED})
    published = tick(LandDetection({}, fixed_wing=False), TICK_US, 2_500_000)
    # at the first run at least a second after the last publication (the runs are on the 20 ms grid)
    assert published == [(10_000, True), (20_000 + REPUBLISH_US, True), (20_000 + 2 * REPUBLISH_US, True)]


def test_a_change_is_published_at_the_run_that_sees_it(monkeypatch):
    Detector(monkeypatch, {0: LANDED, 300_000: FLYING, 500_000: FLYING._replace(in_ground_effect=True)})
    published = tick(LandDetection({}, fixed_wing=False), TICK_US, 700_000)
    assert published == [(10_000, True), (300_000, False), (500_000, False)]


def test_a_change_in_a_flag_not_published_waits_for_the_second(monkeypatch):
    Detector(monkeypatch, {0: LANDED, 300_000: LANDED._replace(in_descend=True)})
    assert tick(LandDetection({}, fixed_wing=False), TICK_US, 1_000_000) == [(10_000, True)]


def test_republish_sends_the_unchanged_result_at_the_next_run(monkeypatch):
    Detector(monkeypatch, {0: LANDED})
    land = LandDetection({}, fixed_wing=False)
    tick(land, TICK_US, 110_000)
    land.republish()
    assert tick(land, 110_000, 210_000) == [(120_000, True)]


def test_the_vehicle_types_detector_takes_over_with_the_parameters_in_force(monkeypatch):
    made: list[dict] = []

    class Recorded(FixedwingLandDetector):
        def __init__(self, params):
            made.append(dict(params))
            super().__init__(params)

    monkeypatch.setattr(land_detection, "FixedwingLandDetector", Recorded)
    land = LandDetection({"LNDFW_TRIG_TIME": 1.0}, fixed_wing=False)
    assert isinstance(land.detector, MulticopterLandDetector)
    land.set_params({"LNDFW_TRIG_TIME": 3.0})
    msg = land.update(TICK_US, True, no_multicopter, lambda: FixedwingLandDetectorInputs(armed=False))
    assert isinstance(land.detector, Recorded) and made == [{"LNDFW_TRIG_TIME": 3.0}]
    assert msg is not None and msg.landed


def test_a_restart_in_flight_starts_from_flying():
    land = LandDetection({}, fixed_wing=False)
    land.resume_in_air()
    assert not land.state.landed and not land.state.maybe_landed
