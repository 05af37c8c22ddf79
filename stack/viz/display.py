"""Where a native Rerun viewer can open, known without importing Rerun (the CLI imports this at start)."""

from __future__ import annotations

import os
import sys

# The native viewer's usual data port (Rerun's own default): plots of several runs join one open viewer.
DEFAULT_GRPC_PORT = 9876


def has_display() -> bool:
    """Whether a native viewer window can open here."""
    if sys.platform in ("darwin", "win32"):
        return True
    return bool(os.environ.get("DISPLAY") or os.environ.get("WAYLAND_DISPLAY"))
