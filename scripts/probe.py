"""Probe one object with the simulated robot and recognise it against the 10-model database.

python scripts/probe.py --object cat
python scripts/probe.py --object snail --seed 3 --out runs/snail
python scripts/probe.py --object cat --rerun serve --web-port 9090
python scripts/probe.py --object cat --model-error-mm 0.1 --json runs/cat.json
python scripts/probe.py --object fish --seed 1 --model-error-mm 0.1 --touches 5
python scripts/probe.py --mesh my_scan.ply --units mm
"""

from __future__ import annotations

import sys
from pathlib import Path
from typing import Any

from recognition.surfaces.mesh_files import UNITS
from tactile_sim.cli import ArgumentParser, integer, real, require_writable, run_cli, viewer_ports
from tactile_sim.evaluation import RERUN_MODES, ProbeRunConfig, probe_run
from tactile_sim.probing import (
    MAX_CURVE_LENGTH_M,
    MAX_SPACING_M,
    MIN_CURVE_POINTS,
    PLANE_ANGLE_RANGE_DEG,
)
from tactile_sim.recording.viewer import GRPC_PORT, WEB_PORT


def run(config: ProbeRunConfig) -> dict[str, Any]:
    """Probe, recognise, report; with ``--rerun serve``, serve the recording until stopped.
    Returns the summary (:func:`tactile_sim.evaluation.probe_run`)."""
    summary = probe_run(config)
    show(summary)
    if config.rerun == "serve":
        from tactile_sim.recording import serve_recording

        with serve_recording(
            Path(summary["recording"]), web_port=config.web_port, grpc_port=config.grpc_port
        ) as viewer:
            print(f"web viewer: {viewer.url} (Ctrl-C to stop)", flush=True)
            viewer.wait()
    return summary


def show(s: dict[str, Any]) -> None:
    """Print a run's summary: the ranking, the errors against the truth, timings, files."""
    mark = "correct" if s["correct"] else "WRONG"
    for note in s.get("mesh_repairs", []):
        print(f"mesh: {note}")
    print(f"object {s['object']} (seed {s['seed']}): recognised as {s['recognized']} ({mark})")
    print("ranking (mean distance of the data to each model, mm):")
    for name, error in s["ranking_mm"][:5]:
        print(f"  {name:10s} {'rejected at table lookup' if error is None else f'{error:.4f}'}")
    if "location_error_mm" in s:
        print(
            f"location error on {s['object']}: {s['location_error_mm']:.3f} mm; pose error "
            f"{s['pose_error_deg']:.2f} deg, data {s['pose_error_mm']:.3f} mm from their true place"
        )
    if "model_error_mm" in s:
        e = s["model_error_mm"]
        print(
            f"model error: the object lies {e['achieved_rms']:.3f} mm RMS from its model "
            f"(asked {e['requested_rms']:g} mm, correlation {e['correlation']:g} mm)"
        )
    if "touches" in s:
        t = s["touches"]
        print(f"confidence after the sweeps: {s['confidence']:.3f} ({s['belief_best']})")
        for k, made in enumerate(t["made"], 1):
            met = "contact" if made["contact"] else "no contact"
            if made.get("no_reading"):
                met = f"no reading ({made['no_reading']})"
            print(
                f"  touch {k}: {met}; best {made['best']}, confidence {made['confidence']:.3f} "
                f"({made['recognition_time_s']:.2f} s planning and update)"
            )
        mark = "correct" if t["correct"] else "WRONG"
        located = (
            f", location error {t['location_error_mm']:.3f} mm" if "location_error_mm" in t else ""
        )
        print(
            f"after {len(t['made'])} touches ({t['stop']}): {t['recognized']} ({mark}), "
            f"confidence {t['confidence']:.3f}{located}"
        )
    if s["outliers"]:
        print(f"outliers rejected: points {', '.join(map(str, s['outliers']))}")
    for message in s["truncated_sweeps"]:
        print(f"  truncated: {message}")
    t = s["timings_s"]
    print(
        f"timings: object {t['object']:.2f} s, database {t['database']:.2f} s, probing "
        f"{t['probing']:.2f} s (scene "
        f"{t['scene_build']:.2f} s), recognition {t['recognition']:.2f} s, touches "
        f"{t['touches']:.2f} s, total {t['total']:.2f} s"
    )
    print(f"curves: {s['curves_file']}")
    if s.get("recording"):
        print(f"recording: {s['recording']}")


