"""Start a supervised program that is not a module: ``python -m stack.supervisor.child SUPERVISOR_PID PROGRAM ARGS...``.

It asks the kernel for SIGTERM when the supervisor dies (the setting survives ``exec``), checks the
supervisor is still there, and becomes the program, so no ``[[process]]`` outlives its stack either.
"""

from __future__ import annotations

import os
import sys

from stack.runtime.orphan import ask_kernel_for_sigterm


def main(argv: list[str]) -> int:
    if len(argv) < 2 or not argv[0].isdigit():
        print("usage: python -m stack.supervisor.child SUPERVISOR_PID PROGRAM [ARGS...]", file=sys.stderr)
        return 2
    supervisor = int(argv[0])
    ask_kernel_for_sigterm()
    if os.getppid() != supervisor:
        return 1  # the supervisor is already gone
    try:
        os.execvp(argv[1], argv[1:])
    except OSError as e:
        print(f"cannot start {argv[1]}: {e}", file=sys.stderr)
    return 127


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
