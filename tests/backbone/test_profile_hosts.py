"""A profile that spreads one vehicle over several machines: ``[hosts.NAME]`` and each module's ``host``, checked
before anything starts; ``stack up --host`` chooses a host's share, and the vehicle's parameters stay the vehicle's."""

import re

import pytest

from stack.bus.config import HOST_LINK_SEND_BUFFER_BYTES
from stack.bus.host_beats import DEFAULT_LEASE_MS
from stack.supervisor.profile import ProfileError, load_profile
from tests.support.harness import run_cli, write_profile

SPLIT = """
[stack]
vehicle = "t1"

[params]
TEST_OFFSET = 2.5

[hosts.sim]
endpoint = "tcp/10.0.0.1:7447"

[hosts.control]
endpoint = "tcp/10.0.0.2:7447"

[hosts.ground]
endpoint = "tcp/10.0.0.3:7447"

[[module]]
module = "tests.support.modules:TickSource"
host = "sim"

[[module]]
module = "tests.support.modules:Doubler"
host = "control"
"""


def test_each_module_runs_on_its_host_and_the_parameters_are_the_vehicles(tmp_path):
    p = load_profile(write_profile(tmp_path / "split.toml", SPLIT))
    assert {name: h.endpoint for name, h in p.hosts.items()} == {
        "sim": "tcp/10.0.0.1:7447",
        "control": "tcp/10.0.0.2:7447",
        "ground": "tcp/10.0.0.3:7447",
    }
    assert [(m.name, m.host) for m in p.modules] == [("tick_source", "sim"), ("doubler", "control")]
    # TEST_OFFSET is the doubler's, on another host than the tick source: still the vehicle's parameter
    assert p.modules[1].params == {"TEST_OFFSET": 2.5}
    assert p.hosts_with_modules() == ["sim", "control"]  # the ground host starts no module
    for host in p.hosts:
        p.check_host(host)


def test_a_hosts_router_listens_on_its_endpoint_and_connects_to_the_hosts_before_it_with_small_send_buffers(tmp_path):
    p = load_profile(write_profile(tmp_path / "split.toml", SPLIT + '\n[bus]\nconnect = ["tcp/10.0.0.9:7447"]\n'))
    small = f"#so_sndbuf={HOST_LINK_SEND_BUFFER_BYTES}"
    assert p.router_links("sim") == ((f"tcp/10.0.0.1:7447{small}",), ("tcp/10.0.0.9:7447",))  # the others connect
    control = ((f"tcp/10.0.0.2:7447{small}",), ("tcp/10.0.0.9:7447", f"tcp/10.0.0.1:7447{small}"))
    assert p.router_links("control") == control
    ground = p.router_links("ground")[1]
    assert ground == ("tcp/10.0.0.9:7447", f"tcp/10.0.0.1:7447{small}", f"tcp/10.0.0.2:7447{small}")
    assert p.router_link_count == 3  # each host's to the two others, and to 10.0.0.9


def test_the_host_lease_is_the_profiles_and_too_short_a_lease_is_refused(tmp_path):
    assert load_profile(write_profile(tmp_path / "a.toml", SPLIT)).host_lease_ms == DEFAULT_LEASE_MS
    longer = load_profile(write_profile(tmp_path / "b.toml", SPLIT + "\n[bus]\nhost_lease_ms = 2000\n"))
    assert longer.host_lease_ms == 2000
    assert longer.placement() == {"sim": ["tick_source"], "control": ["doubler"], "ground": []}
    with pytest.raises(ProfileError, match=r"c\.toml: bus\.host_lease_ms: 200 ms is shorter than 500 ms"):
        load_profile(write_profile(tmp_path / "c.toml", SPLIT + "\n[bus]\nhost_lease_ms = 200\n"))


def test_a_profile_of_one_machine_has_one_host():
    p = load_profile("sitl_quad")
    assert p.hosts == {} and p.hosts_with_modules() == ["local"] and {m.host for m in p.modules} == {""}
    p.check_host(None)
    with pytest.raises(ProfileError, match="runs on one machine"):
        p.check_host("sim")


@pytest.mark.parametrize(
    ("host", "problem"),
    [
        (None, "spread over hosts sim, control, ground; give --host NAME"),
        ("simm", "no such host (did you mean sim?); hosts: sim, control, ground"),
    ],
)
def test_the_host_to_run_is_named_and_known(tmp_path, host, problem):
    p = load_profile(write_profile(tmp_path / "split.toml", SPLIT))
    with pytest.raises(ProfileError, match=re.escape(problem)):
        p.check_host(host)


@pytest.mark.parametrize(
    ("change", "key", "problem"),
    [
        (('host = "control"', 'host = "controll"'), "module (doubler).host", "'controll' is not a host of this"),
        (('host = "control"\n', ""), "module (doubler).host", "missing: say which host runs it (sim, control, ground)"),
        (('host = "control"', "host = 2"), "module[1] (doubler).host", "expected str"),
        (('endpoint = "tcp/10.0.0.2:7447"', 'endpoint = "10.0.0.2:7447"'), "hosts.control.endpoint", "not a Zenoh"),
        (('endpoint = "tcp/10.0.0.2:7447"', 'endpoint = "tcp/10.0.0.2:0"'), "hosts.control.endpoint", "1 and 65535"),
        (('endpoint = "tcp/10.0.0.2:7447"', 'endpoint = "tcp/10.0.0.1:7447"'), "hosts.control.endpoint", "host sim's"),
        (('endpoint = "tcp/10.0.0.2:7447"', 'endpoint = "tcp/10.0.0.2:7447"\nport = 1'), "hosts.control.port", "unkno"),
        (('endpoint = "tcp/10.0.0.2:7447"\n', ""), "hosts.control.endpoint", "missing"),
        (("[hosts.ground]", '[hosts."gr/ound"]'), "hosts.gr/ound", "invalid host name"),
    ],
)
def test_a_broken_placement_is_refused_naming_file_key_and_problem(tmp_path, change, key, problem):
    path = write_profile(tmp_path / "broken.toml", SPLIT.replace(*change))
    with pytest.raises(ProfileError) as err:
        load_profile(path)
    message = str(err.value)
    assert message.startswith(f"{path}: {key}: ") and problem in message, message


def test_a_host_named_in_a_profile_of_one_machine_is_refused(tmp_path):
    one = '[[module]]\nmodule = "tests.support.modules:TickSource"\nhost = "sim"\n'
    path = write_profile(tmp_path / "one.toml", one)
    with pytest.raises(ProfileError, match=r"module \(tick_source\).host: 'sim': this profile declares no"):
        load_profile(path)


def test_stack_up_and_fly_refuse_a_split_profile_without_a_host(tmp_path):
    path = write_profile(tmp_path / "split.toml", SPLIT)
    up = run_cli(tmp_path, "up", str(path))
    assert up.returncode == 2 and "give --host NAME" in up.stderr
    wrong = run_cli(tmp_path, "up", str(path), "--host", "nowhere")
    assert wrong.returncode == 2 and "--host nowhere: no such host" in wrong.stderr
    fly = run_cli(tmp_path, "fly", "takeoff_land", "--profile", str(path))
    assert fly.returncode == 2 and "give --host NAME" in fly.stderr
    router = run_cli(tmp_path, "router", "sitl_quad", "--host", "sim")
    assert router.returncode == 2 and "runs on one machine" in router.stderr
