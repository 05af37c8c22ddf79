"""Where the files shipped under ``launch/`` are found: launch profiles and the missions scenarios fly."""

from __future__ import annotations

import sys
from pathlib import Path


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
