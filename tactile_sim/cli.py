"""The scripts' common entry: run, and turn a package error into one line and exit status 2."""

from __future__ import annotations

import sys
from collections.abc import Callable

from recognition.errors import RecognitionError
from tactile_sim.errors import SimulationError

__all__ = ["CLI_ERRORS", "run_cli"]

#: What a script reports in one line instead of a traceback: the packages' base errors,
#: and a file that cannot be read or written.
CLI_ERRORS = (RecognitionError, SimulationError, OSError)


def run_cli(main: Callable[[], object], *, name: str = "error") -> int:
    """Calls ``main()``; returns 0, or 2 after printing ``"<name>: <message>"`` on one line
    to stderr when it raised one of :data:`CLI_ERRORS`."""
    try:
        main()
    except CLI_ERRORS as exc:
        message = " ".join(str(exc).split())
        print(f"{name}: {message}", file=sys.stderr)
        return 2
    return 0
