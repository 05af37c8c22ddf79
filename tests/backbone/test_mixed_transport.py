"""One lockstep run on two transports: members given ``transport = "zenoh"`` take part in a shared-memory run over
Zenoh, as modules on another host must (stack.fastpath.bridge). The run's behaviours on the mixed transport (the
same trace, a member that dies, restarts or stalls, an attack on the bus) are in test_lockstep; the default quad
with its position chain over Zenoh flies bit for bit the shared-memory flight in tests/flight/test_determinism."""

import pytest

from stack.supervisor.profile import ProfileError, load_profile
from tests.support.harness import RunningStack, chain_profile, eventually, wait_no_processes, write_profile


def test_the_supervisor_says_who_takes_part_over_zenoh_and_they_run_in_their_own_processes(tmp_path):
    home = tmp_path / "home"
    stack = RunningStack(home, chain_profile(tmp_path / "chain.toml", transport="mixed"))
    try:
        stack.wait_up()
        stack.wait_for(r"lockstep members over Zenoh: doubler, pacer")
        stack.wait_for(r"lockstep starting with doubler, pacer, summer, tick_source \(shared-memory fast path\)")
        assert "over Zenoh in the shared-memory lockstep: doubler, pacer" in stack.output
        rows = {}

        def heard_from_every_module() -> bool:  # a module's heartbeat comes about once a second
            rows.update((m["module"], m) for m in stack.status()["modules"])
            return all("trigger" in row for row in rows.values())

        eventually(heard_from_every_module, 30.0, "a heartbeat from every module")
        assert rows["doubler"]["trigger"] == "on sensor_gyro"
        assert len({m["pid"] for m in rows.values()}) == 4
    finally:
        assert stack.stop() == 0
    assert not wait_no_processes(home)


@pytest.mark.parametrize(
    ("entry", "problem"),
    [
        ('module = "simulator"\nname = "sim2"\ntransport = "zenoh"', "sim2 is the lockstep's coordinator"),
        ('module = "recorder"\ntransport = "zenoh"', "recorder is not a lockstep member"),
        ('module = "mavlink"\ntransport = "zenoh"', "mavlink is not a lockstep member"),
        ('module = "commander"\ntransport = "udp"', "'udp' is not one of shm, zenoh"),
        ('module = "commander"\ntransport = "zenoh"\nprocess = "p"', "commander over Zenoh runs in its own process"),
    ],
)
def test_a_transport_a_module_cannot_take_is_refused_naming_the_key(tmp_path, entry, problem):
    path = write_profile(
        tmp_path / "mixed.toml", f'[stack]\nlockstep = true\n[[module]]\nmodule = "simulator"\n[[module]]\n{entry}\n'
    )
    with pytest.raises(ProfileError) as refused:
        load_profile(path)
    assert f"{path}: module[1] (" in str(refused.value) and ").transport: " in str(refused.value)
    assert problem in str(refused.value)
