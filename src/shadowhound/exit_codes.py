"""The exit codes of every `shadowhound` command (run, serve, mcp, node, sim-driver, ...).

    0    success (a node or server: stopped by Ctrl-C / SIGTERM after a clean shutdown)
    1    the mission (or evaluation, or doctor check) failed
    2    usage or configuration error: nothing was run, the message says what to fix
    130  interrupted (Ctrl-C) during a mission; the robot was stopped first
    141  the output went away (a pipe closed early, as in `shadowhound skills | head -1`):
         the command ends quietly with the status a shell reports for tools that SIGPIPE
         ends (128 + 13), so `set -o pipefail` scripts still see the output was cut short

Defined here once; every command imports them.
"""

from __future__ import annotations

from enum import IntEnum


class ExitCode(IntEnum):
    OK = 0
    FAILED = 1
    USAGE = 2
    INTERRUPTED = 130  # 128 + SIGINT, as shells report a Ctrl-C
    BROKEN_PIPE = 141  # 128 + SIGPIPE, as shells report `cat` ended by a closed pipe

    def __str__(self) -> str:  # "2", not "ExitCode.USAGE", on Python 3.10 as on 3.11+
        return str(int(self))


EXIT_OK = ExitCode.OK
EXIT_FAILED = ExitCode.FAILED
EXIT_USAGE = ExitCode.USAGE
EXIT_INTERRUPTED = ExitCode.INTERRUPTED
EXIT_BROKEN_PIPE = ExitCode.BROKEN_PIPE
