"""Recognition benchmark over the 10-model database or your own meshes (thesis 4.3.4).

python scripts/benchmark.py                               # all three methods
python scripts/benchmark.py --method fast --json out.json
python scripts/benchmark.py --sweep delta                 # Fig. 4.11 (also length, angle)
python scripts/benchmark.py --mesh-dir my_meshes --units mm --with-catalog
python scripts/benchmark.py --backend ray --ray-address auto --workers 8
python scripts/benchmark.py --source sim --json out.json   # simulated robot: Tables 4.5-4.7
python scripts/benchmark.py --source sim --experiment catalog --sessions 1 --method fast
python scripts/benchmark.py --out-dir docs/benchmarks     # the committed reports

Reports go to runs/benchmark/ unless --out-dir says otherwise.
"""

from __future__ import annotations

import argparse
import os
import sys
from pathlib import Path

from recognition.evaluation import BACKENDS
from recognition.surfaces.mesh_files import UNITS
from tactile_sim.cli import run_cli
from tactile_sim.evaluation import (
    EXPERIMENTS,
    METHODS,
    SOURCES,
    SWEEPS,
    BenchmarkConfig,
    MeshSettings,
    MethodSettings,
    ReportSettings,
    RunSettings,
    SimSettings,
    SyntheticSettings,
    run,
)


def parse_args(argv: list[str] | None = None) -> BenchmarkConfig:
    """The benchmark's settings from the command line (``argv``: default ``sys.argv``)."""
    defaults = BenchmarkConfig()
    p = argparse.ArgumentParser(description=(__doc__ or "").splitlines()[0])
    p.add_argument(
        "--method",
        action="append",
        choices=METHODS,
        help="registration mode (repeatable; default all three)",
    )
    p.add_argument("--per-model", type=int, default=10)
    p.add_argument("--n-points", type=int, default=81)
    p.add_argument("--spacing-mm", type=float, default=0.3)
    p.add_argument("--plane-angle", type=float, default=60.0)
    p.add_argument("--noise-mm", type=float, default=0.02)
    p.add_argument("--delta", type=float, default=0.03, help="lookup tolerance, 1/mm")
    p.add_argument("--thesis-instances", type=int, default=20)
    p.add_argument("--workers", type=int, default=os.cpu_count() or 1)
    p.add_argument("--backend", choices=BACKENDS, default="local")
    p.add_argument("--ray-address", default=None, help="existing Ray cluster (e.g. auto)")
    p.add_argument("--mesh-dir", type=Path)
    p.add_argument("--units", choices=tuple(UNITS), default="m", help="of the --mesh-dir meshes")
    p.add_argument(
        "--with-catalog",
        action="store_true",
        help="with --mesh-dir: recognise against the catalog's models as well",
    )
    p.add_argument("--sweep", choices=tuple(SWEEPS))
    p.add_argument("--results", type=Path, help="JSONL of per-instance records")
    p.add_argument("--json", type=Path, dest="json_path", help="summary per method")
    p.add_argument(
        "--out-dir",
        type=Path,
        default=defaults.report.out_dir,
        help="reports and figures (default runs/benchmark; docs/benchmarks for the committed)",
    )
    p.add_argument("--tag", default="", help="suffix of the summary file name")
    p.add_argument("--seed", type=int, default=0)
    p.add_argument(
        "--source", choices=SOURCES, default="synthetic", help="synthetic curves or the robot"
    )
    p.add_argument(
        "--experiment",
        action="append",
        choices=EXPERIMENTS,
        help="with --source sim: catalog (Tables 4.6-4.7), solids (Table 4.5) and/or "
        "sensing (sensed points against the meshes, wall times)",
    )
    p.add_argument("--sessions", type=int, default=3, help="with --source sim: seeds per object")
    p.add_argument(
        "--first-session",
        type=int,
        default=0,
        help="with --source sim: index of each object's first session (e.g. 3 with "
        "--sessions 5: sessions 3-7)",
    )
    p.add_argument("--object", action="append", help="with --source sim: probe only these")
    p.add_argument(
        "--sim-curves",
        choices=("sensed", "true_contacts"),
        default="sensed",
        help="with --source sim: recognise the sensed or the true contact points",
    )
    p.add_argument(
        "--sim-spacing-mm",
        type=float,
        help="with --source sim: point spacing instead of the experiment's own",
    )
    p.add_argument(
        "--model-error-mm",
        type=float,
        default=0.0,
        help="with --source sim: each probed object displaced from its model along the "
        "normals by a smooth random field of this RMS, mm, and the fast mode told so "
        "(default 0)",
    )
    a = p.parse_args(argv)
    if a.sim_spacing_mm is not None and not 0 < a.sim_spacing_mm < 20:
        p.error("--sim-spacing-mm must lie in (0, 20)")
    if not 0 <= a.model_error_mm < 5:
        p.error("--model-error-mm must lie in [0, 5)")
    if a.sessions < 1 or a.first_session < 0:
        p.error("--sessions must be at least 1 and --first-session at least 0")
    if a.source == "sim" and a.sweep is not None:
        p.error("--sweep applies to --source synthetic only")
    for name in ("per_model", "n_points", "workers"):
        if getattr(a, name) < 1:
            p.error(f"--{name.replace('_', '-')} must be at least 1")
    if a.spacing_mm <= 0 or a.delta <= 0 or a.noise_mm < 0:
        p.error("--spacing-mm and --delta must be positive, --noise-mm not negative")
    if a.mesh_dir is not None and not a.mesh_dir.is_dir():
        p.error(f"--mesh-dir {a.mesh_dir} is not a directory")
    if a.with_catalog and a.mesh_dir is None:
        p.error("--with-catalog applies to --mesh-dir")
    return BenchmarkConfig(
        source=a.source,
        synthetic=SyntheticSettings(
            per_model=a.per_model,
            n_points=a.n_points,
            spacing_mm=a.spacing_mm,
            plane_angle_deg=a.plane_angle,
            noise_mm=a.noise_mm,
            seed=a.seed,
        ),
        methods=MethodSettings(
            methods=tuple(a.method) if a.method else METHODS,
            delta_per_mm=a.delta,
            thesis_instances=a.thesis_instances,
            model_mismatch_mm=a.model_error_mm,
        ),
        meshes=MeshSettings(mesh_dir=a.mesh_dir, units=a.units, with_catalog=a.with_catalog),
        run=RunSettings(
            workers=a.workers, backend=a.backend, ray_address=a.ray_address, results=a.results
        ),
        report=ReportSettings(
            out_dir=a.out_dir,
            json_path=a.json_path,
            tag=a.tag,
            arguments=tuple(sys.argv[1:] if argv is None else argv),
        ),
        sim=SimSettings(
            experiments=tuple(a.experiment) if a.experiment else EXPERIMENTS,
            sessions=a.sessions,
            first_session=a.first_session,
            objects=tuple(a.object) if a.object else None,
            curves=a.sim_curves,
            spacing_mm=a.sim_spacing_mm,
            seed=a.seed,
            model_error_mm=a.model_error_mm,
        ),
        sweep=a.sweep,
    )


def main(argv: list[str] | None = None) -> int:
    """Parse the arguments and run the benchmark; 2 on bad input."""
    config = parse_args(argv)
    return run_cli(lambda: run(config))


if __name__ == "__main__":
    sys.exit(main())
