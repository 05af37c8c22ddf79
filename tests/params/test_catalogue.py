"""The parameter catalogue: one definition per parameter, held by every module that reads it, and nothing
defined that no module reads; enum values, bitmasks and MAVLink types."""

import math
import re

import pytest

from stack.commander.failsafe import DLL_EXCEPT_AUTO_MODES, DLL_EXCEPT_MISSION
from stack.commander.geofence import GeofenceAction
from stack.commander.offboard import OffboardLossAction
from stack.estimator import position_kf
from stack.params import catalogue
from stack.params.catalogue import CATALOGUE
from stack.params.param import MAV_PARAM_TYPE_INT32, MAV_PARAM_TYPE_REAL32, Param, ParamError
from stack.params.store import ParamStore
from stack.pixhawk_sim import params as pixhawk_sim_params
from stack.posctl import flight_mode_manager
from stack.runtime.spec import MODULES, load_module_class

MODULE_CLASSES = {name: load_module_class(name) for name in MODULES}


@pytest.mark.parametrize("module", sorted(MODULES))
def test_every_parameter_a_module_reads_is_the_catalogue_definition(module):
    names = [p.name for p in MODULE_CLASSES[module].PARAMS]
    assert len(names) == len(set(names)), f"{module} declares a parameter twice"
    for p in MODULE_CLASSES[module].PARAMS:
        assert CATALOGUE.get(p.name) is p, f"{module}: {p.name} is not the catalogue's definition"


def test_every_catalogue_parameter_is_read_by_some_module():
    read = {p.name for cls in MODULE_CLASSES.values() for p in cls.PARAMS}
    assert sorted(set(CATALOGUE) - read) == []


def test_the_simulated_pixhawk_takes_the_catalogue_definition_of_every_parameter():
    for p in pixhawk_sim_params.PARAMS:
        assert CATALOGUE[p.name] is p
    simulated = set(OffboardLossAction) - {OffboardLossAction.RETURN}
    assert set(CATALOGUE["COM_OBL_RC_ACT"].values) == simulated


@pytest.mark.parametrize("name", sorted(CATALOGUE))
def test_each_definition_accepts_its_default_and_documents_itself(name):
    p = CATALOGUE[name]
    assert p.check(p.default) == p.default and type(p.check(p.default)) is p.type
    assert p.doc, f"{name} has no description"
    assert p.min is None or p.max is None or p.min <= p.max
    if p.values:
        assert p.default in p.values and all(p.values.values())
    assert p.mav_type == (MAV_PARAM_TYPE_REAL32 if p.type is float else MAV_PARAM_TYPE_INT32)


BOUNDED = sorted(CATALOGUE.values(), key=lambda p: p.name)


@pytest.mark.parametrize(
    "p", [p for p in BOUNDED if p.type is not bool and not p.values and not p.bits], ids=lambda p: p.name
)
def test_every_number_has_finite_bounds_around_its_default(p):
    """A parameter without a maximum (or a minimum) takes 2.1e9 from any ground station, and the vehicle tumbles:
    every number has both, from PX4's metadata where PX4 gives them (the group's module says where not)."""
    assert p.min is not None and p.max is not None, f"{p.name} has no range: give it PX4's @min and @max"
    assert math.isfinite(p.min) and math.isfinite(p.max) and p.min <= p.default <= p.max


EXTREMES = [
    ("MC_ROLLRATE_I", 2147483600, "above the maximum 2 (range 0 to 2)"),
    ("MC_PITCHRATE_D", 2147483600, "above the maximum 0.01 (range 0 to 0.01)"),
    ("MPC_LAND_SPEED", 2.1e9, "above the maximum 4 (range 0.6 to 4)"),
    ("RTL_RETURN_ALT", 3.4e38, "above the maximum 150 (range 0 to 150)"),
    ("RTL_RETURN_ALT", -1.0, "below the minimum 0 (range 0 to 150)"),
]


@pytest.mark.parametrize(("name", "value", "why"), EXTREMES)
def test_values_that_would_tumble_the_vehicle_are_refused_naming_the_range(name, value, why):
    with pytest.raises(ParamError) as err:
        CATALOGUE[name].check(value)
    assert str(err.value) == f"{name}: {float(value)!r} is {why}"
    store = ParamStore(catalogue.params(name))
    with pytest.raises(ParamError, match=re.escape(why)):
        store.set(name, value)
    assert store.values()[name] == CATALOGUE[name].default and store.set_count == 0
    with pytest.raises(ParamError, match=re.escape(why)):
        ParamStore(catalogue.params(name), {name: value})  # a profile's or a module's overrides


