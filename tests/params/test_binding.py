"""The one way an algorithm takes its parameters (:mod:`stack.params.binding`): every parameter class holds the
catalogue's defaults, no class restates one, and a name the catalogue does not hold is refused at import."""

import dataclasses
import importlib
import inspect
import pkgutil

import pytest

import stack
from stack.params import catalogue
from stack.params.binding import ParamSet, combine, with_defaults
from stack.params.catalogue import CATALOGUE
from stack.params.param import Param, ParamError


def _import_every_module() -> list:
    return [
        importlib.import_module(m.name)
        for m in pkgutil.walk_packages(stack.__path__, "stack.")
        if not m.name.endswith("__main__")
    ]


MODULES = _import_every_module()


def _subclasses(cls: type) -> list[type]:
    direct = cls.__subclasses__()
    return direct + [s for d in direct for s in _subclasses(d)]


PARAM_SETS = sorted(
    (c for c in _subclasses(ParamSet) if c.__module__.startswith("stack.")), key=lambda c: c.__qualname__
)


def test_the_algorithms_take_their_parameters_through_param_sets():
    assert len(PARAM_SETS) >= 30, [c.__qualname__ for c in PARAM_SETS]


@pytest.mark.parametrize("cls", PARAM_SETS, ids=lambda c: f"{c.__module__}.{c.__qualname__}")
def test_every_parameter_class_defaults_to_the_catalogue(cls):
    defaults = cls()
    assert cls.PARAMS, f"{cls.__qualname__} reads no parameter"
    for p in cls.PARAMS:
        assert CATALOGUE[p.name] is p
    for f in dataclasses.fields(cls):
        value = getattr(defaults, f.name)
        if isinstance(value, ParamSet):
            assert value == type(value)(), f.name
            continue
        name = f.name.upper()
        if name in CATALOGUE:
            p = CATALOGUE[name]
            assert value == p.default and type(value) is p.type, f"{cls.__qualname__}.{f.name}"
    assert cls.from_params({p.name: p.default for p in cls.PARAMS}) == defaults


def _dataclasses_of_the_stack() -> list[type]:
    seen: dict[int, type] = {}
    for module in MODULES:
        for obj in vars(module).values():
            if isinstance(obj, type) and dataclasses.is_dataclass(obj) and obj.__module__.startswith("stack."):
                seen[id(obj)] = obj
    return list(seen.values())


NAMESAKES = {"stack.mavlink.presence._Peer.mav_type": "the MAV_TYPE a peer's HEARTBEAT reports, not the parameter"}


def test_no_other_dataclass_restates_a_catalogue_default():
    """A field named after a parameter, with a default of its own, is how a restated default drifts (NAV_ACC_RAD
    was once 10 m in one class and 2 m in the catalogue): outside a ParamSet there is none."""
    restating = [
        f"{cls.__module__}.{cls.__qualname__}.{f.name}"
        for cls in _dataclasses_of_the_stack()
        if not issubclass(cls, ParamSet)
        for f in dataclasses.fields(cls)
        if f.name.upper() in CATALOGUE and f.default is not dataclasses.MISSING
        and f"{cls.__module__}.{cls.__qualname__}.{f.name}" not in NAMESAKES
    ]
    assert restating == []


def _functions_of_the_stack() -> list:
    found: dict[int, object] = {}
    for module in MODULES:
        for obj in vars(module).values():
            if getattr(obj, "__module__", None) != module.__name__:
                continue
            if inspect.isfunction(obj):
                found[id(obj)] = obj
            elif inspect.isclass(obj) and not issubclass(obj, ParamSet):
                generated = {"__init__"} if dataclasses.is_dataclass(obj) else set()  # the dataclass test's
                found.update({id(f): f for n, f in vars(obj).items() if inspect.isfunction(f) and n not in generated})
    return list(found.values())


def test_no_function_restates_a_catalogue_default_as_a_keyword_default():
    """Nor does a keyword argument named after a parameter (``ATT_W_ACC: float = 0.2``) restate its default."""
    restating = [
        f"{f.__module__}.{f.__qualname__}({name})"
        for f in _functions_of_the_stack()
        for name, arg in inspect.signature(f).parameters.items()
        if name.upper() in CATALOGUE and arg.default is not inspect.Parameter.empty
    ]
    assert restating == []


def test_a_name_the_catalogue_does_not_hold_is_refused_when_the_class_is_defined():
    with pytest.raises(ParamError, match=r"unknown parameter 'MPC_THR_HOVR'.*MPC_THR_HOVER"):

        class Misspelt(ParamSet):
            mpc_thr_hovr: float


def test_a_restated_default_or_another_type_is_refused_when_the_class_is_defined():
    with pytest.raises(TypeError, match="MPC_THR_HOVER's default is the catalogue's"):

        class Restated(ParamSet):
            mpc_thr_hover: float = 0.5

    with pytest.raises(TypeError, match="MPC_THR_HOVER is a float in the catalogue, annotated int"):

        class Retyped(ParamSet):
            mpc_thr_hover: int


class Hover(ParamSet):
    mpc_thr_hover: float
    hte_acc_gate: float


class Controller(ParamSet):
    mpc_acc_decouple: int
    hover: Hover
    vehicle_type: int = 1


def test_a_param_set_reads_values_by_name_with_the_catalogue_type_and_defaults():
    c = Controller.from_params({"HTE_ACC_GATE": 2, "MPC_ACC_DECOUPLE": 0, "UNRELATED": 1})
    assert c == Controller(mpc_acc_decouple=0, hover=Hover(hte_acc_gate=2.0))
    assert type(c.hover.hte_acc_gate) is float and c.hover.mpc_thr_hover == 0.5 and c.vehicle_type == 1
    assert [p.name for p in Controller.PARAMS] == ["MPC_ACC_DECOUPLE", "MPC_THR_HOVER", "HTE_ACC_GATE"]
    with pytest.raises(dataclasses.FrozenInstanceError):
        c.vehicle_type = 2  # type: ignore[misc]


def test_combine_keeps_each_name_once_in_order_and_refuses_two_definitions():
    a, b = catalogue.params("MPC_THR_HOVER", "MPC_THR_MIN"), catalogue.params("MPC_THR_MIN", "MPC_THR_MAX")
    assert [p.name for p in combine(a, b)] == ["MPC_THR_HOVER", "MPC_THR_MIN", "MPC_THR_MAX"]
    with pytest.raises(ValueError, match="MPC_THR_MIN is defined twice"):
        combine(a, (Param("MPC_THR_MIN", 0.2, 0.0, 1.0),))


def test_a_family_indexed_at_run_time_takes_the_catalogue_defaults():
    rotor = catalogue.params("CA_ROTOR0_PX", "CA_ROTOR0_CT")
    assert with_defaults(rotor, {"CA_ROTOR0_PX": 0.2, "OTHER": 1}) == {"CA_ROTOR0_PX": 0.2, "CA_ROTOR0_CT": 6.5}
