"""The viewers: ports, the web viewer idling and ending with its parent, and rendering a
recording in headless Chromium."""

from __future__ import annotations

import base64
import io
import json
import os
import select
import signal
import socket
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest
from testing_processes import running

from tactile_sim.errors import PortInUse, RecordingError, SimulationError
from tactile_sim.recording import check_ports, serve_recording

CHROMIUM = Path("/usr/bin/chromium")
ROOT = Path(__file__).resolve().parents[3]
LINUX = sys.platform.startswith("linux")


def test_port_in_use_is_reported_with_a_free_alternative() -> None:
    with socket.socket() as taken:
        taken.bind(("127.0.0.1", 0))
        taken.listen()
        port = taken.getsockname()[1]
        with pytest.raises(PortInUse, match=rf"port {port} in use; pass --web-port \d+") as info:
            check_ports(port, _free_port())
        alternative = info.value.alternative
        assert alternative != port
        check_ports(alternative, _free_port(alternative))
    assert isinstance(info.value, SimulationError)


@pytest.mark.parametrize(
    ("web_port", "grpc_port", "message"),
    [
        (0, 9876, "--web-port 0: expected a port in 1-65535"),
        (9090, 70000, "--grpc-port 70000: expected a port in 1-65535"),
        (9090, 9090, "must differ, both are 9090"),
    ],
)
def test_ports_out_of_range_or_equal_are_refused(
    web_port: int, grpc_port: int, message: str
) -> None:
    with pytest.raises(RecordingError, match=message):
        check_ports(web_port, grpc_port)


def _free_port(*besides: int) -> int:
    """A port free now, none of ``besides`` (the system may hand out a port just freed)."""
    while True:
        with socket.socket() as s:
            s.bind(("127.0.0.1", 0))
            port = s.getsockname()[1]
        if port not in besides:
            return port


def _cpu_seconds(pid: int) -> float:
    """User and system CPU time of a process so far (Linux /proc), seconds."""
    fields = Path(f"/proc/{pid}/stat").read_text().rpartition(")")[2].split()
    return (int(fields[11]) + int(fields[12])) / os.sysconf("SC_CLK_TCK")


@pytest.mark.slow
@pytest.mark.skipif(not LINUX, reason="reads /proc")
def test_the_web_viewer_idles_once_it_holds_the_recording(recording: Path) -> None:
    web_port = _free_port()
    with serve_recording(recording, web_port=web_port, grpc_port=_free_port(web_port)) as viewer:
        time.sleep(1.5)  # reads the recording
        before, start = _cpu_seconds(viewer.process.pid), time.monotonic()
        time.sleep(3.0)
        load = (_cpu_seconds(viewer.process.pid) - before) / (time.monotonic() - start)
        assert viewer.process.poll() is None
    assert load < 0.2, f"the idle server used {load:.0%} of a core"


_PARENT = """
import sys
from tactile_sim.recording import serve_recording
viewer = serve_recording(sys.argv[1], web_port=int(sys.argv[2]), grpc_port=int(sys.argv[3]))
print(viewer.process.pid, flush=True)
viewer.wait()
"""


@pytest.mark.skipif(not LINUX, reason="the parent-death signal is Linux's")
@pytest.mark.parametrize("signum", [signal.SIGKILL, signal.SIGHUP], ids=["SIGKILL", "SIGHUP"])
def test_the_web_viewer_ends_with_its_parent_and_frees_its_ports(
    recording: Path, signum: int
) -> None:
    first = _free_port()
    ports = first, _free_port(first)
    parent = subprocess.Popen(
        [sys.executable, "-c", _PARENT, str(recording), *map(str, ports)],
        cwd=ROOT,
        stdout=subprocess.PIPE,
        text=True,
    )
    try:
        server = int(parent.stdout.readline())
        assert running(server)
        time.sleep(1.0)  # the parent enters viewer.wait(), which hears SIGHUP, after printing
        os.kill(parent.pid, signum)
        # killed at once, or (SIGHUP: a closed terminal) stopped the server and ended
        assert parent.wait(timeout=10) == (0 if signum == signal.SIGHUP else -signum)
        deadline = time.monotonic() + 5.0
        while running(server) and time.monotonic() < deadline:
            time.sleep(0.05)
        assert not running(server)
        while True:  # the sockets close with the server's last threads
            try:
                check_ports(*ports)
                break
            except PortInUse:
                if time.monotonic() > deadline + 10.0:
                    raise
                time.sleep(0.1)
    finally:
        parent.kill()
        parent.wait()


