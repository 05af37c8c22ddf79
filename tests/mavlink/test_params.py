"""The parameter protocol: bytewise INT32, consistent index and count, refusals and broadcasts."""

import math
import struct

import pytest
from pymavlink.dialects.v20 import common as M

from stack.mavlink.params import INT32, REAL32, ListJob, ParamProtocol, SetJob, decode, encode, float32_decimal
from stack.params import catalogue
from stack.params.catalogue import CATALOGUE
from stack.params.param import ParamError
from stack.params.store import ParamStore

OWN = (1, 1)
PARAMS = [
    ("MPC_XY_CRUISE", 5.0, False),
    ("COM_DL_LOSS_T", 10, True),
    ("A_VERY_LONG_PARAMETER_NAME", 1.0, False),
    ("MC_AIRMODE", 2, True),
    ("SYS_HAS_GPS", 1, True),
]


def _loaded(entries=PARAMS) -> ParamProtocol:
    proto = ParamProtocol(OWN)
    proto.refresh()
    assert proto.take_jobs() == [ListJob()]
    proto.on_list(entries)
    return proto


def _set(name: str, value: float, kind: int) -> M.MAVLink_param_set_message:
    return M.MAVLink_param_set_message(1, 1, name.encode(), value, kind)


@pytest.mark.parametrize("value", [0, 1, 4, -1, 21196, 2**31 - 1, -(2**31), 100001])
def test_integers_travel_bytewise(value):
    encoded, kind = encode(value, True)
    assert kind == INT32
    assert struct.pack("<f", encoded) == struct.pack("<i", value)
    assert decode(encoded, INT32) == value


def test_a_c_cast_4_is_not_what_the_bytes_say():
    assert encode(4, True)[0] != 4.0 and decode(4.0, INT32) == 1082130432


def test_floats_come_back_as_the_decimal_that_was_typed():
    single = struct.unpack("<f", struct.pack("<f", 0.2))[0]
    assert single != 0.2 and decode(single, REAL32) == 0.2
    for typed in (3.3, 0.001, 1e-7, 12345.6, -2.75):
        assert float32_decimal(struct.unpack("<f", struct.pack("<f", typed))[0]) == typed
    assert math.isnan(float32_decimal(math.nan))


def test_the_list_is_sorted_with_a_consistent_count_and_index_and_long_names_left_out():
    proto = _loaded()
    proto.on_request_list(M.MAVLink_param_request_list_message(1, 0))
    assert proto.take_jobs() == [ListJob()]
    proto.on_list(PARAMS)
    values = proto.take(100)
    assert [v.param_id for v in values] == ["COM_DL_LOSS_T", "MC_AIRMODE", "MPC_XY_CRUISE", "SYS_HAS_GPS"]
    assert [v.param_index for v in values] == [0, 1, 2, 3] and {v.param_count for v in values} == {4}
    assert [v.param_type for v in values] == [INT32, INT32, REAL32, INT32]
    assert proto.skipped == 1 and not proto.sending()


def test_a_listing_goes_out_at_the_pace_asked_answers_first():
    proto = _loaded()
    proto.on_request_list(M.MAVLink_param_request_list_message(0, 0))
    proto.take_jobs()
    proto.on_list(PARAMS)
    proto.on_request_read(M.MAVLink_param_request_read_message(1, 1, b"SYS_HAS_GPS", -1))
    first = proto.take(2)
    assert [v.param_id for v in first] == ["SYS_HAS_GPS", "COM_DL_LOSS_T"]
    assert len(proto.take(10)) == 3


def test_read_by_name_or_index_and_unknown_ones_ignored():
    proto = _loaded()
    proto.on_request_read(M.MAVLink_param_request_read_message(1, 1, b"MPC_XY_CRUISE", -1))
    proto.on_request_read(M.MAVLink_param_request_read_message(1, 1, b"", 0))
    proto.on_request_read(M.MAVLink_param_request_read_message(1, 1, b"NO_SUCH", -1))
    proto.on_request_read(M.MAVLink_param_request_read_message(1, 1, b"", 99))
    proto.on_request_read(M.MAVLink_param_request_read_message(2, 1, b"MPC_XY_CRUISE", -1))  # another system's
    values = [(v.param_id, decode(v.param_value, v.param_type)) for v in proto.take(10)]
    assert values == [("MPC_XY_CRUISE", 5.0), ("COM_DL_LOSS_T", 10)]
    assert proto.ignored == 2


