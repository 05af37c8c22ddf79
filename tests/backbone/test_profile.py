"""Launch profiles: checked before anything starts; a problem names the file, the key and what is wrong."""

import sys

import pytest

from stack.params.param import Param, ParamError
from stack.params.store import ParamStore
from stack.supervisor.profile import ProfileError, load_profile
from tests.support.harness import run_cli, write_profile

GOOD = """
[stack]
vehicle = "t1"
seed = 3

[params]
TEST_OFFSET = 2.5

[[module]]
module = "tests.support.modules:TickSource"
args = { rate_hz = 100.0 }
params = { TEST_GAIN = 2.0 }
critical = true

[[module]]
module = "tests.support.modules:Doubler"
restart = "on-failure"

[[module]]
name = "pacer_when_plotting"
module = "tests.support.modules:Pacer"
condition = "plot and TEST_OFFSET > 1"
"""


def test_a_good_profile_loads_in_order_with_parameters(tmp_path):
    p = load_profile(write_profile(tmp_path / "good.toml", GOOD))
    assert [m.name for m in p.modules] == ["tick_source", "doubler"]
    assert p.vehicle == "t1" and p.seed == 3 and p.lockstep
    tick, doubler = p.modules
    assert tick.params == {"TEST_GAIN": 2.0} and tick.args["rate_hz"] == 100.0 and tick.critical
    assert doubler.params == {"TEST_OFFSET": 2.5} and doubler.restart == "on-failure"
    with_plot = load_profile(tmp_path / "good.toml", flags={"plot": True, "realtime": True})
    assert [m.name for m in with_plot.modules] == ["tick_source", "doubler", "pacer_when_plotting"]
    assert not with_plot.lockstep
    assert p.open_topics == ()
    opened = load_profile(write_profile(tmp_path / "open.toml", GOOD.replace("seed = 3", 'open_topics = ["wind"]')))
    assert opened.open_topics == ("wind",)


@pytest.mark.parametrize(
    ("change", "key", "problem"),
    [
        (("seed = 3", "seed = 3\nseed = 4"), "", "TOML syntax error"),
        (("tests.support.modules:Doubler", "tests.support.modules:Nope"), "module[1].module", "cannot be loaded"),
        (("tests.support.modules:Doubler", "no_such_module"), "module[1].module", "unknown module 'no_such_module'"),
        (("TEST_GAIN = 2.0", "TEST_GAN = 2.0"), "module[0] (tick_source).params.TEST_GAN", "no such parameter"),
        (("TEST_GAIN = 2.0", 'TEST_GAIN = "high"'), "module[0] (tick_source).params.TEST_GAIN", "expected a number"),
        (("TEST_GAIN = 2.0", "TEST_GAIN = 20.0"), "module[0] (tick_source).params.TEST_GAIN", "above the maximum 10"),
        (("TEST_OFFSET = 2.5", "TEST_OFFSET = -200"), "params.TEST_OFFSET", "below the minimum -100"),
        (("TEST_OFFSET = 2.5", "TEST_OFFSET = 2.5\nMC_ROLL_P = 1.0"), "params.MC_ROLL_P", "no module of this profile"),
        (("rate_hz = 100.0", "rate = 100.0"), "module[0] (tick_source).args", "unknown argument 'rate'"),
        (('restart = "on-failure"', 'restart = "sometimes"'), "module[1] (doubler).restart", "not one of"),
        (('vehicle = "t1"', 'vehicle = "my/drone"'), "stack.vehicle", "invalid vehicle name"),
        (("seed = 3", "seed = 3\ncolour = 1"), "stack.colour", "unknown key"),
        (("critical = true", "critical = 1"), "module[0] (tick_source).critical", "expected bool"),
        (('"plot and TEST_OFFSET > 1"', '"plot and WHATEVER"'), "module[2] (pacer_when_plotting).condition", "unknown"),
        (('"plot and TEST_OFFSET > 1"', '"import os"'), "module[2] (pacer_when_plotting).condition", "cannot parse"),
        (("seed = 3", 'seed = 3\nopen_topics = ["vehicle_atitude"]'), "stack.open_topics[0]", "vehicle_attitude?)"),
        (("seed = 3", 'seed = 3\nopen_topics = "vehicle_attitude"'), "stack.open_topics", "expected list"),
    ],
)
def test_a_broken_profile_is_refused_naming_file_key_and_problem(tmp_path, change, key, problem):
    path = write_profile(tmp_path / "broken.toml", GOOD.replace(*change))
    with pytest.raises(ProfileError) as err:
        load_profile(path)
    message = str(err.value)
    assert "\n" not in message
    assert message.startswith(f"{path}: {key}: " if key else f"{path}: ")
    assert problem in message


