"""Open a saved probing recording (.rrd) in rerun's native viewer or serve it to a browser.

python scripts/replay.py runs/20260101-120000_cat_seed0.rrd
python scripts/replay.py runs/20260101-120000_cat_seed0.rrd --web --port 9090
"""

from __future__ import annotations

import sys
from dataclasses import dataclass
from pathlib import Path

from tactile_sim.cli import ArgumentParser, run_cli, viewer_ports
from tactile_sim.recording.viewer import GRPC_PORT, WEB_PORT


@dataclass(frozen=True)
class Config:
    """Which recording to show, and where.

    Attributes
    ----------
    file : Path
        A recording written by ``scripts/probe.py`` (or any .rrd file).
    web : bool
        Serve it to a browser (web viewer on 127.0.0.1) instead of the native viewer.
    web_port, grpc_port : int
        Ports of the web viewer: HTTP for the page, gRPC for the data.
    """

    file: Path
    web: bool = False
    web_port: int = WEB_PORT
    grpc_port: int = GRPC_PORT


def run(config: Config) -> None:
    """Checks the recording, then shows it until the viewer (or the server) is stopped."""
    from tactile_sim.recording import open_native_viewer, read_recording, serve_recording

    summary = read_recording(config.file)
    rows = sum(summary.rows.values())
    print(f"{config.file}: {len(summary.entities)} entities, {rows} timed rows")
    if not config.web:
        open_native_viewer(config.file)
        return
    with serve_recording(
        config.file, web_port=config.web_port, grpc_port=config.grpc_port
    ) as viewer:
        print(f"web viewer: {viewer.url} (Ctrl-C to stop)", flush=True)
        viewer.wait()


def parse_args(argv: list[str] | None = None) -> Config:
    """The recording and viewer from the command line (``argv``: default ``sys.argv``);
    bad or busy ports exit 2 here."""
    p = ArgumentParser(description=(__doc__ or "").splitlines()[0])
    p.add_argument("file", type=Path, help="the .rrd recording")
    p.add_argument("--web", action="store_true", help="serve to a browser on 127.0.0.1")
    p.add_argument(
        "--port", "--web-port", dest="web_port", type=int, help=f"web viewer port ({WEB_PORT})"
    )
    p.add_argument("--grpc-port", type=int, help=f"recording gRPC port (--web; {GRPC_PORT})")
    a = p.parse_args(argv)
    ports = viewer_ports(p, a.web_port, a.grpc_port, serving=a.web, needs="--web")
    return Config(a.file, a.web, *ports)


def main(argv: list[str] | None = None) -> int:
    """Parse the arguments and show the recording; 2 on a bad recording."""
    config = parse_args(argv)
    return run_cli(lambda: run(config))


if __name__ == "__main__":
    sys.exit(main())
