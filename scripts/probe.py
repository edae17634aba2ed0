"""Probe one object with the simulated robot and recognise it against the 10-model database.

python scripts/probe.py --object cat
python scripts/probe.py --object snail --seed 3 --out runs/snail
python scripts/probe.py --object cat --rerun serve --web-port 9090
"""

from __future__ import annotations

import argparse
import sys
import time
from dataclasses import dataclass
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

import numpy as np

from recognition.errors import RecognitionError
from tactile_sim.errors import SimulationError

ROOT = Path(__file__).resolve().parents[1]


@dataclass(frozen=True)
class Config:
    """What to probe and where to put the results.

    Attributes
    ----------
    object_name : str
        A catalog object (``tactile_sim.objects.object_names()``).
    seed : int
        Seeds the object's pose, the probed point, the planes and the sensor noise.
    n_points, spacing_mm, plane_angle_deg
        Points per curve, their spacing and the angle between sampling planes
        (thesis Section 4.4.3: 21, 1.2 mm, 60 degrees).
    out : Path or None
        Directory for the curves (.npz) and the summary; default runs/.
    rerun : str
        "save" (an .rrd file), "spawn" (open the viewer), "serve" (web viewer on
        127.0.0.1) or "off".
    web_port, grpc_port : int
        Ports of the web viewer ("serve"): HTTP for the page, gRPC for the data.
    trajectory_hz : float
        Rate (per second of simulated time) at which the recording samples the robot.
    """

    object_name: str = "cat"
    seed: int = 0
    n_points: int = 21
    spacing_mm: float = 1.2
    plane_angle_deg: float = 60.0
    out: Path | None = None
    rerun: str = "save"
    web_port: int = 9090
    grpc_port: int = 9876
    trajectory_hz: float = 200.0


def pose_error(
    T_estimated: np.ndarray, T_true: np.ndarray, points: np.ndarray
) -> tuple[float, float]:
    """Returns the rotation error (degrees) between two 4x4 poses and the mean distance
    (metres) between where they put ``points`` (n, 3): the data on the model."""
    dR = T_estimated[:3, :3] @ T_true[:3, :3].T
    angle = np.degrees(np.arccos(np.clip((np.trace(dR) - 1) / 2, -1.0, 1.0)))
    moved = points @ (T_estimated[:3, :3] - T_true[:3, :3]).T + (T_estimated - T_true)[:3, 3]
    return float(angle), float(np.linalg.norm(moved, axis=1).mean())


def run(config: Config) -> dict:
    """Probe, recognise, report; returns the summary as a dict."""
    from tactile_sim.objects import object_names
    from tactile_sim.objects.database import catalog_database
    from tactile_sim.probing import probe_object

    if config.object_name not in object_names():
        from tactile_sim.errors import UnknownObject

        raise UnknownObject(config.object_name, object_names())
    if config.rerun == "serve":
        from tactile_sim.recording import check_ports

        check_ports(config.web_port, config.grpc_port)
    elif config.rerun == "spawn":
        from tactile_sim.recording import check_display

        check_display()
    start = time.perf_counter()
    database = catalog_database()
    loaded = time.perf_counter()
    session = probe_object(
        config.object_name,
        seed=config.seed,
        n_points=config.n_points,
        spacing_m=config.spacing_mm * 1e-3,
        plane_angle_deg=config.plane_angle_deg,
        trajectory_hz=None if config.rerun == "off" else config.trajectory_hz,
    )
    probed = time.perf_counter()
    result = database.recognize(session.curves)
    recognized = time.perf_counter()

    truth = session.ground_truth
    T_object_from_world = np.linalg.inv(truth.T_world_from_object)
    summary = {
        "object": config.object_name,
        "seed": config.seed,
        "recognized": result.name,
        "correct": result.name == config.object_name,
        "ranking_mm": [(n, e * 1e3 if np.isfinite(e) else None) for n, e in result.ranking],
        "margin_mm": result.margin_m * 1e3,
        "truncated_sweeps": list(session.messages),
        "timings_s": {
            "database": loaded - start,
            "probing": probed - loaded,
            "recognition": recognized - probed,
            "total": recognized - start,
        },
    }
    own = result.registrations[config.object_name]
    if np.all(np.isfinite(own.location)):
        summary["location_error_mm"] = float(
            np.linalg.norm(own.location - truth.point_in_object) * 1e3
        )
        data = np.concatenate(session.curves.curves)
        angle, shift = pose_error(own.T_model_from_data, T_object_from_world, data)
        summary["pose_error_deg"], summary["pose_error_mm"] = angle, shift * 1e3

    out = Path(config.out) if config.out else ROOT / "runs"
    out.mkdir(parents=True, exist_ok=True)
    stem = f"{time.strftime('%Y%m%d-%H%M%S')}_{config.object_name}_seed{config.seed}"
    session.curves.save(out / f"{stem}_curves.npz")
    summary["curves_file"] = str(out / f"{stem}_curves.npz")
    if config.rerun != "off":
        from tactile_sim.recording import record_probe_run

        summary["recording"] = record_probe_run(
            session, result, database, mode=config.rerun, path=out / f"{stem}.rrd"
        )
    _print(summary)
    if config.rerun == "serve":
        from tactile_sim.recording import serve_recording

        with serve_recording(
            out / f"{stem}.rrd", web_port=config.web_port, grpc_port=config.grpc_port
        ) as viewer:
            print(f"web viewer: {viewer.url} (Ctrl-C to stop)", flush=True)
            viewer.wait()
    return summary