def test_a_profile_extends_another_giving_only_what_differs(tmp_path):
    write_profile(tmp_path / "good.toml", GOOD)
    child = write_profile(
        tmp_path / "child.toml",
        """extends = "good"
[stack]
seed = 9

[params]
TEST_OFFSET = 4.0

[[module]]
module = "tests.support.modules:TickSource"
params = { TEST_GAIN = 3.0 }

[[module]]
module = "tests.support.modules:Summer"
""",
    )
    p = load_profile(child)
    assert p.vehicle == "t1" and p.seed == 9
    assert [m.name for m in p.modules] == ["tick_source", "doubler", "summer"]
    tick, doubler, _ = p.modules
    assert tick.params == {"TEST_GAIN": 3.0} and tick.args["rate_hz"] == 100.0 and tick.critical
    assert doubler.params == {"TEST_OFFSET": 4.0} and doubler.restart == "on-failure"
    assert load_profile(tmp_path / "good.toml").seed == 3


def test_the_vehicle_profiles_extend_sitl_quad_changing_only_airframe_and_tuning():
    quad = load_profile("sitl_quad")
    for name in ("sitl_hummingbird", "sitl_pelican", "sitl_firefly"):
        vehicle = load_profile(name)
        assert [m.name for m in vehicle.modules] == [m.name for m in quad.modules]
        assert vehicle.modules[0].args["vehicle"] == vehicle.airframe != quad.airframe
        commander = next(m for m in vehicle.modules if m.name == "commander")
        assert commander.params["NAV_DLL_ACT"] == 2  # inherited failsafe setting
        rate = next(m for m in vehicle.modules if m.name == "mc_rate_control")
        assert (
            rate.params["MC_ROLLRATE_K"]
            != next(m for m in quad.modules if m.name == "mc_rate_control").params["MC_ROLLRATE_K"]
        )


@pytest.mark.parametrize(
    ("child", "problem"),
    [
        ('extends = "nowhere"\n', "extends: no such profile 'nowhere'"),
        ("extends = 3\n", "extends: expected a profile name or path"),
        ('extends = "child"\n', "extends: 'child' leads back to this profile"),
    ],
)
def test_a_broken_extends_is_refused_naming_the_file(tmp_path, child, problem):
    path = write_profile(tmp_path / "child.toml", child)
    with pytest.raises(ProfileError) as err:
        load_profile(path)
    assert str(err.value).startswith(f"{path}: ")
    assert problem in str(err.value)


def test_a_problem_in_an_extended_profile_names_both_files(tmp_path):
    base = write_profile(tmp_path / "good.toml", GOOD)
    child = write_profile(tmp_path / "child.toml", 'extends = "good"\n[params]\nTEST_OFFSET = 500\n')
    with pytest.raises(ProfileError) as err:
        load_profile(child)
    assert str(err.value).startswith(f"{child} (extends {base}): params.TEST_OFFSET: ")


def test_stack_up_refuses_a_broken_profile_before_starting_anything(tmp_path):
    path = write_profile(tmp_path / "broken.toml", GOOD.replace("TEST_GAIN = 2.0", "TEST_GAIN = 20.0"))
    home = tmp_path / "home"
    out = run_cli(home, "up", str(path), "--duration", "1")
    assert out.returncode == 2
    assert out.stderr.strip().splitlines() == [
        f"error: {path}: module[0] (tick_source).params.TEST_GAIN: 20.0 is above the maximum 10 (range -10 to 10)"
    ]
    assert not (home / "runs").exists()


