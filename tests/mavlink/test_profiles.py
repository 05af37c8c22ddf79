"""The ground-station links the shipped profiles start."""

from stack.params.catalogue import CATALOGUE
from stack.supervisor.profile import load_profile

MAV_TYPE = CATALOGUE["MAV_TYPE"]


def _links(profile: str) -> dict[str, dict]:
    return {m.name: m.args for m in load_profile(profile).modules if m.module == "mavlink"}


def test_sitl_quad_has_px4_sitls_two_links_on_loopback():
    links = _links("sitl_quad")
    assert (links["mavlink_gcs"]["device"], links["mavlink_gcs"]["remote"]) == (
        "udp:127.0.0.1:18570",
        "127.0.0.1:14550",
    )
    assert (links["mavlink_api"]["device"], links["mavlink_api"]["remote"]) == (
        "udp:127.0.0.1:14580",
        "127.0.0.1:14540",
    )
    assert all(not link["signing_key"] for link in links.values())


def test_the_vehicle_profiles_keep_the_links_and_say_what_they_are():
    assert _links("sitl_pelican") == _links("sitl_quad")
    assert _links("sitl_firefly") == _links("sitl_quad")
    # MAV_TYPE, the commander's and every link's, is one parameter: 13 (hexarotor) on the Firefly.
    for profile, mav_type in (("sitl_quad", 2), ("sitl_firefly", 13)):
        modules = [m for m in load_profile(profile).modules if m.module in ("mavlink", "commander")]
        assert len(modules) == 3 and {m.params.get("MAV_TYPE", MAV_TYPE.default) for m in modules} == {mav_type}


def test_a_companion_computer_has_a_gcs_link_and_no_api_link():
    for profile in ("pixhawk", "pixhawk_sim", "pixhawk_sim_pty"):
        assert list(_links(profile)) == ["mavlink_gcs"]
