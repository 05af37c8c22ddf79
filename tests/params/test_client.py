"""The parameter client against parameter services over real Zenoh (in this process, on 127.0.0.1): one entry
per parameter with its owners, and a set that reaches every owner or none."""

import pytest
import zenoh

from stack.bus.config import BusConfig
from stack.bus.topics import MAX_SAMPLE_BYTES
from stack.params import catalogue, client
from stack.params.param import ParamError
from stack.params.store import ParamStore
from stack.runtime.services import ParamService
from stack.sim.module import SimulatorModule

VEHICLE = "tp1"
SHARED = catalogue.params("MPC_THR_HOVER", "MPC_MANTHR_MIN", "NAV_DLL_ACT")


class FailingStore(ParamStore):
    """Accepts every check, then fails to set: a module that stopped between the two phases."""

    def set(self, name, value):
        raise ParamError(f"{name}: the module is shutting down")


class Modules:
    """Parameter services of pretend modules, on one session that the client uses too."""

    def __init__(self, session: zenoh.Session) -> None:
        self.session = session
        self.services: list[ParamService] = []

    def serve(self, module: str, store: ParamStore) -> ParamStore:
        self.services.append(ParamService(self.session, VEHICLE, module, store))
        return store


@pytest.fixture
def modules():
    session = zenoh.open(BusConfig().zenoh_config("test_params_client"))
    m = Modules(session)
    yield m
    for service in m.services:
        service.close()
    session.close()


def test_one_entry_per_parameter_with_the_modules_that_read_it(modules):
    modules.serve("commander", ParamStore(SHARED))
    modules.serve("mc_att_control", ParamStore(SHARED[:2], {"MPC_THR_HOVER": 0.45}))
    params = {p.name: p for p in client.list_params(modules.session, VEHICLE)}
    assert list(params) == ["MPC_MANTHR_MIN", "MPC_THR_HOVER", "NAV_DLL_ACT"]
    assert params["MPC_MANTHR_MIN"].owners == ("commander", "mc_att_control") and params["MPC_MANTHR_MIN"].consistent
    assert params["NAV_DLL_ACT"].owners == ("commander",) and params["NAV_DLL_ACT"].param == SHARED[2]
    hover = params["MPC_THR_HOVER"]
    assert dict(hover.values) == {"commander": 0.5, "mc_att_control": 0.45} and not hover.consistent
    assert client.get_param(modules.session, VEHICLE, "nav_dll_act").name == "NAV_DLL_ACT"
    with pytest.raises(ParamError, match=r"no running module has a parameter 'NAV_DL_ACT' \(did you mean NAV_DLL_ACT"):
        client.get_param(modules.session, VEHICLE, "NAV_DL_ACT")


def test_a_set_reaches_every_module_that_reads_the_parameter(modules):
    a = modules.serve("commander", ParamStore(SHARED))
    b = modules.serve("mc_att_control", ParamStore(SHARED[:2], {"MPC_THR_HOVER": 0.45}))
    result = client.set_param(modules.session, VEHICLE, "mpc_thr_hover", "0.55")
    assert result == client.SetResult("MPC_THR_HOVER", {"commander": 0.5, "mc_att_control": 0.45}, 0.55)
    assert a.values()["MPC_THR_HOVER"] == b.values()["MPC_THR_HOVER"] == 0.55


def test_a_refused_value_changes_nothing_anywhere(modules):
    a = modules.serve("commander", ParamStore(SHARED))
    b = modules.serve("mc_att_control", ParamStore(SHARED[:2]))
    with pytest.raises(
        ParamError, match=r"MPC_THR_HOVER: 0.9 is above the maximum 0.8 \(range 0.1 to 0.8\) \(refused by commander"
    ):
        client.set_param(modules.session, VEHICLE, "MPC_THR_HOVER", 0.9)
    assert a.set_count == b.set_count == 0


