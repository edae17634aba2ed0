"""The viewer processes: the web viewer server, the native viewer, and their ports."""

from __future__ import annotations

import contextlib
import ctypes
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
from collections.abc import Callable, Sequence
from pathlib import Path
from types import FrameType
from typing import IO

from tactile_sim.errors import PortInUse, RecordingError
from tactile_sim.recording.read import read_recording

__all__ = [
    "GRPC_PORT",
    "WEB_PORT",
    "WebViewer",
    "check_display",
    "check_ports",
    "open_native_viewer",
    "rerun_executable",
    "serve_recording",
]

#: Default HTTP port of the web viewer page.
WEB_PORT = 9090
#: Default gRPC port of the recording's data.
GRPC_PORT = 9876


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


def check_ports(
    web_port: int = WEB_PORT, grpc_port: int = GRPC_PORT, host: str = "127.0.0.1"
) -> None:
    """Checks that the web viewer's ports are two different ports, free on ``host``.

    Raises
    ------
    RecordingError
        A port outside 1-65535, or both the same; the message names the option.
    PortInUse
        A port is taken; the message names the option to pass and a free port.
    """
    for port, option in ((web_port, "--web-port"), (grpc_port, "--grpc-port")):
        if not 1 <= port <= 65535:
            raise RecordingError(f"{option} {port}: expected a port in 1-65535")
    if web_port == grpc_port:
        raise RecordingError(f"--web-port and --grpc-port must differ, both are {web_port}")
    if not _port_free(host, web_port):
        raise PortInUse(web_port, "--web-port", _free_port(host, (grpc_port,)))
    if not _port_free(host, grpc_port):
        raise PortInUse(grpc_port, "--grpc-port", _free_port(host, (web_port,)))


def _interrupt(signum: int, frame: FrameType | None) -> None:
    """Turns SIGTERM or SIGHUP into a KeyboardInterrupt (the server then stops like on
    Ctrl-C)."""
    raise KeyboardInterrupt


#: Signals that stop :meth:`WebViewer.wait` like Ctrl-C: ``kill`` and a closed terminal.
_STOP_SIGNALS = (signal.SIGTERM, signal.SIGHUP) if hasattr(signal, "SIGHUP") else (signal.SIGTERM,)

#: ``prctl`` option: the signal a process gets when the thread that started it ends.
_PR_SET_PDEATHSIG = 1


def _stopped_with_parent() -> Callable[[], None] | None:
    """A ``preexec_fn`` that has Linux send the child SIGTERM when its parent ends, however
    it ends (SIGKILL included); None elsewhere."""
    if not sys.platform.startswith("linux"):
        return None
    libc = ctypes.CDLL(None, use_errno=True)
    parent = os.getpid()

    def preexec() -> None:
        libc.prctl(_PR_SET_PDEATHSIG, int(signal.SIGTERM), 0, 0, 0)
        if os.getppid() != parent:  # the parent ended before prctl took effect
            os._exit(1)

    return preexec


def _feed(path: Path, pipe: IO[bytes]) -> None:
    """Writes the recording into the server's stdin, and leaves the pipe open."""
    with contextlib.suppress(OSError, ValueError), path.open("rb") as f:
        shutil.copyfileobj(f, pipe)
        pipe.flush()


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
        """Blocks until the server stops (Ctrl-C, SIGTERM or SIGHUP stop it); returns its
        exit status (0 when stopped here)."""
        main = threading.current_thread() is threading.main_thread()
        previous = {s: signal.signal(s, _interrupt) for s in _STOP_SIGNALS} if main else {}
        try:
            return self.process.wait()
        except KeyboardInterrupt:
            return 0
        finally:
            self.close()
            for s, handler in previous.items():
                signal.signal(s, handler)

    def close(self) -> None:
        """Stops the server."""
        if self.process.poll() is None:
            self.process.terminate()
            try:
                self.process.wait(timeout=5)
            except subprocess.TimeoutExpired:
                self.process.kill()
                self.process.wait()
        if self.process.stdin is not None:
            with contextlib.suppress(OSError):
                self.process.stdin.close()

    def __enter__(self) -> WebViewer:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()


def serve_recording(
    path: str | Path,
    *,
    web_port: int = WEB_PORT,
    grpc_port: int = GRPC_PORT,
    host: str = "127.0.0.1",
    timeout_s: float = 30.0,
) -> WebViewer:
    """Serves a recording to browsers: the web viewer over HTTP, the data over gRPC.

    Both servers bind ``host`` only (loopback by default). The server (``rerun
    --serve-web``) reads the recording from its stdin, a pipe this process keeps open:
    rerun 0.41's server spins on a full core once a file or a closed pipe it reads from
    has ended, and idles while the pipe stays open. On Linux the server ends with the
    thread that started it, even when this process is killed (``prctl`` parent-death
    signal); :meth:`WebViewer.close` or leaving the ``with`` block stops it otherwise.

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
        The ports are not two valid ports, or the viewer did not start.
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
            "-",
        ],
        stdout=log,
        stderr=subprocess.STDOUT,
        stdin=subprocess.PIPE,
        preexec_fn=_stopped_with_parent(),
    )
    threading.Thread(target=_feed, args=(path, process.stdin), daemon=True).start()
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
