"""Process entry point of a module: ``python -m stack.runtime.main SPEC_FILE [SPEC_FILE...]``.

The supervisor writes the spec (JSON) into the run directory and starts one such process per
module, or one for the modules a profile puts in one process (``process = "NAME"``), given all their
specs. SIGTERM and SIGINT unwind the loop so the Zenoh session is always closed; when the supervisor
dies the process stops too, within a second (:mod:`stack.runtime.orphan`).

The process loads its code first, then waits for the supervisor's go (a line on its standard input)
before it opens its session: modules still start one after another, each once the one before is
ready, but the supervisor can start the next processes early, so their imports overlap that wait.
Standard input at its end (no supervisor pipe) is a go too.
"""

from __future__ import annotations

import cProfile
import logging
import os
import signal
import sys
import time
from pathlib import Path
from types import FrameType

from stack.params.param import ParamError
from stack.runtime.ledger import LockstepError
from stack.runtime.orphan import watch_supervisor
from stack.runtime.runner import Runtime, Shutdown, run_together, shutdown_behind
from stack.runtime.spec import ModuleSpec, load_module_class

# Where each module writes its cProfile statistics (<module>.prof) when it stops, if set: for finding
# where a module's main thread spends its CPU time (`python -m pstats DIR/simulator.prof`).
PROFILE_ENV = "STACK_PROFILE_DIR"
_stopping = False


def _on_signal(signum: int, frame: FrameType | None) -> None:
    global _stopping
    if _stopping:
        return  # already unwinding; the supervisor escalates to SIGKILL if needed
    _stopping = True
    raise Shutdown(signal.Signals(signum).name)


def main(argv: list[str] | None = None) -> int:
    argv = sys.argv[1:] if argv is None else argv
    if not argv:
        print("usage: python -m stack.runtime.main SPEC_FILE [SPEC_FILE...]", file=sys.stderr)
        return 2
    specs = [ModuleSpec.from_json(Path(arg).read_text()) for arg in argv]
    spec = specs[0]
    name = "+".join(each.name for each in specs)
    logging.basicConfig(
        level=getattr(logging, spec.log_level.upper(), logging.INFO),
        stream=sys.stderr,
        format="%(levelname)-7s %(message)s",
    )
    signal.signal(signal.SIGTERM, _on_signal)
    signal.signal(signal.SIGINT, _on_signal)
    log = logging.getLogger(name)
    profile_dir = os.environ.get(PROFILE_ENV)
    profiler = cProfile.Profile(time.thread_time) if profile_dir else None
    try:
        if spec.supervisor_pid > 0 and not watch_supervisor(spec.supervisor_pid):
            raise Shutdown("supervisor already gone")
        for each in specs:
            load_module_class(each.module)
        sys.stdin.buffer.readline()
        if profiler is not None:
            profiler.enable()
        if len(specs) == 1:
            Runtime(spec).run()
        else:
            run_together(specs)
    except Shutdown as stop:
        log.info("stopped (%s)", stop)
        return 0
    except Exception as e:
        stop = shutdown_behind(e)
        if stop is not None:
            log.info("stopped (%s)", stop)
            return 0
        if isinstance(e, (LockstepError, ParamError, ValueError)):
            log.error("%s", e)
        else:
            log.exception("crashed")
        return 1
    finally:
        if profiler is not None:
            profiler.disable()
            profiler.dump_stats(Path(str(profile_dir)) / f"{name}.prof")
    return 0


if __name__ == "__main__":
    sys.exit(main())