def test_values_the_vehicle_could_not_fly_with_are_refused_by_set_and_by_load(modules):
    rate = catalogue.params("MC_ROLLRATE_I", "MC_PITCHRATE_D")
    landing = catalogue.params("MPC_LAND_SPEED", "RTL_RETURN_ALT")
    a = modules.serve("mc_rate_control", ParamStore(rate))
    b = modules.serve("flight_mode_manager", ParamStore(landing))
    with pytest.raises(ParamError, match=r"MC_ROLLRATE_I: 2147483600.0 is above the maximum 2 \(range 0 to 2\)"):
        client.set_param(modules.session, VEHICLE, "MC_ROLLRATE_I", 2147483600)
    with pytest.raises(ParamError, match=r"RTL_RETURN_ALT: 3.4e\+38 is above the maximum 150 \(range 0 to 150\)"):
        client.set_param(modules.session, VEHICLE, "RTL_RETURN_ALT", "3.4e38")
    report = client.set_many(
        modules.session, VEHICLE, [("MC_PITCHRATE_D", 2147483600.0, 9), ("MPC_LAND_SPEED", 2.1e9, 9)]
    )
    assert report.changed == [] and report.refused == [
        "MC_PITCHRATE_D: 2147483600.0 is above the maximum 0.01 (range 0 to 0.01)",
        "MPC_LAND_SPEED: 2100000000.0 is above the maximum 4 (range 0.6 to 4)",
    ]
    assert a.set_count == b.set_count == 0


def test_a_module_that_fails_to_take_a_checked_value_has_the_others_set_back(modules):
    a = modules.serve("a_commander", ParamStore(SHARED))
    modules.serve("b_failing", FailingStore(SHARED[:2]))
    why = r"shutting down \(refused by b_failing\); the modules already changed were set back"
    with pytest.raises(ParamError, match=why):
        client.set_param(modules.session, VEHICLE, "MPC_MANTHR_MIN", 0.1)
    assert a.set_count == 2 and a.values()["MPC_MANTHR_MIN"] == 0.08


def test_a_module_that_does_not_answer_fails_the_set_before_anything_changes(modules):
    a = modules.serve("commander", ParamStore(SHARED))
    ghost = client.StackParam(SHARED[0], {"commander": 0.5, "gone": 0.5})
    with pytest.raises(ParamError, match="module gone did not answer"):
        client.set_in_owners(modules.session, VEHICLE, ghost, 0.6, timeout=0.3)
    assert a.set_count == 0


def test_reset_goes_back_to_the_definitions_default(modules):
    a = modules.serve("commander", ParamStore(SHARED, {"NAV_DLL_ACT": 2, "MPC_THR_HOVER": 0.4}))
    assert client.reset_param(modules.session, VEHICLE, "NAV_DLL_ACT").new == 0
    done, refused = client.reset_all(modules.session, VEHICLE)
    assert [r.name for r in done] == ["MPC_THR_HOVER"] and refused == []
    assert a.values() == {p.name: p.default for p in SHARED}


def test_many_values_each_set_or_reported(modules):
    a = modules.serve("commander", ParamStore(SHARED))
    report = client.set_many(
        modules.session,
        VEHICLE,
        [
            ("NAV_DLL_ACT", 3, 6),
            ("MPC_MANTHR_MIN", 0.08, 9),
            ("MPC_THR_HOVER", 0.6, 6),
            ("MPC_THR_HOVER", 2.0, 9),
            ("MPC_THR_HOVR", 0.6, 9),
        ],
    )
    assert [r.name for r in report.changed] == ["NAV_DLL_ACT"] and report.unchanged == ["MPC_MANTHR_MIN"]
    assert report.refused == [
        "MPC_THR_HOVER: type 6 given, the parameter's is 9",
        "MPC_THR_HOVER: 2.0 is above the maximum 0.8 (range 0.1 to 0.8)",
    ]
    assert len(report.unknown) == 1 and "did you mean MPC_THR_HOVER?" in report.unknown[0]
    assert a.values()["NAV_DLL_ACT"] == 3 and a.values()["MPC_THR_HOVER"] == 0.5


def test_a_module_with_more_parameters_than_one_reply_carries_lists_them_all(modules):
    store = modules.serve("simulator", ParamStore(SimulatorModule.PARAMS))
    service = modules.services[-1]
    replies = service.replies(service.handle({"op": "list"}))
    assert len(replies) > 1 and all(len(r) < MAX_SAMPLE_BYTES for r in replies)
    params = client.list_params(modules.session, VEHICLE)
    assert [p.name for p in params] == sorted(store.defs) and all(p.owners == ("simulator",) for p in params)
