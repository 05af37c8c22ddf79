"""The observers ``--plot`` and ``--record`` add to any profile: the Rerun bridge and the recorder."""

from __future__ import annotations

from pathlib import Path

from stack.runtime.spec import load_module_class
from stack.supervisor.profile import ModuleEntry, Profile


def _entry(name: str, args: dict[str, object], host: str) -> ModuleEntry:
    cls = load_module_class(name)
    defaults = {a.name: a.default for a in cls.ARGS}
    return ModuleEntry(
        name=name,
        module=name,
        cls=cls,
        params={},
        args={**defaults, **args},
        condition="",
        restart="no",
        max_restarts=0,
        critical=False,
        host=host,
    )


def add_observers(
    prof: Profile,
    *,
    plot: bool,
    web: bool,
    save: str | None,
    record: Path | None,
    own_ports: bool = False,
    host: str = "",
) -> None:
    """Insert the recorder first (it stops last, so it records to the end) and the plot bridge last.

    ``own_ports``: the native viewer listens on free ports of its own (a flight beside others) instead of
    the usual ones, where the plots of ``stack up`` join a viewer already open. A web viewer always has
    ports of its own: it is the stack's, and stops with it. ``host``: the machine of a vehicle spread over
    several that runs them (where ``stack up --host`` was given them)."""
    if record is not None:
        prof.modules.insert(0, _entry("recorder", {"path": str(record.resolve())}, host))
    if plot or web or save:
        args: dict[str, object] = {"web": web, "spawn": not web}
        if own_ports or web:
            args.update(grpc_port=0, web_port=0)
        if save:
            args["save"] = str(Path(save).resolve())
        prof.modules.append(_entry("rerun_bridge", args, host))
