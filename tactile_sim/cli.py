"""The scripts' common parts: one-line argument errors, checked argument types, and the entry
that turns a package error into one line and exit status 2 (an interrupt into 130).

A script parses with :class:`ArgumentParser`, gives numeric options a checked ``type``
(:func:`integer`, :func:`real`), checks its output paths and viewer ports before any
work (:func:`require_writable`, :func:`viewer_ports`), then calls :func:`run_cli`.
"""

from __future__ import annotations

import argparse
import math
import sys
from collections.abc import Callable
from pathlib import Path
from typing import NoReturn

from recognition.errors import RecognitionError
from recognition.files import check_writable
from tactile_sim.errors import SimulationError

__all__ = [
    "CLI_ERRORS",
    "INTERRUPTED_STATUS",
    "ArgumentParser",
    "integer",
    "real",
    "require_writable",
    "run_cli",
    "viewer_ports",
]

#: What a script reports in one line instead of a traceback: the packages' base errors,
#: and a file that cannot be read or written.
CLI_ERRORS = (RecognitionError, SimulationError, OSError)

#: Exit status after Ctrl-C (128 + SIGINT, as a shell reports it).
INTERRUPTED_STATUS = 130


class ArgumentParser(argparse.ArgumentParser):
    """argparse's parser, reporting a bad argument in one line on stderr
    (``error: <message>``) with exit status 2, without the usage text (``--help`` shows it)."""

    def error(self, message: str) -> NoReturn:
        self.exit(2, f"error: {message}\n")


def integer(minimum: int, maximum: int | None = None) -> Callable[[str], int]:
    """An argparse ``type``: an integer in ``[minimum, maximum]`` (no maximum: None)."""
    expected = f">= {minimum}" if maximum is None else f"in {minimum}-{maximum}"

    def parse(text: str) -> int:
        try:
            value = int(text)
        except ValueError:
            raise argparse.ArgumentTypeError(
                f"expected an integer {expected}, got {text!r}"
            ) from None
        if value < minimum or (maximum is not None and value > maximum):
            raise argparse.ArgumentTypeError(f"expected an integer {expected}, got {value}")
        return value

    return parse


def real(
    low: float | None = None,
    high: float | None = None,
    *,
    low_open: bool = False,
    high_open: bool = False,
) -> Callable[[str], float]:
    """An argparse ``type``: a finite number between ``low`` and ``high`` (None: unbounded
    on that side), each bound included unless ``low_open`` / ``high_open``."""
    if low is not None and high is not None:
        expected = f"in {'(' if low_open else '['}{low:g}, {high:g}{')' if high_open else ']'}"
    elif low is not None:
        expected = f"{'>' if low_open else '>='} {low:g}"
    elif high is not None:
        expected = f"{'<' if high_open else '<='} {high:g}"
    else:
        expected = ""

    def parse(text: str) -> float:
        try:
            value = float(text)
        except ValueError:
            value = math.nan
        below = low is not None and (value <= low if low_open else value < low)
        above = high is not None and (value >= high if high_open else value > high)
        if not math.isfinite(value) or below or above:
            raise argparse.ArgumentTypeError(
                f"expected a finite number {expected}".rstrip() + f", got {text!r}"
            )
        return value

    return parse


def require_writable(
    parser: argparse.ArgumentParser, option: str, path: Path | None, *, directory: bool = False
) -> None:
    """Stops with a one-line error naming ``option`` unless ``path`` (a file, or a directory
    when ``directory``) can be written (:func:`recognition.files.check_writable`); None
    passes."""
    if path is None:
        return
    try:
        check_writable(path, directory=directory)
    except OSError as exc:
        parser.error(f"{option} {path}: {exc.strerror or exc}")


def viewer_ports(
    parser: argparse.ArgumentParser,
    web_port: int | None,
    grpc_port: int | None,
    *,
    serving: bool,
    needs: str,
) -> tuple[int, int]:
    """The web viewer's HTTP and gRPC ports from ``--web-port`` and ``--grpc-port`` (None:
    not given, the defaults), checked (:func:`tactile_sim.recording.check_ports`) when
    ``serving``; given without serving, they are an error that names ``needs`` (the option
    that serves)."""
    from tactile_sim.recording.viewer import GRPC_PORT, WEB_PORT, check_ports

    given = [o for o, v in (("--web-port", web_port), ("--grpc-port", grpc_port)) if v is not None]
    if given and not serving:
        verb = "applies" if len(given) == 1 else "apply"
        parser.error(f"{' and '.join(given)} {verb} only with {needs}")
    ports = (
        WEB_PORT if web_port is None else web_port,
        GRPC_PORT if grpc_port is None else grpc_port,
    )
    if serving:
        try:
            check_ports(*ports)
        except SimulationError as exc:
            parser.error(str(exc))
    return ports


def run_cli(
    main: Callable[[], object], *, name: str = "error", interrupted: str = "interrupted"
) -> int:
    """Calls ``main()``; returns 0, or 2 after printing ``"<name>: <message>"`` on one line
    to stderr when it raised one of :data:`CLI_ERRORS`, or :data:`INTERRUPTED_STATUS`
    after printing ``interrupted`` when it was interrupted (Ctrl-C)."""
    try:
        main()
    except CLI_ERRORS as exc:
        message = " ".join(str(exc).split())
        print(f"{name}: {message}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print(interrupted, file=sys.stderr)
        return INTERRUPTED_STATUS
    return 0
