"""Trajectory capture, rerun recordings read back, bad recordings, ports and the web viewer."""

from __future__ import annotations

import base64
import io
import json
import os
import select
import socket
import subprocess
import time
from pathlib import Path

import numpy as np
import pytest
from testing_scripts import load_script

from tactile_sim.errors import InvalidRecording, PortInUse, SimulationError
from tactile_sim.probing import probe_object, resolve_object
from tactile_sim.recording import (
    check_ports,
    read_recording,
    record_probe_run,
    serve_recording,
)

ROOT = Path(__file__).resolve().parents[2]
CHROMIUM = Path("/usr/bin/chromium")


@pytest.fixture(scope="module")
def session():
    return probe_object("sphere", seed=3, n_points=7, trajectory_hz=200.0, progress=False)


@pytest.fixture(scope="module")
def recognized(session):
    from recognition import ModelDatabase

    database = ModelDatabase.from_meshes(
        {name: resolve_object(name, progress=False).mesh for name in ("sphere", "cylinder_1")}
    )
    return database.recognize(session.curves), database


@pytest.fixture(scope="module")
def recording(session, recognized, tmp_path_factory):
    result, database = recognized
    path = tmp_path_factory.mktemp("recording") / "sphere_seed3.rrd"
    assert record_probe_run(session, result, database, mode="save", path=path) == str(path)
    return path


# Trajectory capture ------------------------------------------------------------------------


def test_capture_is_off_by_default_and_does_not_change_the_session(session):
    plain = probe_object("sphere", seed=3, n_points=7, progress=False)
    assert plain.trajectory is None
    assert plain.sim_seconds == session.sim_seconds
    for a, b in zip(plain.curves.curves, session.curves.curves, strict=True):
        np.testing.assert_array_equal(a, b)


def test_trajectory_samples_every_few_steps_and_passes_through_the_readings(session):
    trajectory = session.trajectory
    every = 5  # 200 Hz at the 1 ms timestep
    total_steps = round(session.sim_seconds / trajectory.timestep_s)
    assert len(trajectory) == total_steps // every + 1
    np.testing.assert_array_equal(trajectory.steps, every * np.arange(len(trajectory)))
    b = len(trajectory.body_names)
    assert {"inner_link", "joystick_probe/tip"} <= set(trajectory.body_names)
    assert trajectory.body_positions_in_world.shape == (len(trajectory), b, 3)
    norms = np.linalg.norm(trajectory.body_quats_wxyz_in_world, axis=-1)
    np.testing.assert_allclose(norms, 1.0, atol=1e-9)
    assert "base" in trajectory.static_body_names
    # The tip passes (within the distance covered between two samples) through every
    # true tip centre at a reading.
    for sweep in session.sweeps:
        gaps = np.linalg.norm(
            sweep.true_tip_centres_in_world[:, None] - trajectory.tip_centres_in_world[None],
            axis=-1,
        ).min(axis=1)
        assert gaps.max() < 0.2e-3
        assert np.all(np.diff(np.sort(sweep.reading_times_s)) > 0)
    assert trajectory.deflection_magnitude_rad.max() > 1e-3  # the presses tilt the stylus
    assert trajectory.tip_force_n[:, 2].max() > 0.01  # and load it axially


# Round trip --------------------------------------------------------------------------------


def test_recording_round_trip(recording, session, recognized):
    result, _ = recognized
    summary = read_recording(recording)
    trajectory = session.trajectory
    n = len(trajectory)
    assert summary.application_id == "tactile_sim"
    assert summary.has_blueprint
    for body in trajectory.body_names:
        assert summary.rows[f"world/robot/{body}"] == n
    for entity in ("world/probe/tip", "sensors/deflection", "sensors/force"):
        assert summary.rows[entity] == n
    sensed = sum(s.n_points for s in session.sweeps)
    assert sensed == 21
    for entity in ("world/probe/sensed", "world/probe/contacts", "world/probe/normals"):
        assert summary.rows[entity] == sensed
    for curve in ("alpha", "beta", "gamma"):
        assert summary.rows[f"world/curves/{curve}"] == 1
    static = summary.static
    assert {
        "world/object",
        "world/object/visual",
        "world/table/table_top",
        "world/robot/base",
        "world/robot/inner_link/inner_link_beam",
        "world/robot/joystick_probe/tip/tip_visual",
        "recognition/ranking",
    } <= static
    for name in result.registrations:
        assert f"recognition/models/{name}/candidates" in static
    assert result.name == "sphere"
    assert {f"recognition/models/sphere/curves/{c}" for c in ("alpha", "beta", "gamma")} <= static


