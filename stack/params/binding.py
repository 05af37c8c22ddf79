"""An algorithm's parameters, bound to the catalogue: the one way a library class takes its parameters.

A :class:`ParamSet` subclass names the parameters it reads as its fields, each the parameter's name in lower
case, annotated with the catalogue's type; the catalogue (:mod:`stack.params.catalogue`) gives each its
default, so no algorithm restates one::

    class HoverParams(ParamSet):
        mpc_thr_hover: float
        hte_acc_gate: float

    HoverParams()                              # the catalogue's defaults
    HoverParams.from_params(module.params)     # the values a module holds, by PX4 name
    HoverParams.PARAMS                         # their definitions, for a module's PARAMS

The class becomes a frozen dataclass. A name the catalogue does not hold, a type other than the catalogue's
and a default written for a catalogue parameter are refused when the class is defined (at import). A field
may be something else:

* another ParamSet, whose parameters are read from the same values (its definitions join ``PARAMS``);
* a value of the algorithm's own that no parameter gives, with an explicit default (``vehicle_type: int = 1``).

A field holds the catalogue's value in the catalogue's unit: what an algorithm computes from it (degrees to
radians, a product of two) it computes where it uses it.

:func:`combine` joins parameter definitions (a module's PARAMS from its algorithms'), each name once;
:func:`with_defaults` gives the values of a family of parameters indexed at run time (CA_ROTOR<i>_*).
"""

from __future__ import annotations

import dataclasses
import inspect
import sys
from collections.abc import Iterable, Mapping
from typing import Any, ClassVar, Protocol, Self, dataclass_transform

from stack.params import catalogue
from stack.params.param import Param

_SCALARS: dict[str, type] = {"bool": bool, "int": int, "float": float}
_A: dict[type, str] = {bool: "a bool", int: "an int", float: "a float"}


class Values(Protocol):
    """Parameter values by PX4 name: a dict, or the :class:`~stack.params.store.ParamStore` a module holds."""

    def __contains__(self, name: str, /) -> bool: ...

    def __getitem__(self, name: str, /) -> object: ...


def combine(*groups: Iterable[Param]) -> tuple[Param, ...]:
    """The definitions of ``groups``, in order, each name once (the first definition of a name that several
    groups read). Two different definitions of one name are refused."""
    seen: dict[str, Param] = {}
    for group in groups:
        for p in group:
            first = seen.setdefault(p.name, p)
            if first is not p and first != p:
                raise ValueError(f"parameter {p.name} is defined twice, differently")
    return tuple(seen.values())


def with_defaults(params: Iterable[Param], values: Mapping[str, object]) -> dict[str, object]:
    """The values of ``params`` by name: ``values``' where it has one, else the definition's default. For a family
    of parameters indexed at run time (rotor ``i``'s CA_ROTOR<i>_*), which a ParamSet's fields cannot name."""
    return {p.name: values.get(p.name, p.default) for p in params}


@dataclass_transform(frozen_default=True, field_specifiers=(dataclasses.field,))
class ParamSet:
    """Base of an algorithm's parameter class (see the module docstring)."""

    PARAMS: ClassVar[tuple[Param, ...]] = ()
    """The catalogue's definitions of the parameters the class reads (nested ParamSets' included)."""
    _SCALAR_FIELDS: ClassVar[tuple[tuple[str, str, type], ...]] = ()
    _NESTED_FIELDS: ClassVar[tuple[tuple[str, type[ParamSet]], ...]] = ()

    def __init_subclass__(cls, **kwargs: Any) -> None:
        super().__init_subclass__(**kwargs)
        scalars: list[tuple[str, str, type]] = []
        nested: list[tuple[str, type[ParamSet]]] = []
        groups: list[tuple[Param, ...]] = []
        for attr, annotation in inspect.get_annotations(cls).items():
            if str(annotation).startswith(("ClassVar", "typing.ClassVar")):
                continue
            name = attr.upper()
            own_default = attr in cls.__dict__
            kind = _resolve(cls, annotation) if not own_default or name in catalogue.CATALOGUE else None
            if isinstance(kind, type) and issubclass(kind, ParamSet):
                if own_default:
                    raise TypeError(f"{cls.__qualname__}.{attr}: a nested ParamSet's defaults are the catalogue's")
                setattr(cls, attr, dataclasses.field(default_factory=kind))
                nested.append((attr, kind))
                groups.append(kind.PARAMS)
                continue
            if own_default and name not in catalogue.CATALOGUE:
                continue  # the algorithm's own value, no parameter's
            p = catalogue.get(name)  # ParamError for a name the catalogue does not hold
            if own_default:
                raise TypeError(f"{cls.__qualname__}.{attr}: {name}'s default is the catalogue's; write none")
            if kind is not p.type:
                raise TypeError(
                    f"{cls.__qualname__}.{attr}: {name} is {_A[p.type]} in the catalogue, "
                    f"annotated {getattr(annotation, '__name__', annotation)}"
                )
            setattr(cls, attr, p.default)
            scalars.append((attr, name, p.type))
            groups.append((p,))
        cls._SCALAR_FIELDS = tuple(scalars)
        cls._NESTED_FIELDS = tuple(nested)
        cls.PARAMS = combine(*groups)
        dataclasses.dataclass(frozen=True)(cls)

    @classmethod
    def from_params(cls, values: Values) -> Self:
        """The parameters from ``values`` (a module's, by PX4 name), each converted to the catalogue's type;
        a name ``values`` lacks takes the catalogue's default."""
        kwargs: dict[str, object] = {
            attr: kind(values[name]) for attr, name, kind in cls._SCALAR_FIELDS if name in values
        }
        for attr, kind in cls._NESTED_FIELDS:
            kwargs[attr] = kind.from_params(values)
        return cls(**kwargs)


def _resolve(cls: type, annotation: object) -> object:
    """The type an annotation names: bool, int or float, or a class of the defining module (a nested ParamSet)."""
    if not isinstance(annotation, str):
        return annotation
    if annotation in _SCALARS:
        return _SCALARS[annotation]
    namespace = vars(sys.modules[cls.__module__])
    return namespace.get(annotation, annotation)
