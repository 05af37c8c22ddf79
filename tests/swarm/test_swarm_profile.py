"""A swarm's copies of a profile (stack.supervisor.swarm): names, MAVLink system ids and ports as PX4 multi-vehicle
SITL numbers them, homes spaced east, the others joining the first's bus; and what a profile cannot give a swarm,
refused before anything starts."""

import re

import pytest

from stack.mathlib.geo import MapProjection
from stack.params import catalogue
from stack.supervisor.profile import ProfileError, load_profile
from stack.supervisor.swarm import vehicle_copy, vehicle_names
from tests.support.harness import REPO, run_cli, write_profile

JOIN = "tcp/127.0.0.1:7447"


def entry(profile, name):
    return next(m for m in profile.modules if m.name == name)


def test_vehicle_i_is_named_numbered_and_linked_as_px4_sitl_instance_i_minus_1():
    base = load_profile("sitl_quad")
    first = vehicle_copy(base, 1, 3)  # the bus the others join (on one machine)
    third = vehicle_copy(base, 3, 3, JOIN)
    assert (first.vehicle, third.vehicle) == ("v1", "v3")
    assert first.bus.connect == base.bus.connect and third.bus.connect == (*base.bus.connect, JOIN)
    assert not first.bus.low_latency and not third.bus.low_latency
    assert vehicle_copy(base, 1, 3, JOIN).bus.connect == (*base.bus.connect, JOIN)  # a hub of machines' shares
    assert first.seed == base.seed and third.seed != base.seed and third.seed != vehicle_copy(base, 2, 3).seed
    for m in third.modules:
        if "MAV_SYS_ID" in {p.name for p in m.cls.PARAMS}:
            assert m.params["MAV_SYS_ID"] == 3, m.name
    assert entry(first, "mavlink_gcs").args == entry(base, "mavlink_gcs").args
    gcs, api = entry(third, "mavlink_gcs").args, entry(third, "mavlink_api").args
    assert (gcs["device"], gcs["remote"]) == ("udp:127.0.0.1:18572", "127.0.0.1:14550")
    assert (api["device"], api["remote"]) == ("udp:127.0.0.1:14582", "127.0.0.1:14542")
    sim = entry(third, "simulator").params
    home = (catalogue.get("SIH_LOC_LAT0").default, catalogue.get("SIH_LOC_LON0").default)
    north, east = MapProjection(*home).project(sim["SIH_LOC_LAT0"], sim["SIH_LOC_LON0"])
    assert north == pytest.approx(0.0, abs=1e-6) and east == pytest.approx(2 * base.swarm_spacing_m, abs=1e-6)
    assert "SIH_LOC_LAT0" not in entry(first, "simulator").params
    assert entry(base, "mavlink_api").args["device"] == "udp:127.0.0.1:14580"  # the profile itself is left as it was
    assert "MAV_SYS_ID" not in entry(base, "commander").params


def test_a_profile_names_its_vehicles_and_their_spacing(tmp_path):
    text = f'extends = "{REPO / "launch" / "sitl_quad.toml"}"\n[swarm]\nnames = ["alpha", "bravo"]\nspacing_m = 12\n'
    profile = load_profile(write_profile(tmp_path / "pair.toml", text))
    assert vehicle_names(profile, 2) == ["alpha", "bravo"]
    assert vehicle_copy(profile, 2, 2).vehicle == "bravo"
    assert profile.swarm_spacing_m == 12.0
    with pytest.raises(ValueError, match=r"\[swarm\] names 2 vehicles, not 3"):
        vehicle_names(profile, 3)
    # Each vehicle is a MAVLink system of its own: MAV_SYS_ID 1…250, as PX4's parameter allows.
    assert len(vehicle_names(load_profile("sitl_quad"), 250)) == 250
    with pytest.raises(ValueError, match=r"at most 250 vehicles, each its own MAVLink system \(MAV_SYS_ID\), not 251"):
        vehicle_names(load_profile("sitl_quad"), 251)


@pytest.mark.parametrize(
    ("swarm", "message"),
    [
        ('names = ["v1", "v1"]', "swarm.names: a vehicle is named twice"),
        ('names = ["a b"]', "swarm.names[0]: 'a b' is not a vehicle name"),
        ("spacing_m = 0", "swarm.spacing_m: expected metres above 0, got 0"),
        ("spacing = 3", "swarm.spacing: unknown key (expected one of: names, spacing_m)"),
    ],
)
def test_a_broken_swarm_table_names_the_key_and_the_problem(tmp_path, swarm, message):
    text = f'extends = "{REPO / "launch" / "sitl_quad.toml"}"\n[swarm]\n{swarm}\n'
    with pytest.raises(ProfileError, match=re.escape(message)):
        load_profile(write_profile(tmp_path / "broken.toml", text))


def test_links_a_swarm_cannot_share_are_refused(tmp_path):
    serial = '[[module]]\nname = "radio"\nmodule = "mavlink"\nargs = { device = "serial:/dev/ttyUSB0:57600" }\n'
    text = f'extends = "{REPO / "launch" / "sitl_quad.toml"}"\n{serial}'
    profile = load_profile(write_profile(tmp_path / "radio.toml", text))
    assert vehicle_copy(profile, 1, 2).vehicle == "v1"
    with pytest.raises(ValueError, match="radio: the vehicles of a swarm cannot share the serial link"):
        vehicle_copy(profile, 2, 2)
    with pytest.raises(ValueError, match="vehicle 3 of a swarm of 2"):
        vehicle_copy(profile, 3, 2)


def test_stack_up_refuses_a_swarm_it_cannot_start_before_starting_anything(tmp_path):
    home = tmp_path / "home"
    out = run_cli(home, "up", "--vehicles", "2", "--record", str(tmp_path / "flight.mcap"))
    assert out.returncode == 2
    assert out.stderr.strip() == (
        "error: --vehicles starts a swarm of whole vehicles on this machine: not with --record"
    )
    text = f'extends = "{REPO / "launch" / "sitl_quad.toml"}"\n[swarm]\nnames = ["alpha", "bravo"]\n'
    out = run_cli(home, "up", str(write_profile(tmp_path / "pair.toml", text)), "--vehicles", "3")
    assert out.returncode == 2
    assert out.stderr.strip() == f"error: {tmp_path / 'pair.toml'}: [swarm] names 2 vehicles, not 3"
    assert not (home / "runs").exists()


def test_a_swarm_scenarios_limits_and_choices_are_checked_with_the_profile(tmp_path):
    good = tmp_path / "good.toml"
    good.write_text(
        'extends = "sitl_quad"\n[scenario.swarm_formation]\nformation_error_max_m = 0.8\n'
        '[scenario.swarm_leader_loss]\non_leader_loss = "land"\n'
    )
    profile = load_profile(str(good))
    assert profile.scenario_limits["swarm_formation"] == {"formation_error_max_m": 0.8}
    assert profile.scenario_options["swarm_leader_loss"] == {"on_leader_loss": "land"}
    bad = tmp_path / "bad.toml"
    bad.write_text('extends = "sitl_quad"\n[scenario.swarm_leader_loss]\non_leader_loss = "panic"\n')
    said = "scenario.swarm_leader_loss.on_leader_loss: 'panic' is not one of hold, land"
    with pytest.raises(ProfileError, match=re.escape(said)):
        load_profile(str(bad))
