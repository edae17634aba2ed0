"""Recognition benchmark over the 10-model database or your own meshes (thesis 4.3.4).

python scripts/benchmark.py                               # all three methods
python scripts/benchmark.py --method fast --json out.json
python scripts/benchmark.py --sweep delta                 # Fig. 4.11 (also length, angle)
python scripts/benchmark.py --mesh-dir my_meshes --units mm --with-catalog
python scripts/benchmark.py --backend ray --ray-address auto --workers 8
python scripts/benchmark.py --source sim --json out.json   # simulated robot: Tables 4.5-4.7
python scripts/benchmark.py --source sim --experiment catalog --sessions 1 --method fast
python scripts/benchmark.py --source sim --mesh-dir my_meshes --units mm   # your objects, probed
python scripts/benchmark.py --out-dir docs/benchmarks     # the committed reports (else runs/)
"""

from __future__ import annotations

import sys
from pathlib import Path

from recognition.errors import RecognitionError
from recognition.evaluation import BACKENDS
from recognition.evaluation.ray_backend import check_ray_address
from recognition.surfaces.mesh_files import UNITS
from tactile_sim.cli import ArgumentParser, integer, real, require_writable, run_cli
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
from tactile_sim.probing import MAX_SPACING_M

#: Options of one source only, by source (given with the other, they are an error).
_SOURCE_OPTIONS = {
    "synthetic": "per_model n_points spacing_mm plane_angle noise_mm sweep database_size "
    "per_generated".split(),
    "sim": "experiment sessions first_session object sim_curves sim_spacing_mm "
    "model_error_mm".split(),
}


def _option(dest: str) -> str:
    return "--" + dest.replace("_", "-")