def test_a_read_before_the_list_is_known_waits_for_it():
    proto = ParamProtocol(OWN)
    proto.on_request_read(M.MAVLink_param_request_read_message(1, 1, b"MC_AIRMODE", -1))
    assert proto.take_jobs() == [ListJob()] and proto.take(10) == []
    proto.on_list(PARAMS)
    (value,) = proto.take(10)
    assert (value.param_id, decode(value.param_value, value.param_type)) == ("MC_AIRMODE", 2)


def test_a_set_goes_to_the_source_and_its_new_value_comes_back():
    proto = _loaded()
    assert proto.on_set(_set("MPC_XY_CRUISE", 7.5, REAL32)) == ""
    assert proto.take_jobs() == [SetJob("MPC_XY_CRUISE", 7.5)]
    assert proto.on_set_result("MPC_XY_CRUISE", 7.5) == ""
    (value,) = proto.take(10)
    assert (value.param_id, value.param_value, value.param_index, value.param_count) == ("MPC_XY_CRUISE", 7.5, 2, 4)
    assert proto.on_set(_set("COM_DL_LOSS_T", encode(20, True)[0], INT32)) == ""
    assert proto.take_jobs() == [SetJob("COM_DL_LOSS_T", 20)]


def test_a_refused_set_answers_the_unchanged_value_and_says_why():
    proto = _loaded()
    proto.on_set(_set("COM_DL_LOSS_T", encode(1000, True)[0], INT32))
    reason = proto.on_set_result("COM_DL_LOSS_T", ParamError("1000 is above the maximum 300"))
    assert "COM_DL_LOSS_T not set: 1000 is above the maximum 300" in reason
    (value,) = proto.take(10)
    assert decode(value.param_value, value.param_type) == 10


class StoreSource:
    """The parameters of one module's store (the stack's modules check a set with the same definitions)."""

    def __init__(self, store: ParamStore) -> None:
        self.store = store

    def list(self):
        return [
            (name, value, self.store.definition(name).type is not float) for name, value in self.store.values().items()
        ]

    def set(self, name, value):
        return self.store.set(name, value)[1]


@pytest.mark.parametrize(
    ("name", "value", "why"),
    [
        ("MC_ROLLRATE_I", 2147483600.0, "2147483600.0 is above the maximum 2 (range 0 to 2)"),
        ("MC_PITCHRATE_D", 2147483600.0, "2147483600.0 is above the maximum 0.01 (range 0 to 0.01)"),
        ("MPC_LAND_SPEED", 2.1e9, "2100000000.0 is above the maximum 4 (range 0.6 to 4)"),
        ("RTL_RETURN_ALT", 3.4e38, "3.4e+38 is above the maximum 150 (range 0 to 150)"),
    ],
)
def test_a_param_set_the_vehicle_could_not_fly_with_is_refused_naming_the_range(name, value, why):
    source = StoreSource(
        ParamStore(catalogue.params("MC_ROLLRATE_I", "MC_PITCHRATE_D", "MPC_LAND_SPEED", "RTL_RETURN_ALT"))
    )
    proto = _loaded(source.list())
    single = struct.unpack("<f", struct.pack("<f", value))[0]  # what a ground station sends: REAL32
    assert proto.on_set(_set(name, single, REAL32)) == ""
    (job,) = proto.take_jobs()
    try:
        result = source.set(job.name, job.value)
    except ParamError as e:
        result = e
    assert isinstance(result, ParamError) and why in proto.on_set_result(name, result)
    (answer,) = proto.take(10)
    assert decode(answer.param_value, answer.param_type) == CATALOGUE[name].default
    assert source.store.set_count == 0


def test_a_wrong_type_or_an_unknown_name_is_refused_at_once():
    proto = _loaded()
    reason = proto.on_set(_set("COM_DL_LOSS_T", 20.0, REAL32))
    assert "it is INT32" in reason and proto.take_jobs() == []
    (value,) = proto.take(10)
    assert decode(value.param_value, value.param_type) == 10
    assert "no such parameter" in proto.on_set(_set("NO_SUCH", 1.0, REAL32))
    assert proto.take(10) == [] and proto.take_jobs() == []


def test_changes_made_elsewhere_are_broadcast_when_the_list_is_read_again():
    proto = _loaded()
    proto.refresh()
    proto.refresh()  # several parameter_update at once: one listing now, one after it
    assert proto.take_jobs() == [ListJob()]
    changed = [(n, 7.0 if n == "MPC_XY_CRUISE" else v, i) for n, v, i in PARAMS]
    proto.on_list(changed)
    (value,) = proto.take(10)
    assert (value.param_id, value.param_value) == ("MPC_XY_CRUISE", 7.0)
    assert proto.take_jobs() == [ListJob()]