def test_unknown_profile_lists_the_available_ones(tmp_path):
    out = run_cli(tmp_path / "home", "up", "no_such_profile")
    assert out.returncode == 2 and "no such profile" in out.stderr


def test_a_misspelled_profile_scenario_or_topic_gets_the_closest_name(tmp_path):
    home = tmp_path / "home"
    for args, said in (
        (("up", "sitl_quadd"), "launch/sitl_quadd.toml: no such profile (did you mean sitl_quad?) (available: "),
        (("fly", "takeof_land"), "unknown scenario 'takeof_land' (did you mean takeoff_land?) (known: "),
        (("topic", "info", "vehicle_attitud"), "unknown topic 'vehicle_attitud' (did you mean vehicle_attitude?)"),
    ):
        out = run_cli(home, *args)
        assert out.returncode != 0 and out.stderr.startswith(f"error: {said}"), (args, out.stderr)


def test_parameter_checks():
    p = Param("MC_ROLLRATE_P", 0.15, 0.01, 0.5)
    assert p.check("0.2") == 0.2 and p.check(0.3) == 0.3
    for bad, why in ((0.6, "above the maximum"), (float("nan"), "not a finite"), (True, "expected a number")):
        with pytest.raises(ParamError, match=why):
            p.check(bad)
    mode = Param("MC_AIRMODE", 0, 0, 2)
    assert mode.check("2") == 2
    with pytest.raises(ParamError, match="expected an integer"):
        mode.check(1.5)
    flag = Param("SYS_HAS_MAG", True)
    assert flag.check("false") is False and flag.check(1) is True


def test_parameter_store_applies_changes_between_runs():
    store = ParamStore((Param("A", 1.0, 0, 10), Param("B", 2, 0, 5)), {"A": 3.0})
    assert store["A"] == 3.0
    assert store.set("A", 4) == (3.0, 4.0)
    assert store["A"] == 3.0 and store.values()["A"] == 4.0  # pending until the loop takes it
    assert store.take_changes() == {"A"} and store["A"] == 4.0
    assert store.take_changes() == set()
    with pytest.raises(ParamError):
        store.set("B", 9)
    assert store.values()["B"] == 2


@pytest.mark.parametrize(
    ("text", "problem"),
    [
        ("a = " + "[" * 10_000 + "]" * 10_000, "arrays or inline tables nested too deeply to read"),
        ("a = " + "{ b = " * 10_000 + "1" + " }" * 10_000, "arrays or inline tables nested too deeply to read"),
        ("a = " + "[" * 40 + "]" * 40, "a" + "[0]" * 32 + ": nested more than 32 levels deep"),
        ("[params." + ".".join(["a"] * 10_000) + "]\nb = 1", "params.a.a.a"),
    ],
    ids=["array", "inline_table", "array_40", "table"],
)
def test_a_deeply_nested_profile_is_refused_in_one_line(tmp_path, text, problem):
    path = write_profile(tmp_path / "deep.toml", text + "\n" + GOOD)
    with pytest.raises(ProfileError) as err:
        load_profile(path)
    message = str(err.value)
    assert message.startswith(f"{path}: ") and problem in message and "\n" not in message


def test_a_deeply_nested_extended_profile_is_refused_before_merging(tmp_path):
    # Merging walks both documents: the same deep table in both would recurse once per level.
    deep = "[params." + ".".join(["a"] * 10_000) + "]\nb = 1\n"
    base = write_profile(tmp_path / "good.toml", GOOD + deep)
    child = write_profile(tmp_path / "child.toml", 'extends = "good"\n' + deep)
    home = tmp_path / "home"
    out = run_cli(home, "up", str(child), "--duration", "1")
    assert out.returncode == 2
    lines = out.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith(f"error: {child}: params.a.a.a"), out.stderr
    assert "nested more than 32 levels deep" in lines[0] and str(base) not in lines[0]
    assert not (home / "runs").exists()


