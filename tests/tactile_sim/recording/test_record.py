"""Recording modes and the probe script's recording options."""

from __future__ import annotations

from pathlib import Path

import pytest
from testing_scripts import load_script

from tactile_sim.probing import ProbeSession
from tactile_sim.recording import record_probe_run


def test_bad_modes_and_probe_options_are_rejected(session: ProbeSession, tmp_path: Path) -> None:
    with pytest.raises(ValueError, match="mode"):
        record_probe_run(session, mode="stream", path=tmp_path / "x.rrd")
    probe = load_script("probe")
    config = probe.parse_args(["--object", "cat", "--rerun", "serve", "--web-port", "9191"])
    assert (config.rerun, config.web_port, config.grpc_port) == ("serve", 9191, 9876)
