"""QGroundControl's .params files: what `stack param save` writes loads back exactly; bad lines are reported."""

from stack.params.catalogue import CATALOGUE
from stack.params.qgc_file import Entry, format_file, other_vehicle, parse_file


def test_a_saved_file_loads_back_exactly():
    values = {"MC_ROLLRATE_P": 0.3604, "LPE_ACC_XY": 1.2e-5, "NAV_DLL_ACT": 2, "MPC_USE_HTE": False}
    values["ATT_MAG_DECL"] = -3.2
    text = format_file(((n, v, CATALOGUE[n].mav_type) for n, v in values.items()), "v1", system_id=7)
    lines = text.splitlines()
    assert lines[0] == "# Onboard parameters for v1" and lines[4] == "# Vehicle-Id Component-Id Name Value Type"
    assert "7\t1\tMC_ROLLRATE_P\t0.3604\t9" in lines and "7\t1\tMPC_USE_HTE\t0\t6" in lines
    entries, problems = parse_file(text)
    assert problems == []
    assert {e.name: e.value for e in entries} == {**values, "MPC_USE_HTE": 0}
    assert {e.name: e.mav_type for e in entries} == {n: CATALOGUE[n].mav_type for n in values}


def test_a_file_as_qgroundcontrol_writes_it_is_read():
    text = (
        "# Onboard parameters for Vehicle 1\n#\n# Stack: PX4 Pro 1.15.0 Release\n"
        "# Vehicle-Id Component-Id Name Value Type\n"
        "1\t1\tMC_ROLLRATE_P\t0.150000005960464478\t9\n"
        "1\t1\tCOM_DLL_EXCEPT\t3\t6\n"
        "\n"
        "1\t1\tBAT1_N_CELLS\t4\t2\n"
    )
    entries, problems = parse_file(text)
    assert problems == []
    assert entries == [
        Entry(5, "MC_ROLLRATE_P", 0.150000005960464478, 9),
        Entry(6, "COM_DLL_EXCEPT", 3, 6),
        Entry(8, "BAT1_N_CELLS", 4, 2),
    ]


def test_lines_that_are_not_parameters_are_reported_with_their_number_and_the_rest_read():
    text = (
        "1\t1\tNAV_DLL_ACT\t2\t6\n"
        "1\t1\tNAV_DLL_ACT\t2\n"
        "one\t1\tNAV_DLL_ACT\t2\t6\n"
        "1\t1\tNAV DLL\t2\t6\n"
        "1\t1\tNAV_DLL_ACT\t2\tINT32\n"
        "1\t1\tNAV_DLL_ACT\t2\t11\n"
        "1\t1\tNAV_DLL_ACT\t2.5\t6\n"
        "1\t1\tMC_ROLL_P\tfast\t9\n"
        "1\t1\tMC_ROLL_P\t6.5\t9\n"
    )
    entries, problems = parse_file(text)
    assert [(e.line, e.name) for e in entries] == [(1, "NAV_DLL_ACT"), (9, "MC_ROLL_P")]
    assert [p.split(":")[0] for p in problems] == [f"line {n}" for n in range(2, 9)]
    assert "expected 5 tab-separated fields" in problems[0]
    assert "ids must be numbers" in problems[1]
    assert "is not a parameter name" in problems[2]
    assert "not a MAV_PARAM_TYPE number" in problems[3]
    assert "type 11 is not a MAV_PARAM_TYPE" in problems[4]
    assert "'2.5' is not an integer (INT32)" in problems[5]
    assert "'fast' is not a number (REAL32)" in problems[6]


def test_a_file_of_another_vehicle_is_named_as_such():
    text = format_file([("NAV_DLL_ACT", 2, 6), ("MAV_SYS_ID", 1, 6)], "v1", system_id=1)
    entries, _ = parse_file(text)
    assert [e.system_id for e in entries] == [1, 1] and other_vehicle(entries, 1) is None
    assert other_vehicle(entries, 2) == (
        "the parameters were saved from system id 1, but this vehicle's is 2 (MAV_SYS_ID)"
    )
    mixed, _ = parse_file(text + "3\t1\tNAV_DLL_ACT\t3\t6\n")
    assert other_vehicle(mixed, 1) == "the parameters were saved from system id 3, but this vehicle's is 1 (MAV_SYS_ID)"