class _Chromium:
    """Headless Chromium driven over the DevTools protocol on a pipe (fds 3 and 4)."""

    def __init__(self, profile: Path, width: int = 1280, height: int = 800) -> None:
        to_browser_r, self._to_browser = os.pipe()
        self._from_browser, from_browser_w = os.pipe()

        def plumb() -> None:
            a, b = os.dup(to_browser_r), os.dup(from_browser_w)
            os.dup2(a, 3)
            os.dup2(b, 4)

        self.process = subprocess.Popen(
            [
                str(CHROMIUM),
                "--headless=new",
                "--no-sandbox",
                "--use-angle=swiftshader",
                "--enable-unsafe-swiftshader",
                "--disable-gpu",
                "--no-first-run",
                "--disable-background-networking",
                "--disable-component-update",
                "--disable-sync",
                f"--user-data-dir={profile}",
                f"--window-size={width},{height}",
                "--remote-debugging-pipe",
                "about:blank",
            ],
            preexec_fn=plumb,
            close_fds=False,
            stdin=subprocess.DEVNULL,
            stdout=subprocess.DEVNULL,
            stderr=subprocess.DEVNULL,
            start_new_session=True,
        )
        os.close(to_browser_r)
        os.close(from_browser_w)
        self._buffer = b""
        self._id = 0
        self.console: list[str] = []
        self._session = None

    def open(self, url: str) -> None:
        target = self.call("Target.createTarget", {"url": url})["targetId"]
        self._session = self.call("Target.attachToTarget", {"targetId": target, "flatten": True})[
            "sessionId"
        ]
        for domain in ("Runtime", "Log", "Page"):
            self.call(f"{domain}.enable")

    def screenshot(self, attempts: int = 5) -> np.ndarray:
        """Returns the page as an (h, w, 3) uint8 image (retried while the page loads)."""
        from PIL import Image

        for attempt in range(attempts):
            try:
                data = self.call("Page.captureScreenshot", {"format": "png"}, timeout_s=60)
                break
            except RuntimeError:
                if attempt == attempts - 1:
                    raise
                time.sleep(2.0)
        image = Image.open(io.BytesIO(base64.b64decode(data["data"])))
        return np.asarray(image.convert("RGB"))

    def call(self, method: str, params: dict | None = None, timeout_s: float = 30.0) -> dict:
        self._id += 1
        message = {"id": self._id, "method": method, "params": params or {}}
        if self._session is not None:
            message["sessionId"] = self._session
        os.write(self._to_browser, json.dumps(message).encode() + b"\0")
        deadline = time.monotonic() + timeout_s
        while True:
            reply = self._receive(deadline)
            if reply.get("id") == self._id:
                if "error" in reply:
                    raise RuntimeError(f"{method}: {reply['error']}")
                return reply["result"]
            self._note(reply)

    def _receive(self, deadline: float) -> dict:
        while b"\0" not in self._buffer:
            ready, _, _ = select.select([self._from_browser], [], [], deadline - time.monotonic())
            if not ready:
                raise TimeoutError("no reply from Chromium")
            data = os.read(self._from_browser, 1 << 20)
            if not data:
                raise EOFError("Chromium closed the DevTools pipe")
            self._buffer += data
        message, _, self._buffer = self._buffer.partition(b"\0")
        return json.loads(message)

    def _note(self, event: dict) -> None:
        method, params = event.get("method"), event.get("params", {})
        if method == "Runtime.consoleAPICalled":
            texts = [str(a.get("value", a.get("description", ""))) for a in params["args"]]
            self.console.append(" ".join(texts))
        elif method == "Log.entryAdded":
            self.console.append(params["entry"]["text"])

    def close(self) -> None:
        self.process.terminate()
        try:
            self.process.wait(timeout=10)
        except subprocess.TimeoutExpired:
            self.process.kill()
            self.process.wait()
        os.close(self._to_browser)
        os.close(self._from_browser)


def _table_fraction(image: np.ndarray) -> float:
    """Fraction of pixels in the table's brown (the dark viewer UI is grey)."""
    r, g, b = (image[..., k].astype(int) for k in range(3))
    return float(np.mean((r > g) & (g > b) & (r - b > 30) & (r > 70)))


@pytest.mark.slow
@pytest.mark.skipif(not CHROMIUM.exists(), reason="needs /usr/bin/chromium (make test installs it)")
def test_web_viewer_renders_the_recording_in_headless_chromium(
    recording: Path, tmp_path: Path
) -> None:
    web_port = _free_port()
    grpc_port = _free_port(web_port)
    with serve_recording(recording, web_port=web_port, grpc_port=grpc_port) as viewer:
        assert viewer.url.startswith(f"http://127.0.0.1:{web_port}/")
        browser = _Chromium(tmp_path / "profile")
        try:
            browser.open(viewer.url)
            deadline = time.monotonic() + 180.0
            image = browser.screenshot()
            while _table_fraction(image) < 0.02 and time.monotonic() < deadline:
                time.sleep(3.0)
                image = browser.screenshot()
        finally:
            browser.close()
    console = browser.console
    streamed = [line for line in console if "Streaming messages from gRPC" in line]
    assert any(f"port: {grpc_port}" in line for line in streamed), console[-20:]
    assert not [line for line in console if "panicked" in line or line.startswith(" ERROR")]
    assert not [line for line in console if "ERR_CONNECTION_REFUSED" in line]
    assert image.std() > 10.0
    assert _table_fraction(image) >= 0.02