def parse_args(argv: list[str] | None = None) -> ProbeRunConfig:
    """The run's settings from the command line (``argv``: default ``sys.argv``); a bad
    one, an output path that cannot be written or a viewer port in use exits 2 here,
    before any work."""
    low_angle, high_angle = PLANE_ANGLE_RANGE_DEG
    p = ArgumentParser(description=(__doc__ or "").splitlines()[0])
    p.add_argument("--object", default="cat", help="catalog object to probe")
    p.add_argument(
        "--mesh",
        type=Path,
        default=None,
        help="probe this mesh file instead (OBJ, PLY, STL, OFF, GLB, glTF; open or in pieces)",
    )
    p.add_argument("--units", choices=tuple(UNITS), default="m", help="of the --mesh file")
    p.add_argument(
        "--database",
        type=Path,
        default=None,
        help="recognise against this saved database (default: the catalog's, with --mesh "
        "the catalog's and the mesh's)",
    )
    p.add_argument("--seed", type=integer(0), default=0)
    p.add_argument("--n-points", type=integer(MIN_CURVE_POINTS), default=21, help="per curve")
    p.add_argument(
        "--spacing-mm",
        type=real(0.0, MAX_SPACING_M * 1e3, low_open=True, high_open=True),
        default=1.2,
        help="between points along a curve",
    )
    p.add_argument(
        "--plane-angle",
        type=real(low_angle, high_angle),
        default=60.0,
        help="between sampling planes, degrees",
    )
    p.add_argument("--out", type=Path, default=None, help="output directory (default runs/)")
    p.add_argument(
        "--rerun",
        choices=RERUN_MODES,
        default="save",
        help="save an .rrd (default), spawn the native viewer, serve a web viewer on "
        "127.0.0.1, or record nothing",
    )
    p.add_argument("--web-port", type=int, help=f"web viewer HTTP port (serve; {WEB_PORT})")
    p.add_argument("--grpc-port", type=int, help=f"recording gRPC port (serve; {GRPC_PORT})")
    p.add_argument(
        "--model-error-mm",
        type=real(0.0),
        default=0.0,
        help="probe the object displaced from its model along the normals by a smooth "
        "random field of this RMS, mm (default 0)",
    )
    p.add_argument(
        "--model-error-correlation-mm",
        type=real(0.0, low_open=True),
        default=5.0,
        help="correlation length of that field, mm",
    )
    p.add_argument(
        "--touches",
        type=integer(0),
        default=5,
        help="verification touches after the sweeps, at most, until the answer is sure "
        "(confidence 0.99; default 5; 0: the three curves alone)",
    )
    p.add_argument("--json", type=Path, default=None, help="also write the summary here")
    a = p.parse_args(argv)
    if (a.n_points - 1) * a.spacing_mm > MAX_CURVE_LENGTH_M * 1e3:
        p.error(
            f"--n-points {a.n_points} at --spacing-mm {a.spacing_mm:g} make curves of "
            f"{(a.n_points - 1) * a.spacing_mm:g} mm; expected at most "
            f"{MAX_CURVE_LENGTH_M * 1e3:g} mm"
        )
    if a.mesh is not None and not a.mesh.is_file():
        p.error(f"--mesh {a.mesh} is not a file")
    if a.database is not None and not (a.database / "manifest.json").is_file():
        p.error(f"--database {a.database} is not a saved model database (no manifest.json)")
    web_port, grpc_port = viewer_ports(
        p, a.web_port, a.grpc_port, serving=a.rerun == "serve", needs="--rerun serve"
    )
    config = ProbeRunConfig(
        object_name=a.object,
        mesh=a.mesh,
        units=a.units,
        database=a.database,
        seed=a.seed,
        n_points=a.n_points,
        spacing_mm=a.spacing_mm,
        plane_angle_deg=a.plane_angle,
        out=a.out,
        rerun=a.rerun,
        web_port=web_port,
        grpc_port=grpc_port,
        model_error_mm=a.model_error_mm,
        model_error_correlation_mm=a.model_error_correlation_mm,
        json_path=a.json,
        touches=a.touches,
    )
    require_writable(p, "--out", config.out_dir, directory=True)
    require_writable(p, "--json", a.json)
    return config


def main(argv: list[str] | None = None) -> int:
    """Parse the arguments, probe and report; 2 on bad input."""
    config = parse_args(argv)
    return run_cli(lambda: run(config))


if __name__ == "__main__":
    sys.exit(main())
