"""The viewer processes: the web viewer server, the native viewer, and their ports."""

from __future__ import annotations

import contextlib
import os
import shutil
import signal
import socket
import subprocess
import sys
import tempfile
import threading
import time
import urllib.parse
from collections.abc import Sequence
from pathlib import Path
from types import FrameType

from tactile_sim.errors import PortInUse, RecordingError
from tactile_sim.recording.read import read_recording

__all__ = [
    "WebViewer",
    "check_display",
    "check_ports",
    "open_native_viewer",
    "rerun_executable",
    "serve_recording",
]


def rerun_executable() -> str:
    """The rerun command-line viewer shipped with rerun-sdk."""
    import rerun_cli

    bundled = Path(rerun_cli.__file__).parent / "rerun"
    if bundled.is_file():
        return str(bundled)
    found = shutil.which("rerun")
    if found is None:
        raise RecordingError("the rerun viewer executable is missing: reinstall rerun-sdk")
    return found


def _port_free(host: str, port: int) -> bool:
    """True if ``port`` can be bound on ``host``."""
    with socket.socket(socket.AF_INET, socket.SOCK_STREAM) as s:
        try:
            s.bind((host, port))
        except OSError:
            return False
    return True


def _free_port(host: str, avoid: Sequence[int] = ()) -> int:
    """A port free on ``host`` now, none of ``avoid``."""
    while True:
        with socket.socket(socket.AF_INET, socket.SOCK_STREAM) as s:
            s.bind((host, 0))
            port = int(s.getsockname()[1])
        if port not in avoid:
            return port


def check_ports(web_port: int = 9090, grpc_port: int = 9876, host: str = "127.0.0.1") -> None:
    """Checks that the web viewer's ports are free on ``host``.

    Raises
    ------
    PortInUse
        A port is taken; the message names the option to pass and a free port.
    """
    if web_port == grpc_port:
        raise ValueError(f"the web and gRPC ports must differ, both are {web_port}")
    if not _port_free(host, web_port):
        raise PortInUse(web_port, "--web-port", _free_port(host, (grpc_port,)))
    if not _port_free(host, grpc_port):
        raise PortInUse(grpc_port, "--grpc-port", _free_port(host, (web_port,)))


def _interrupt(signum: int, frame: FrameType | None) -> None:
    """Turns SIGTERM into a KeyboardInterrupt (the server then stops like on Ctrl-C)."""
    raise KeyboardInterrupt


class WebViewer:
    """A running web viewer (``rerun --serve-web``) serving one recording on one host.

    Use as a context manager, or call :meth:`close`.

    Attributes
    ----------
    url : str
        Open this in a browser: the viewer page, connected to the recording's server.
    process : subprocess.Popen
    """

    def __init__(self, process: subprocess.Popen, url: str) -> None:
        self.process = process
        self.url = url

    def wait(self) -> int:
        """Blocks until the server stops (Ctrl-C or SIGTERM stop it); returns its exit
        status (0 when stopped here)."""
        main = threading.current_thread() is threading.main_thread()
        previous = signal.signal(signal.SIGTERM, _interrupt) if main else None
        try:
            return self.process.wait()
        except KeyboardInterrupt:
            return 0
        finally:
            self.close()
            if main:
                signal.signal(signal.SIGTERM, previous)

    def close(self) -> None:
        """Stops the server."""
        if self.process.poll() is None:
            self.process.terminate()
            try:
                self.process.wait(timeout=5)
            except subprocess.TimeoutExpired:
                self.process.kill()
                self.process.wait()

    def __enter__(self) -> WebViewer:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()


def serve_recording(
    path: str | Path,
    *,
    web_port: int = 9090,
    grpc_port: int = 9876,
    host: str = "127.0.0.1",
    timeout_s: float = 30.0,
) -> WebViewer:
    """Serves a recording to browsers: the web viewer over HTTP, the data over gRPC.

    Both servers bind ``host`` only (loopback by default).

    Parameters
    ----------
    path : str or Path
        The .rrd file; checked first (:func:`read_recording`).
    web_port, grpc_port : int
        HTTP port of the viewer page, gRPC port of the data.
    host : str
        Address both servers bind.
    timeout_s : float, seconds
        How long to wait for the servers to come up.

    Raises
    ------
    InvalidRecording
        The file is missing, truncated or not a recording.
    PortInUse
        A port is taken; the message names a free one.
    RecordingError
        The viewer did not start.
    """
    path = Path(path)
    read_recording(path)
    check_ports(web_port, grpc_port, host)
    log = tempfile.TemporaryFile()
    process = subprocess.Popen(
        [
            rerun_executable(),
            "--serve-web",
            "--bind",
            host,
            "--web-viewer-port",
            str(web_port),
            "--port",
            str(grpc_port),
            str(path),
        ],
        stdout=log,
        stderr=subprocess.STDOUT,
        stdin=subprocess.DEVNULL,
    )
    viewer = WebViewer(process, _viewer_url(host, web_port, grpc_port))
    deadline = time.monotonic() + timeout_s
    while not (_listening(host, web_port) and _listening(host, grpc_port)):
        if process.poll() is not None or time.monotonic() > deadline:
            viewer.close()
            log.seek(0)
            tail = log.read().decode(errors="replace").strip().splitlines()[-3:]
            raise RecordingError(
                f"the web viewer did not start on {host}:{web_port}: " + " / ".join(tail)
            )
        time.sleep(0.1)
    return viewer


def _listening(host: str, port: int) -> bool:
    """True if something accepts connections on ``host:port``."""
    with contextlib.suppress(OSError), socket.create_connection((host, port), timeout=0.5):
        return True
    return False


def _viewer_url(host: str, web_port: int, grpc_port: int) -> str:
    """The web viewer's page, connected to the recording's gRPC server."""
    source = urllib.parse.quote(f"rerun+http://{host}:{grpc_port}/proxy", safe="")
    return f"http://{host}:{web_port}/?url={source}"


def check_display() -> None:
    """Checks that the native viewer has a display to open a window on.

    Raises
    ------
    RecordingError
        Linux without DISPLAY or WAYLAND_DISPLAY; the message names the web viewer instead.
    """
    if sys.platform.startswith("linux") and not (
        os.environ.get("DISPLAY") or os.environ.get("WAYLAND_DISPLAY")
    ):
        raise RecordingError(
            "no display for the native viewer (DISPLAY is not set): use the web viewer "
            "(scripts/probe.py --rerun serve, scripts/replay.py FILE --web)"
        )


def open_native_viewer(path: str | Path) -> int:
    """Opens a recording in the native viewer and waits until it is closed.

    Raises
    ------
    InvalidRecording
        The file is missing, truncated or not a recording.
    RecordingError
        The viewer failed (e.g. no display); the message says what to do instead.
    """
    path = Path(path)
    read_recording(path)
    check_display()
    status = subprocess.call([rerun_executable(), "--bind", "127.0.0.1", str(path)])
    if status not in (0, 130):
        raise RecordingError(
            f"the native viewer exited with status {status} (no display? serve the "
            "recording to a browser instead: --web)"
        )
    return status
