"""Reading recordings back: missing, truncated and foreign files."""

from __future__ import annotations

from pathlib import Path

import pytest
from testing_scripts import load_script

from tactile_sim.errors import InvalidRecording
from tactile_sim.recording import read_recording


def test_missing_truncated_and_foreign_files_raise_invalid_recording(
    recording: Path, tmp_path: Path
) -> None:
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


def test_a_recording_without_its_footer_is_reported_truncated(tmp_path: Path) -> None:
    import rerun as rr

    path = tmp_path / "unfinished.rrd"
    rec = rr.RecordingStream("tactile_sim", recording_id="unfinished")
    rec.save(path, write_footer=False)
    rec.log("world/p", rr.Points3D([[0.0, 0.0, 0.0]]))
    rec.disconnect()
    with pytest.raises(InvalidRecording, match="no footer"):
        read_recording(path)


def test_replay_reports_bad_files_in_one_line_with_status_2(
    recording: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    replay = load_script("replay")
    truncated = tmp_path / "cut.rrd"
    truncated.write_bytes(recording.read_bytes()[:4000])
    for path in (tmp_path / "missing.rrd", truncated):
        assert replay.main([str(path)]) == 2
        err = capsys.readouterr().err.strip().splitlines()
        assert len(err) == 1 and err[0].startswith("error: ")