def test_body_quaternions_are_stored_xyzw(recording, session):
    from rerun.chunk import RrdReader

    trajectory = session.trajectory
    b = trajectory.body_names.index("inner_link")
    for chunk in RrdReader(recording).stream():
        if chunk.entity_path == "/world/robot/inner_link" and not chunk.is_static:
            batch = chunk.to_record_batch()
            columns = dict(zip(batch.schema.names, batch.columns, strict=True))
            steps = columns["step"].to_numpy()
            quats = np.array(columns["Transform3D:quaternion"].to_pylist()).reshape(-1, 4)
            break
    else:
        pytest.fail("no temporal chunk for world/robot/inner_link")
    index = np.searchsorted(trajectory.steps, steps)
    wxyz = trajectory.body_quats_wxyz_in_world[index, b]
    np.testing.assert_allclose(quats, wxyz[:, [1, 2, 3, 0]], atol=1e-6)


# Bad input ---------------------------------------------------------------------------------


def test_missing_truncated_and_foreign_files_raise_invalid_recording(recording, tmp_path):
    with pytest.raises(InvalidRecording, match="does not exist"):
        read_recording(tmp_path / "missing.rrd")
    data = recording.read_bytes()
    truncated = tmp_path / "truncated.rrd"
    truncated.write_bytes(data[: len(data) // 2])
    with pytest.raises(InvalidRecording, match="truncated"):
        read_recording(truncated)
    foreign = tmp_path / "notes.rrd"
    foreign.write_text("not a recording\n")
    with pytest.raises(InvalidRecording):
        read_recording(foreign)


def test_a_recording_without_its_footer_is_reported_truncated(tmp_path):
    import rerun as rr

    path = tmp_path / "unfinished.rrd"
    rec = rr.RecordingStream("tactile_sim", recording_id="unfinished")
    rec.save(path, write_footer=False)
    rec.log("world/p", rr.Points3D([[0.0, 0.0, 0.0]]))
    rec.disconnect()
    with pytest.raises(InvalidRecording, match="no footer"):
        read_recording(path)


def test_replay_reports_bad_files_in_one_line_with_status_2(recording, tmp_path, capsys):
    replay = load_script("replay")
    truncated = tmp_path / "cut.rrd"
    truncated.write_bytes(recording.read_bytes()[:4000])
    for path in (tmp_path / "missing.rrd", truncated):
        assert replay.main([str(path)]) == 2
        err = capsys.readouterr().err.strip().splitlines()
        assert len(err) == 1 and err[0].startswith("error: ")


def test_port_in_use_is_reported_with_a_free_alternative():
    with socket.socket() as taken:
        taken.bind(("127.0.0.1", 0))
        taken.listen()
        port = taken.getsockname()[1]
        with pytest.raises(PortInUse, match=rf"port {port} in use; pass --web-port \d+") as info:
            check_ports(port, _free_port())
        alternative = info.value.alternative
        assert alternative != port
        check_ports(alternative, _free_port())
    assert isinstance(info.value, SimulationError)


def test_bad_modes_and_probe_options_are_rejected(session, tmp_path):
    with pytest.raises(ValueError, match="mode"):
        record_probe_run(session, mode="stream", path=tmp_path / "x.rrd")
    probe = load_script("probe")
    config = probe.parse_args(["--object", "cat", "--rerun", "serve", "--web-port", "9191"])
    assert (config.rerun, config.web_port, config.grpc_port) == ("serve", 9191, 9876)


# The web viewer in a headless browser ------------------------------------------------------


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


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
def test_web_viewer_renders_the_recording_in_headless_chromium(recording, tmp_path):
    web_port, grpc_port = _free_port(), _free_port()
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


def test_recording_overhead_reports_times_and_sizes():
    from tactile_sim.recording import recording_overhead

    report = recording_overhead("sphere", seeds=(1,), n_points=7)
    (run,) = report["runs"]
    assert run["plain_s"] > 0 and run["sampled_s"] > 0 and run["logging_s"] > 0
    assert run["rrd_bytes"] > 10_000 and run["samples"] > 100
    assert report["total"]["overhead"] == pytest.approx(run["overhead"])