def _print(s: dict) -> None:
    mark = "correct" if s["correct"] else "WRONG"
    print(f"object {s['object']} (seed {s['seed']}): recognised as {s['recognized']} ({mark})")
    print("ranking (mean distance of the data to each model, mm):")
    for name, error in s["ranking_mm"][:5]:
        print(f"  {name:10s} {'rejected at table lookup' if error is None else f'{error:.4f}'}")
    if "location_error_mm" in s:
        print(
            f"location error on {s['object']}: {s['location_error_mm']:.3f} mm; pose error "
            f"{s['pose_error_deg']:.2f} deg, data {s['pose_error_mm']:.3f} mm from their true place"
        )
    for message in s["truncated_sweeps"]:
        print(f"  truncated: {message}")
    t = s["timings_s"]
    print(
        f"timings: database {t['database']:.2f} s, probing {t['probing']:.2f} s, "
        f"recognition {t['recognition']:.2f} s, total {t['total']:.2f} s"
    )
    print(f"curves: {s['curves_file']}")
    if s.get("recording"):
        print(f"recording: {s['recording']}")


def parse_args(argv=None) -> Config:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--object", default="cat", help="catalog object to probe")
    p.add_argument("--seed", type=int, default=0)
    p.add_argument("--n-points", type=int, default=21)
    p.add_argument("--spacing-mm", type=float, default=1.2)
    p.add_argument("--plane-angle", type=float, default=60.0)
    p.add_argument("--out", type=Path, default=None, help="output directory (default runs/)")
    p.add_argument(
        "--rerun",
        choices=("save", "spawn", "serve", "off"),
        default="save",
        help="save an .rrd (default), spawn the native viewer, serve a web viewer on "
        "127.0.0.1, or record nothing",
    )
    p.add_argument("--web-port", type=int, default=9090, help="web viewer HTTP port (serve)")
    p.add_argument("--grpc-port", type=int, default=9876, help="recording gRPC port (serve)")
    a = p.parse_args(argv)
    if a.n_points < 5 or a.spacing_mm <= 0:
        p.error("--n-points must be at least 5 and --spacing-mm positive")
    return Config(
        a.object,
        a.seed,
        a.n_points,
        a.spacing_mm,
        a.plane_angle,
        a.out,
        a.rerun,
        a.web_port,
        a.grpc_port,
    )


def main(argv=None) -> int:
    config = parse_args(argv)
    try:
        run(config)
    except (SimulationError, RecognitionError, OSError) as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2
    return 0


if __name__ == "__main__":
    sys.exit(main())