def parse_args(argv: list[str] | None = None) -> BenchmarkConfig:
    """The benchmark's settings from the command line (``argv``: default ``sys.argv``); a
    bad one, an option of the other source, an output path that cannot be written or a
    Ray address where no cluster answers exits 2 here, before any work."""
    defaults = BenchmarkConfig()
    syn, sim = defaults.synthetic, defaults.sim
    p = ArgumentParser(description=(__doc__ or "").splitlines()[0])
    p.add_argument(
        "--method",
        action="append",
        choices=METHODS,
        help="registration mode (repeatable; default all three)",
    )
    p.add_argument("--per-model", type=integer(1), help=f"instances per model ({syn.per_model})")
    p.add_argument("--n-points", type=integer(5), help=f"points per curve ({syn.n_points})")
    p.add_argument(
        "--spacing-mm",
        type=real(0.0, low_open=True),
        help=f"between points ({syn.spacing_mm})",
    )
    p.add_argument(
        "--plane-angle",
        type=real(0.0, 180.0, low_open=True, high_open=True),
        help=f"between sampling planes, degrees ({syn.plane_angle_deg:g})",
    )
    p.add_argument(
        "--noise-mm", type=real(0.0), help=f"Gaussian noise per coordinate ({syn.noise_mm})"
    )
    p.add_argument(
        "--delta",
        type=real(0.0, low_open=True),
        default=defaults.methods.delta_per_mm,
        help="lookup tolerance, 1/mm",
    )
    p.add_argument(
        "--thesis-instances",
        type=integer(0),
        default=defaults.methods.thesis_instances,
        help="instances run in thesis mode (0: all)",
    )
    p.add_argument(
        "--touches",
        type=integer(0),
        default=defaults.methods.touches,
        help="verification touches after the curves, at most (fast mode; default 0)",
    )
    p.add_argument(
        "--workers",
        type=integer(1),
        default=defaults.run.workers,
        help="processes or Ray actors (default: the cores)",
    )
    p.add_argument("--backend", choices=BACKENDS, default="local")
    p.add_argument("--ray-address", help="existing Ray cluster (HOST:PORT of its head, or auto)")
    p.add_argument("--mesh-dir", type=Path)
    p.add_argument("--units", choices=tuple(UNITS), help="of the --mesh-dir meshes (m)")
    p.add_argument(
        "--with-catalog",
        action="store_true",
        help="with --mesh-dir: recognise against the catalog's models as well",
    )
    p.add_argument("--sweep", choices=tuple(SWEEPS))
    p.add_argument("--database-size", type=integer(1), help="models: the catalog, then generated")
    p.add_argument("--per-generated", type=integer(1), help="instances per generated model")
    p.add_argument("--results", type=Path, help="JSONL of per-instance records")
    p.add_argument("--json", type=Path, dest="json_path", help="summary per method")
    p.add_argument(
        "--out-dir",
        type=Path,
        default=defaults.report.out_dir,
        help="reports and figures (default runs/benchmark; docs/benchmarks for the committed)",
    )
    p.add_argument("--tag", default="", help="suffix of the summary file name")
    p.add_argument("--seed", type=integer(0), default=0)
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
    p.add_argument(
        "--sessions", type=integer(1), help=f"with --source sim: seeds per object ({sim.sessions})"
    )
    p.add_argument(
        "--first-session",
        type=integer(0),
        help="with --source sim: index of each object's first session (e.g. 3 with "
        "--sessions 5: sessions 3-7)",
    )
    p.add_argument("--object", action="append", help="with --source sim: probe only these")
    p.add_argument(
        "--sim-curves",
        choices=("sensed", "true_contacts"),
        help="with --source sim: recognise the sensed (default) or the true contact points",
    )
    p.add_argument(
        "--sim-spacing-mm",
        type=real(0.0, MAX_SPACING_M * 1e3, low_open=True, high_open=True),
        help="with --source sim: point spacing instead of the experiment's own",
    )
    p.add_argument(
        "--model-error-mm",
        type=real(0.0, 5.0, high_open=True),
        help="with --source sim: each probed object displaced from its model along the "
        "normals by a smooth random field of this RMS, mm, and the fast mode told so "
        "(default 0)",
    )
    a = p.parse_args(argv)
    for source, options in _SOURCE_OPTIONS.items():
        given = [_option(o) for o in options if getattr(a, o) is not None]
        if a.source != source and given:
            verb = "applies" if len(given) == 1 else "apply"
            p.error(f"{', '.join(given)} {verb} to --source {source} only")
    if a.units is not None and a.mesh_dir is None:
        p.error("--units applies to the meshes of --mesh-dir only")
    if a.mesh_dir is not None and not a.mesh_dir.is_dir():
        p.error(f"--mesh-dir {a.mesh_dir} is not a directory")
    if a.with_catalog and a.mesh_dir is None:
        p.error("--with-catalog applies to --mesh-dir")
    if a.mesh_dir is not None and (a.database_size or a.sweep == "database-size"):
        p.error("--mesh-dir and a database of generated models exclude each other")
    if a.ray_address is not None:
        if a.backend != "ray":
            p.error("--ray-address applies to --backend ray only")
        try:
            check_ray_address(a.ray_address)
        except RecognitionError as exc:
            p.error(f"--ray-address: {exc}")
    if "/" in a.tag or "\\" in a.tag or "\0" in a.tag:
        p.error(f"--tag {a.tag!r}: expected a file-name suffix, without '/'")
    require_writable(p, "--out-dir", a.out_dir, directory=True)
    require_writable(p, "--json", a.json_path)
    require_writable(p, "--results", a.results)

    def given(name: str, default: object) -> object:
        value = getattr(a, name)
        return default if value is None else value

    model_error_mm = given("model_error_mm", sim.model_error_mm)

    return BenchmarkConfig(
        source=a.source,
        synthetic=SyntheticSettings(
            per_model=given("per_model", syn.per_model),
            n_points=given("n_points", syn.n_points),
            spacing_mm=given("spacing_mm", syn.spacing_mm),
            plane_angle_deg=given("plane_angle", syn.plane_angle_deg),
            noise_mm=given("noise_mm", syn.noise_mm),
            seed=a.seed,
            per_generated=given("per_generated", syn.per_generated),
            database_size=a.database_size,
        ),
        methods=MethodSettings(
            methods=tuple(dict.fromkeys(a.method)) if a.method else METHODS,
            delta_per_mm=a.delta,
            thesis_instances=a.thesis_instances,
            model_mismatch_mm=model_error_mm,
            touches=a.touches,
        ),
        meshes=MeshSettings(
            mesh_dir=a.mesh_dir, units=given("units", "m"), with_catalog=a.with_catalog
        ),
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
            experiments=tuple(dict.fromkeys(a.experiment)) if a.experiment else EXPERIMENTS,
            sessions=given("sessions", sim.sessions),
            first_session=given("first_session", sim.first_session),
            objects=tuple(dict.fromkeys(a.object)) if a.object else None,
            curves=given("sim_curves", sim.curves),
            spacing_mm=a.sim_spacing_mm,
            seed=a.seed,
            model_error_mm=model_error_mm,
        ),
        sweep=a.sweep,
    )


def main(argv: list[str] | None = None) -> int:
    """Parse the arguments and run the benchmark; 2 on bad input, 130 on Ctrl-C (the
    records so far are kept: the same command resumes)."""
    config = parse_args(argv)
    return run_cli(lambda: run(config), interrupted="interrupted; rerun the same command to resume")


if __name__ == "__main__":
    sys.exit(main())