def plugin_package(root, marker):
    """A package on the path whose every file, when imported, appends its name to ``marker``."""
    package = root / "plugins_here"
    package.mkdir()
    run = f"open({str(marker)!r}, 'a').write(__name__ + '\\n')\n"
    (package / "__init__.py").write_text(run)
    (package / "tools.py").write_text(run + "class Helper:\n    pass\n")
    (package / "broken.py").write_text(run + "class Helper:\n    pass\n\nraise RuntimeError('no hardware here')\n")
    return package


@pytest.mark.parametrize(
    ("ref", "problem", "ran"),
    [
        ("plugins_here.missing:Thing", "no module 'plugins_here.missing' is installed or on the path", []),
        ("plugins_here.tools:Nope", "defines no 'Nope'", []),
        ("plugins_here.tools.deeper:Nope", "no module 'plugins_here.tools.deeper' is installed or on the path", []),
        ("plugins_here:Thing; import os", "unknown module", []),
        ("plugins_here.tools:Helper", "is not a stack Module class", ["plugins_here", "plugins_here.tools"]),
        ("plugins_here.broken:Helper", "RuntimeError: no hardware here", ["plugins_here", "plugins_here.broken"]),
    ],
    ids=["no_module", "no_class", "below_a_module", "not_a_path", "not_a_module_class", "raises_on_import"],
)
def test_a_module_path_is_checked_before_its_code_runs(tmp_path, monkeypatch, ref, problem, ran):
    marker = tmp_path / "ran.txt"
    plugin_package(tmp_path, marker)
    monkeypatch.syspath_prepend(str(tmp_path))
    for name in [m for m in sys.modules if m.startswith("plugins_here")]:
        monkeypatch.delitem(sys.modules, name)
    path = write_profile(tmp_path / "plugin.toml", f'[stack]\nvehicle = "t1"\n\n[[module]]\nmodule = "{ref}"\n')
    with pytest.raises(ProfileError) as err:
        load_profile(path)
    message = str(err.value)
    assert message.startswith(f"{path}: module[0].module: ") and problem in message and "\n" not in message
    assert (marker.read_text().split() if marker.exists() else []) == ran


def test_stack_up_refuses_a_module_that_fails_on_import_in_one_line(tmp_path, monkeypatch):
    plugin_package(tmp_path, tmp_path / "ran.txt")
    monkeypatch.setenv("PYTHONPATH", str(tmp_path))
    text = '[stack]\nvehicle = "t1"\n\n[[module]]\nmodule = "plugins_here.broken:Helper"\n'
    path = write_profile(tmp_path / "plugin.toml", text)
    home = tmp_path / "home"
    out = run_cli(home, "up", str(path), "--duration", "1")
    assert out.returncode == 2
    assert out.stderr.strip().splitlines() == [
        f"error: {path}: module[0].module: module 'plugins_here.broken:Helper' cannot be loaded from "
        "plugins_here.broken:Helper: "
        "RuntimeError: no hardware here"
    ]
    assert not (home / "runs").exists()


def test_a_profile_chooses_a_scenarios_options_and_a_wrong_one_is_refused_before_anything_starts(tmp_path):
    c172 = load_profile("jsbsim_c172")
    assert c172.scenario_options == {"plane_mission": {"mission": "c172_rectangle"}}
    assert load_profile("sitl_plane").scenario_options == {}
    for table, problem in (
        (
            'mission = "c172_rectangel"',
            "scenario.plane_mission.mission: c172_rectangel: no such mission file (did you mean c172_rectangle?)",
        ),
        ("mission = 3", "scenario.plane_mission.mission: expected a string"),
        ("missions = 'box'", "scenario.plane_mission.missions: not a check or option of plane_mission ("),
    ):
        path = write_profile(tmp_path / "plane.toml", f'extends = "sitl_plane"\n[scenario.plane_mission]\n{table}\n')
        with pytest.raises(ProfileError) as err:
            load_profile(path)
        assert problem in str(err.value), str(err.value)