def test_no_parameter_is_a_string_and_the_mavlink_types_follow_the_python_types():
    assert {p.type for p in CATALOGUE.values()} == {bool, int, float}
    assert CATALOGUE["MPC_USE_HTE"].mav_type == MAV_PARAM_TYPE_INT32  # a bool is INT32 on MAVLink
    assert CATALOGUE["NAV_DLL_ACT"].mav_type == MAV_PARAM_TYPE_INT32  # so is an enum
    assert CATALOGUE["MC_ROLLRATE_P"].mav_type == MAV_PARAM_TYPE_REAL32
    with pytest.raises(TypeError, match="MAVLink has no other"):
        Param("SYS_NAME", "quad")


def test_enum_values_have_px4_meanings_and_nothing_else_is_accepted():
    nav_dll_act = CATALOGUE["NAV_DLL_ACT"]
    assert nav_dll_act.values == {
        0: "Disabled",
        1: "Hold mode",
        2: "Return mode",
        3: "Land mode",
        5: "Terminate",
        6: "Disarm",
    }
    assert nav_dll_act.meaning(2) == "Return mode" and nav_dll_act.check("2") == 2
    with pytest.raises(ParamError, match=r"4 is not one of 0 \(Disabled\), 1 \(Hold mode\)"):
        nav_dll_act.check(4)
    assert CATALOGUE["MC_AIRMODE"].meaning(2) == "Roll/Pitch/Yaw"
    assert CATALOGUE["COM_LOW_BAT_ACT"].meaning(3) == "Return at critical level, land at emergency level"
    assert CATALOGUE["MC_ROLLRATE_P"].meaning(0.2) == ""


def test_a_bitmask_names_its_bits_and_refuses_others():
    p = CATALOGUE["COM_DLL_EXCEPT"]
    assert p.meaning(3) == "Mission + Auto modes" and p.meaning(0) == "none"
    assert p.check(31) == 31
    with pytest.raises(ParamError, match="sets a bit other than"):
        p.check(32)


def test_the_code_constants_are_the_catalogue_values():
    assert {int(a) for a in GeofenceAction} == set(CATALOGUE["GF_ACTION"].values)
    yaw_modes = (
        flight_mode_manager.YAW_TOWARD_WAYPOINT,
        flight_mode_manager.YAW_TOWARD_HOME,
        flight_mode_manager.YAW_AWAY_FROM_HOME,
        flight_mode_manager.YAW_ALONG_TRAJECTORY,
        flight_mode_manager.YAW_HOLD,
    )
    assert set(yaw_modes) == set(CATALOGUE["MPC_YAW_MODE"].values)
    assert CATALOGUE["MPC_YAW_MODE"].values[flight_mode_manager.YAW_HOLD] == "hold heading"
    bits = CATALOGUE["COM_DLL_EXCEPT"].bits
    assert (bits[0], bits[1]) == ("Mission", "Auto modes")
    assert (DLL_EXCEPT_MISSION, DLL_EXCEPT_AUTO_MODES) == (1 << 0, 1 << 1)
    hgt_ref = CATALOGUE["EKF2_HGT_REF"].values
    assert hgt_ref[position_kf.HGT_REF_BARO] == "Barometric pressure" and hgt_ref[position_kf.HGT_REF_GPS] == "GPS"


def test_declarations_that_disagreed_take_px4s_metadata():
    assert (CATALOGUE["MPC_THR_MIN"].min, CATALOGUE["MPC_THR_MIN"].max) == (0.05, 0.5)
    assert (CATALOGUE["MPC_LAND_SPEED"].min, CATALOGUE["MPC_LAND_SPEED"].max) == (0.6, 4.0)
    assert (CATALOGUE["MPC_MAN_TILT_MAX"].min, CATALOGUE["MPC_MAN_TILT_MAX"].max) == (1.0, 70.0)
    assert CATALOGUE["MPC_USE_HTE"].type is bool


def test_lookup_by_name_suggests_the_closest_name():
    assert catalogue.params("MPC_THR_MIN", "NAV_DLL_ACT") == (CATALOGUE["MPC_THR_MIN"], CATALOGUE["NAV_DLL_ACT"])
    with pytest.raises(ParamError, match=r"unknown parameter 'MPC_THR_MN' \(did you mean MPC_THR_MIN\?\)"):
        catalogue.get("MPC_THR_MN")
    with pytest.raises(ParamError, match=r"did you mean MC_ROLLRATE_P\?"):
        catalogue.get("mc_rollrate_pp")


def test_a_definition_survives_the_wire():
    for p in CATALOGUE.values():
        assert Param.from_description(p.describe()) == p
