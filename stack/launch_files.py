"""Where the files shipped under ``launch/`` are found: launch profiles and the missions scenarios fly."""

from __future__ import annotations

import sys
from pathlib import Path

from stack.names import suggestion

MISSION_SUFFIXES = (".plan", ".waypoints", ".txt")
"""What a mission named without its suffix may be: a QGroundControl plan, then a waypoint list."""


def launch_dirs() -> list[Path]:
    """Where profiles are looked up by name: ./launch, the source checkout's launch/, the installed copy."""
    candidates = [
        Path.cwd() / "launch",
        Path(__file__).resolve().parents[1] / "launch",
        Path(sys.prefix) / "share" / "stack" / "launch",
    ]
    seen: list[Path] = []
    for d in candidates:
        if d.is_dir() and d not in seen:
            seen.append(d)
    return seen


def find_launch_file(relative: str) -> Path:
    """A file shipped under launch/ (e.g. ``missions/box.plan``), from the first launch directory holding it."""
    for d in launch_dirs():
        if (d / relative).is_file():
            return d / relative
    raise FileNotFoundError(f"launch/{relative} not found in {', '.join(str(d) for d in launch_dirs())}")


def find_mission(name: str | Path) -> Path:
    """A mission file by path, else by name among the shipped missions (``box`` → launch/missions/box.plan,
    ``box.txt``), as profiles are found; FileNotFoundError naming what is there otherwise."""
    path = Path(name)
    if path.is_file():
        return path
    if path.parent == Path("."):
        for d in launch_dirs():
            for candidate in (path.name, *(path.name + s for s in MISSION_SUFFIXES)):
                if (d / "missions" / candidate).is_file():
                    return d / "missions" / candidate
    known = shipped_missions()
    hint = suggestion(path.stem, sorted({Path(k).stem for k in known}))
    shipped = f"; the shipped missions are {', '.join(known)}" if known else ""
    raise FileNotFoundError(f"{name}: no such mission file{hint}{shipped}")


def shipped_missions() -> list[str]:
    """The missions under launch/missions, by file name."""
    return sorted({p.name for d in launch_dirs() for p in (d / "missions").glob("*") if p.is_file()})
