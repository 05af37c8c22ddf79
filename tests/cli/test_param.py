"""`stack param` against a running stack (the first-flight profile: simulator, estimator, commander, allocator,
attitude and rate controllers): one row per parameter, sets that reach every module that reads the parameter
or none, QGroundControl .params files, reset, patterns and names in any case."""

import json

import pytest

from stack.params.catalogue import CATALOGUE
from stack.params.client import matches
from tests.support.harness import RunningStack, attitude_only_profile, run_cli, wait_no_processes


@pytest.fixture(scope="module")
def stack(tmp_path_factory):
    tmp = tmp_path_factory.mktemp("param")
    home = tmp / "home"
    running = RunningStack(home, attitude_only_profile(tmp / "first_flight.toml"), "--speed", "1")
    running.wait_up()
    yield running
    assert running.stop() == 0
    assert not wait_no_processes(home)


def listing(stack: RunningStack, *args: str) -> dict[str, dict]:
    out = stack.cli("param", "list", "--json", *args)
    assert out.returncode == 0, out.stderr
    return {p["name"]: p for p in json.loads(out.stdout)}


def module_values(stack: RunningStack, name: str) -> dict[str, object]:
    out = stack.cli("param", "get", name, "--json")
    assert out.returncode == 0, out.stderr
    return json.loads(out.stdout)["module_values"]


def refusal(out, code: int = 1) -> str:
    assert out.returncode == code, (out.stdout, out.stderr)
    lines = out.stderr.strip().splitlines()
    assert len(lines) == 1, out.stderr
    return lines[0]


def test_one_row_per_parameter_with_its_owners_unit_description_and_meaning(stack):
    params = listing(stack)
    assert params["MC_AIRMODE"]["owners"] == ["control_allocator", "mc_att_control", "simulator"]
    assert params["SYS_FAILURE_EN"]["owners"] == ["commander", "simulator"]
    assert params["NAV_DLL_ACT"]["value"] == 2 and params["NAV_DLL_ACT"]["meaning"] == "Return mode"
    assert params["MC_ROLLRATE_MAX"]["unit"] == "deg/s" and params["MC_ROLLRATE_MAX"]["mav_type"] == 9
    table = stack.cli("param", "list", "NAV_DLL_ACT").stdout.splitlines()
    assert table[0].split() == ["NAME", "VALUE", "DEFAULT", "MIN", "MAX", "UNIT", "MODULES", "DESCRIPTION"]
    assert table[1].split()[:6] == ["*", "NAV_DLL_ACT", "2", "(Return", "mode)", "0"]
    assert "GCS connection loss failsafe action" in table[1]
    airmode = stack.cli("param", "list", "MC_AIRMODE").stdout.splitlines()
    assert len(airmode) == 3 and "control_allocator,mc_att_control,simulator" in airmode[1]
    assert airmode[2] == "1 parameters, 1 changed from default (*)"


def test_patterns_and_names_are_case_insensitive(stack):
    found = set(listing(stack, "mc_*p"))
    running = set(listing(stack))
    assert found == {n for n in running if matches("MC_*P", n)} and {"MC_ROLL_P", "MC_ROLLRATE_P"} <= found
    get = stack.cli("param", "get", "nav_dll_act")
    assert get.returncode == 0, get.stderr
    assert get.stdout.splitlines()[0] == "NAV_DLL_ACT = 2 (Return mode)  (commander)"
    assert "values 0 Disabled, 1 Hold mode, 2 Return mode, 3 Land mode, 5 Terminate, 6 Disarm" in get.stdout


def test_an_unknown_name_suggests_the_closest(stack):
    for command in (("get", "MC_ROLLRATE_PP"), ("set", "MC_ROLLRATE_PP", "0.2"), ("reset", "MC_ROLLRATE_PP")):
        line = refusal(stack.cli("param", *command))
        assert line == "error: no running module has a parameter 'MC_ROLLRATE_PP' (did you mean MC_ROLLRATE_P?)"


def test_a_set_reaches_every_module_that_reads_it(stack):
    out = stack.cli("param", "set", "MPC_THR_HOVER", "0.45")
    assert out.returncode == 0, out.stderr
    assert out.stdout.strip() == "MPC_THR_HOVER: 0.4903 -> 0.45  (commander, mc_att_control, simulator)"
    stack.wait_for(r"\[commander\] INFO\s+parameters changed: MPC_THR_HOVER=0.45")
    stack.wait_for(r"\[mc_att_control\] INFO\s+parameters changed: MPC_THR_HOVER=0.45")
    assert module_values(stack, "MPC_THR_HOVER") == {"commander": 0.45, "mc_att_control": 0.45, "simulator": 0.45}


def test_a_refused_set_changes_nothing_anywhere(stack):
    before = module_values(stack, "MPC_MANTHR_MIN")
    assert set(before) == {"commander", "mc_att_control", "simulator"}
    line = refusal(stack.cli("param", "set", "MPC_MANTHR_MIN", "1.5"))
    assert line.startswith("error: MPC_MANTHR_MIN: 1.5 is above the maximum 1") and "nothing changed" in line
    assert refusal(stack.cli("param", "set", "MC_AIRMODE", "3")).startswith("error: MC_AIRMODE: 3 is not one of")
    assert module_values(stack, "MPC_MANTHR_MIN") == before
    assert module_values(stack, "MC_AIRMODE") == {"control_allocator": 2, "mc_att_control": 2, "simulator": 2}


