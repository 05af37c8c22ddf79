"""A module process never outlives its supervisor.

Two guards, because either alone can fail. The kernel sends SIGTERM when the parent dies
(``prctl(PR_SET_PDEATHSIG)``, Linux), and the process unwinds as on any stop; but an unwinding that hangs
(a session close waiting on a router that died with the supervisor) would leave it running, and the
kernel's signal is tied to the thread that forked it. So a watch thread also waits on the supervisor's
pidfd and, once it is gone, asks for the same stop and ends the process outright ``EXIT_GRACE_S`` later.
"""

from __future__ import annotations

import ctypes
import logging
import os
import select
import signal
import sys
import threading
import time

PR_SET_PDEATHSIG = 1
EXIT_GRACE_S = 0.8
"""How long a module may take to stop cleanly once its supervisor is gone (it ends within a second)."""
ORPHAN_EXIT_CODE = 3

log = logging.getLogger("stack.runtime")


def ask_kernel_for_sigterm() -> None:
    """SIGTERM to this process when its parent dies (survives ``exec``)."""
    if sys.platform.startswith("linux"):
        ctypes.CDLL(None, use_errno=True).prctl(PR_SET_PDEATHSIG, signal.SIGTERM, 0, 0, 0)


def watch_supervisor(supervisor_pid: int) -> bool:
    """Arm both guards for ``supervisor_pid``; False if it is already gone (not this process's parent)."""
    ask_kernel_for_sigterm()
    try:
        pidfd = os.pidfd_open(supervisor_pid)
    except ProcessLookupError:
        return False
    # Opened before this check, the pidfd is the parent's own, not a later process reusing its number.
    if os.getppid() != supervisor_pid:
        os.close(pidfd)
        return False
    threading.Thread(target=_end_after, args=(pidfd, supervisor_pid), name="supervisor-watch", daemon=True).start()
    return True


def _end_after(pidfd: int, supervisor_pid: int) -> None:
    select.select([pidfd], [], [])
    log.error("supervisor %d is gone: stopping", supervisor_pid)
    os.kill(os.getpid(), signal.SIGTERM)
    time.sleep(EXIT_GRACE_S)
    os._exit(ORPHAN_EXIT_CODE)
