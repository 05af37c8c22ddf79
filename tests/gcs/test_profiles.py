"""The ground-station links the shipped profiles start."""

from stack.supervisor.profile import load_profile


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
    assert all(link["mav_type"] == 2 and not link["signing_key"] for link in links.values())


def test_the_vehicle_profiles_keep_the_links_and_say_what_they_are():
    assert _links("sitl_pelican") == _links("sitl_quad")
    assert {name: link["mav_type"] for name, link in _links("sitl_firefly").items()} == {
        "mavlink_gcs": 13,
        "mavlink_api": 13,
    }


def test_a_companion_computer_has_a_gcs_link_and_no_api_link():
    for profile in ("pixhawk", "pixhawk_sim", "pixhawk_sim_pty"):
        assert list(_links(profile)) == ["mavlink_gcs"]