def test_a_negative_value_is_a_value_not_an_option(stack):
    line = refusal(stack.cli("param", "set", "MPC_THR_MIN", "-1"))
    assert line.startswith("error: MPC_THR_MIN: -1.0 is below the minimum 0.05")
    out = stack.cli("param", "set", "ATT_MAG_DECL", "-2.5")
    assert out.returncode == 0, out.stderr
    assert out.stdout.strip() == "ATT_MAG_DECL: 3.2 -> -2.5  (attitude_estimator_q)"
    assert stack.cli("param", "set", "ATT_MAG_DECL", "3.2").returncode == 0


def test_save_then_change_then_load_restores(stack, tmp_path):
    saved = tmp_path / "saved.params"
    out = stack.cli("param", "save", str(saved))
    assert out.returncode == 0, out.stderr
    lines = [line for line in saved.read_text().splitlines() if not line.startswith("#")]
    rows = {f[2]: f for f in (line.split("\t") for line in lines)}
    assert out.stdout.strip() == f"saved {len(rows)} parameters to {saved}" and len(rows) == len(listing(stack))
    assert rows["NAV_DLL_ACT"] == ["1", "1", "NAV_DLL_ACT", "2", "6"]
    assert rows["MC_ROLLRATE_P"][3:] == [repr(0.3604), "9"]
    assert all(int(f[4]) == CATALOGUE[name].mav_type for name, f in rows.items())
    before = listing(stack)
    for name, value in (("NAV_DLL_ACT", "3"), ("MC_ROLLRATE_P", "0.2"), ("MPC_MANTHR_MIN", "0.1")):
        assert stack.cli("param", "set", name, value).returncode == 0
    loaded = stack.cli("param", "load", str(saved))
    assert loaded.returncode == 0, loaded.stderr
    assert f"{saved}: 3 changed, {len(rows) - 3} unchanged, 0 refused, 0 unknown, 0 lines not parameters" in (
        loaded.stdout
    )
    assert "NAV_DLL_ACT: 3 (Land mode) -> 2 (Return mode)  (commander)" in loaded.stdout
    after = listing(stack)
    assert {n: p["module_values"] for n, p in after.items()} == {n: p["module_values"] for n, p in before.items()}


def test_a_file_saved_from_another_vehicle_sets_nothing(stack, tmp_path):
    # As QGroundControl refuses it: in a swarm, vehicle 2's file would give this one MAV_SYS_ID 2.
    other = tmp_path / "v2.params"
    other.write_text("2\t1\tMAV_SYS_ID\t2\t6\n2\t1\tNAV_DLL_ACT\t3\t6\n")
    out = stack.cli("param", "load", str(other))
    assert out.returncode == 1 and out.stdout == ""
    assert out.stderr.strip() == (
        f"error: {other}: the parameters were saved from system id 2, but this vehicle's is 1 (MAV_SYS_ID); nothing "
        "set (save the file from this vehicle, or change its Vehicle-Id column)"
    )
    assert module_values(stack, "NAV_DLL_ACT") == {"commander": 2}


def test_load_reports_every_bad_line_and_applies_the_others(stack, tmp_path):
    bad = tmp_path / "bad.params"
    bad.write_text(
        "# Vehicle-Id Component-Id Name Value Type\n"
        "1\t1\tNAV_DLL_ACT\t3\t6\n"
        "1\t1\tNAV_DLL_AC\t3\t6\n"
        "1\t1\tMC_AIRMODE\t4\t6\n"
        "1\t1\tMC_ROLL_P\t5\t6\n"
        "not a parameter line\n"
    )
    out = stack.cli("param", "load", str(bad))
    assert out.returncode == 1
    errors = out.stderr.strip().splitlines()
    assert errors[0].startswith("error: line 6: expected 5 tab-separated fields")
    assert "NAV_DLL_AC' (did you mean NAV_DLL_ACT?)" in errors[1]
    assert errors[2].startswith("error: MC_AIRMODE: 4 is not one of")
    assert errors[3] == "error: MC_ROLL_P: type 6 given, the parameter's is 9"
    assert "1 changed, 0 unchanged, 2 refused, 1 unknown, 1 lines not parameters" in out.stdout
    assert module_values(stack, "NAV_DLL_ACT") == {"commander": 3}
    assert module_values(stack, "MC_AIRMODE") == {"control_allocator": 2, "mc_att_control": 2, "simulator": 2}


def test_reset_goes_to_the_firmware_default_not_the_profiles_value(stack):
    out = stack.cli("param", "reset", "nav_dll_act")
    assert out.returncode == 0, out.stderr
    assert out.stdout.strip().endswith("-> 0 (Disabled)  (commander)")
    assert module_values(stack, "NAV_DLL_ACT") == {"commander": 0}
    usage = "error: give a parameter name or --all (not both)"
    assert refusal(stack.cli("param", "reset"), code=2) == usage
    assert refusal(stack.cli("param", "reset", "NAV_DLL_ACT", "--all"), code=2) == usage


def test_reset_all_leaves_nothing_changed_from_default(stack):
    assert listing(stack, "--changed")
    out = stack.cli("param", "reset", "--all")
    assert out.returncode == 0, out.stderr
    assert listing(stack, "--changed") == {}
    assert listing(stack)["CA_ROTOR_COUNT"]["value"] == 0


def test_help_of_every_subcommand(tmp_path):
    for sub in ((), ("list",), ("get",), ("set",), ("reset",), ("save",), ("load",)):
        out = run_cli(tmp_path, "param", *sub, "--help")
        assert out.returncode == 0, out.stderr
    reset = run_cli(tmp_path, "param", "reset", "--help").stdout
    assert "firmware default" in " ".join(reset.split())
