"""The control chain's scheduling priority on the wall clock, after PX4's work queues on Linux.

PX4 runs its loops in threads of fixed real-time priority (SCHED_FIFO), each work queue a step below the
maximum (``platforms/common/include/px4_platform_common/px4_work_queue/WorkQueueManager.hpp``): the rate
controller and the allocator at the top (``wq:rate_ctrl``), then the attitude and position controllers
(``wq:nav_and_controllers``, -13), the estimators (``wq:INS0``, -14), the rest lower. A module process here
takes its class's :data:`WorkQueue` the same way, so that a machine busy with other programs delays the
flight last; the plant, standing for the world and the sensors' drivers, goes first.

Real-time priority needs the privilege (root, CAP_SYS_NICE or an RLIMIT_RTPRIO); without it the module asks
for a raised niceness instead, and runs as it is if refused too, saying so once. Only a module running on
the wall clock is raised: in lockstep, time waits for every module anyway, and a module that computes as
fast as it can at real-time priority would starve the machine.
"""

from __future__ import annotations

import logging
import os
from collections.abc import Iterable
from dataclasses import dataclass

log = logging.getLogger("stack.runtime")


@dataclass(frozen=True)
class WorkQueue:
    name: str
    relative_priority: int
    """Below the system's maximum SCHED_FIFO priority, as PX4's ``wq_config_t::relative_priority``."""

    @property
    def niceness(self) -> int:
        """The niceness asked for when real-time priority is not allowed: higher queues get more of the CPU."""
        return -10 + min(9, -self.relative_priority // 2)


PLANT = WorkQueue("plant", 0)
RATE_CTRL = WorkQueue("rate_ctrl", 0)
NAV_AND_CONTROLLERS = WorkQueue("nav_and_controllers", -13)
INS = WorkQueue("INS0", -14)
COMMANDER = WorkQueue("commander", -10)
"""PX4 starts its commander task at SCHED_PRIORITY_DEFAULT + 40 (``src/modules/commander/Commander.cpp``)."""
HP_DEFAULT = WorkQueue("hp_default", -18)


def raise_priority(module: str, queue: WorkQueue) -> str:
    """Put the calling thread (and the threads it starts later: in a module's process, before its session opens, the
    whole process) at ``queue``'s priority; returns what was done."""
    try:
        top = os.sched_get_priority_max(os.SCHED_FIFO)
        os.sched_setscheduler(0, os.SCHED_FIFO, os.sched_param(top + queue.relative_priority))
        done = f"SCHED_FIFO {top + queue.relative_priority} (wq:{queue.name})"
    except (PermissionError, AttributeError, OSError) as fifo_refused:
        try:
            os.setpriority(os.PRIO_PROCESS, 0, queue.niceness)
            done = f"niceness {queue.niceness} (wq:{queue.name}; SCHED_FIFO not allowed: {fifo_refused})"
        except (PermissionError, OSError) as nice_refused:
            done = f"normal priority (neither SCHED_FIFO nor a raised niceness allowed: {nice_refused})"
    log.info("%s: scheduling %s", module, done)
    return done


def highest_queue(queues: Iterable[WorkQueue | None]) -> WorkQueue | None:
    """The work queue of highest priority among ``queues`` (None if none has one)."""
    chosen = [q for q in queues if q is not None]
    return max(chosen, key=lambda q: q.relative_priority) if chosen else None
