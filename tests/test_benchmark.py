"""The benchmark runner: resuming after a kill, the process pool and Ray give the same
records as a serial run, typed records read back as written, simulated instances, and
the benchmark runs' outputs and bad-input exits."""

import dataclasses
import json
import os
import signal
import subprocess
import sys
import time
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest
from testing_meshes import blob, ellipsoid
from testing_scripts import load_script

from recognition import evaluation as bench
from recognition.surfaces.database import ModelDatabase
from recognition.surfaces.registration import ClosedFormConfig, FastConfig
from tactile_sim.cli import run_cli
from tactile_sim.evaluation import SWEEPS, BenchmarkConfig, run
from tactile_sim.evaluation.benchmark import plan_jobs

ROOT = Path(__file__).resolve().parents[1]
SOURCE = bench.SyntheticSource(per_model=4, n_points=21, spacing_m=1.2e-3, separation_m=5e-3)


@pytest.fixture(scope="module")
def database_dir(tmp_path_factory: pytest.TempPathFactory) -> Path:
    database = ModelDatabase.from_meshes(
        {"blob": blob(subdivisions=4), "ellipsoid": ellipsoid(subdivisions=4)}, progress=False
    )
    return database.save(tmp_path_factory.mktemp("benchmark") / "database")


@pytest.fixture(scope="module")
def jobs(database_dir: Path) -> list[bench.Job]:
    specs = SOURCE.specs(ModelDatabase.load(database_dir))
    assert len(specs) == 8
    return [bench.Job(spec, SOURCE, (FastConfig(),)) for spec in specs]


@pytest.fixture(scope="module")
def uninterrupted(
    database_dir: Path, jobs: list[bench.Job], tmp_path_factory: pytest.TempPathFactory
) -> list[bench.Record]:
    path = tmp_path_factory.mktemp("uninterrupted") / "records.jsonl"
    return bench.run(database_dir, jobs, path, progress=False)


def _comparable(records: list[bench.Record]) -> list[dict[str, Any]]:
    return sorted(
        (bench.comparable(r) for r in records), key=lambda r: (r["instance"], r["method"])
    )


def test_a_run_writes_one_record_per_instance_and_method(
    uninterrupted: list[bench.Record], jobs: list[bench.Job]
) -> None:
    assert len(uninterrupted) == len(jobs)
    assert {r.instance for r in uninterrupted} == {j.spec.key for j in jobs}
    settings = {r.settings for r in uninterrupted}
    assert settings == {bench.settings_key(SOURCE, FastConfig())}
    summary = bench.summarize(uninterrupted)["fast"].to_json()
    assert set(summary) >= {
        "success_rate",
        "median_time_s",
        "p90_time_s",
        "median_localization_error_mm",
        "instances",
        "method",
    }
    assert summary["instances"] == len(jobs)


def test_interrupted_run_resumes_without_redoing_finished_instances(
    database_dir: Path, jobs: list[bench.Job], uninterrupted: list[bench.Record], tmp_path: Path
) -> None:
    path = tmp_path / "records.jsonl"
    first: list[dict] = []

    def stop_after_three(record: bench.Record) -> None:
        first.append(record)
        if len(first) == 3:
            raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):
        bench.run(database_dir, jobs, path, progress=False, on_record=stop_after_three)
    assert len(bench.read_results(path)) == 3
    again: list[dict] = []
    records = bench.run(database_dir, jobs, path, progress=False, on_record=again.append)
    assert len(again) == len(jobs) - 3
    assert not {r.instance for r in again} & {r.instance for r in first}
    assert _comparable(records) == _comparable(uninterrupted)


def test_truncated_last_line_is_ignored_and_its_instance_redone(
    database_dir: Path, jobs: list[bench.Job], uninterrupted: list[bench.Record], tmp_path: Path
) -> None:
    path = tmp_path / "records.jsonl"
    lines = [r.dumps() for r in uninterrupted[:2]]
    path.write_text("\n".join(lines) + "\n" + lines[0][: len(lines[0]) // 2])
    again: list[dict] = []
    records = bench.run(database_dir, jobs, path, progress=False, on_record=again.append)
    assert len(again) == len(jobs) - 2
    assert _comparable(records) == _comparable(uninterrupted)


def test_other_settings_are_not_taken_for_done(
    database_dir: Path, jobs: list[bench.Job], uninterrupted: list[bench.Record], tmp_path: Path
) -> None:
    path = tmp_path / "records.jsonl"
    path.write_text("".join(r.dumps() + "\n" for r in uninterrupted))
    other = [bench.Job(j.spec, j.source, (FastConfig(delta=20.0),)) for j in jobs[:2]]
    again: list[dict] = []
    bench.run(database_dir, other, path, progress=False, on_record=again.append)
    assert len(again) == 2


_KILLED_RUN = """
import sys
from pathlib import Path
from recognition import evaluation as bench
from recognition.surfaces.database import ModelDatabase
from recognition.surfaces.registration import FastConfig
source = bench.SyntheticSource(per_model=4, n_points=21, spacing_m=1.2e-3, separation_m=5e-3)
database = Path(sys.argv[1])
specs = source.specs(ModelDatabase.load(database))
jobs = [bench.Job(s, source, (FastConfig(),)) for s in specs]
slow = lambda record: __import__("time").sleep(0.5)
bench.run(database, jobs, Path(sys.argv[2]), progress=False, on_record=slow)
"""


@pytest.mark.slow
def test_benchmark_killed_halfway_finishes_without_redoing(
    database_dir: Path, jobs: list[bench.Job], uninterrupted: list[bench.Record], tmp_path: Path
) -> None:
    path = tmp_path / "records.jsonl"
    process = subprocess.Popen(
        [sys.executable, "-c", _KILLED_RUN, str(database_dir), str(path)], cwd=ROOT
    )
    try:
        deadline = time.monotonic() + 120
        while len(bench.read_results(path)) < 3:
            assert process.poll() is None, "the benchmark ended before it was killed"
            assert time.monotonic() < deadline
            time.sleep(0.05)
        os.kill(process.pid, signal.SIGKILL)
    finally:
        process.kill()
        process.wait()
    done = {r.instance for r in bench.read_results(path)}
    assert 3 <= len(done) < len(jobs)
    again: list[dict] = []
    records = bench.run(database_dir, jobs, path, progress=False, on_record=again.append)
    assert {r.instance for r in again} == {j.spec.key for j in jobs} - done
    assert _comparable(records) == _comparable(uninterrupted)


@pytest.mark.slow
def test_process_pool_gives_the_same_records(
    database_dir: Path, jobs: list[bench.Job], uninterrupted: list[bench.Record], tmp_path: Path
) -> None:
    records = bench.run(database_dir, jobs, tmp_path / "records.jsonl", workers=2, progress=False)
    assert _comparable(records) == _comparable(uninterrupted)


@pytest.fixture(scope="module")
def ray_cluster() -> Iterator[str]:
    """A local Ray cluster of 2 CPUs on 127.0.0.1, its GCS address."""
    # Ray binds to the loopback address only when told that it cannot form a cluster
    # (read when ray is imported).
    names = ("RAY_ENABLE_WINDOWS_OR_OSX_CLUSTER", "RAY_USAGE_STATS_ENABLED")
    saved = {k: os.environ.get(k) for k in names}
    os.environ.update(dict.fromkeys(names, "0"))
    ray = pytest.importorskip("ray")
    try:
        ray.init(num_cpus=2, include_dashboard=False, log_to_driver=False)
        address = ray.get_runtime_context().gcs_address
        assert address.startswith("127.0.0.1:")
        yield address
    finally:
        ray.shutdown()
        for k, v in saved.items():
            if v is None:
                os.environ.pop(k, None)
            else:
                os.environ[k] = v


@pytest.mark.slow
def test_ray_backend_gives_the_same_records_as_local(
    ray_cluster: str,
    database_dir: Path,
    jobs: list[bench.Job],
    uninterrupted: list[bench.Record],
    tmp_path: Path,
) -> None:
    records = bench.run(
        database_dir, jobs, tmp_path / "ray.jsonl", workers=2, backend="ray", progress=False
    )
    assert _comparable(records) == _comparable(uninterrupted)


_RAY_DRIVER = """
import sys
from pathlib import Path
from recognition import evaluation as bench
from recognition.surfaces.database import ModelDatabase
from recognition.surfaces.registration import FastConfig
source = bench.SyntheticSource(per_model=4, n_points=21, spacing_m=1.2e-3, separation_m=5e-3)
database = Path(sys.argv[1])
specs = source.specs(ModelDatabase.load(database))
jobs = [bench.Job(s, source, (FastConfig(),)) for s in specs]
bench.run(database, jobs, Path(sys.argv[2]), workers=2, backend="ray",
          ray_address=sys.argv[3], progress=False)
"""


@pytest.mark.slow
def test_ray_address_connects_to_an_existing_cluster(
    ray_cluster: str, database_dir: Path, uninterrupted: list[bench.Record], tmp_path: Path
) -> None:
    path = tmp_path / "driver.jsonl"
    subprocess.run(
        [sys.executable, "-c", _RAY_DRIVER, str(database_dir), str(path), ray_cluster],
        cwd=ROOT,
        check=True,
        timeout=300,
    )
    assert _comparable(bench.read_results(path)) == _comparable(uninterrupted)


@pytest.mark.slow
def test_simulated_instances_are_reproducible_and_recorded(tmp_path: Path) -> None:
    from tactile_sim.evaluation import solids_experiment

    source = solids_experiment(objects=("sphere",), sessions_per_object=2, n_points=11)
    specs = source.specs(None)
    assert [s.key for s in specs] == ["sphere/0", "sphere/1"]
    assert specs[0].seed != specs[1].seed
    models = bench.ClosedFormModels()
    registration = ClosedFormConfig(delta=float("inf"), max_candidates=4)
    jobs = [bench.Job(s, source, (registration,)) for s in specs]
    records = bench.run(models, jobs, tmp_path / "sim.jsonl", progress=False)
    assert len(records) == 2
    for r in records:
        assert r.info["points_per_curve"] == [11, 11, 11]
        assert set(r.errors_mm) == set(models.names)
        assert r.reference is not None
        assert r.reference.errors_mm.keys() == r.errors_mm.keys()
        assert 0 <= r.info["sensed_error_mean_mm"] < 0.1
    again = bench.run_job(models.load(), jobs[0])[0]
    assert bench.comparable(again) == {
        k: v for k, v in bench.comparable(records[0]).items() if k != "settings"
    }


def test_records_read_back_as_written(uninterrupted: list[bench.Record], tmp_path: Path) -> None:
    path = tmp_path / "records.jsonl"
    path.write_text("".join(r.dumps() + "\n" for r in uninterrupted))
    again = bench.read_results(path)
    assert again == uninterrupted
    assert [r.dumps() for r in again] == path.read_text().splitlines()
    first = json.loads(path.read_text().splitlines()[0])
    assert list(first)[:5] == ["instance", "model", "index", "vertex", "seed"]
    last = ["localization_error_mm", "confidence", "answer_error_mm"]
    last += ["truth_fit"] if "truth_fit" in first else []  # a wrong answer's diagnosis
    assert list(first)[-len(last) - 1 :] == [*last, "settings"]


def test_instance_facts_and_errors_are_kept_apart() -> None:
    failed = bench.Record(
        "cat/0",
        "cat",
        0,
        None,
        7,
        {"error": "SweepTruncated: too few"},
        0.5,
        "fast",
        None,
        False,
        0.0,
    )
    payload = failed.to_json()
    assert list(payload) == [
        "instance",
        "model",
        "index",
        "vertex",
        "seed",
        "error",
        "instance_time_s",
        "method",
        "recognized",
        "success",
        "time_s",
        "errors_mm",
        "times_s",
        "localization_error_mm",
    ]
    again = bench.Record.from_json(payload)
    assert again == failed and again.error is None
    assert again.instance_error == "SweepTruncated: too few"
    unrecognised = dataclasses.replace(failed, info={"probe_time_s": 1.0}, error="Degenerate")
    again = bench.Record.from_json(unrecognised.to_json())
    assert again.info == {"probe_time_s": 1.0} and again.error == "Degenerate"


_IMPORTS = """
import sys
import recognition, recognition.evaluation, recognition.evaluation.reports
import recognition.evaluation.figures, recognition.evaluation.ray_backend
heavy = ("ray", "matplotlib", "mujoco", "tactile_sim", "tqdm", "numba", "scipy.stats")
print(" ".join(sorted(m for m in heavy if m in sys.modules)))
"""


def test_importing_the_evaluation_layer_pulls_in_neither_ray_nor_matplotlib_nor_mujoco() -> None:
    # nor numba (loaded at the first distance-field lookup) nor scipy.stats (0.3 s)
    done = subprocess.run(
        [sys.executable, "-c", _IMPORTS], capture_output=True, text=True, check=True, cwd=ROOT
    )
    assert done.stdout.strip() == ""


def _replace(config: BenchmarkConfig, **parts: dict[str, Any]) -> BenchmarkConfig:
    """``config`` with fields of its parts replaced: ``run={"workers": 1}``."""
    return dataclasses.replace(
        config,
        **{k: dataclasses.replace(getattr(config, k), **v) for k, v in parts.items()},
    )


def test_script_reports_an_unknown_object_and_exits_2(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    script = load_script("benchmark")
    assert script.main(["--source", "sim", "--object", "unicorn", "--out-dir", str(tmp_path)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1
    assert "unknown object 'unicorn'" in err and "cat" in err


def test_script_parses_the_sim_options() -> None:
    config = load_script("benchmark").parse_args(
        ["--source", "sim", "--experiment", "solids", "--sessions", "2", "--tag", "_x"]
    )
    assert config.source == "sim"
    assert config.sim.experiments == ("solids",)
    assert config.sim.sessions == 2
    assert config.report.tag == "_x"


def test_reports_go_to_runs_unless_told_otherwise() -> None:
    script = load_script("benchmark")
    assert script.parse_args([]).report.out_dir == ROOT / "runs" / "benchmark"
    config = script.parse_args(["--out-dir", "docs/benchmarks"])
    assert config.report.out_dir == Path("docs/benchmarks")


@pytest.mark.slow
def test_sensing_experiment_measures_points_and_wall_times(tmp_path: Path) -> None:
    config = load_script("benchmark").parse_args(
        ["--source", "sim", "--experiment", "sensing", "--sessions", "1", "--object", "bird"]
    )
    config = _replace(config, report={"out_dir": tmp_path, "json_path": tmp_path / "sensing.json"})
    figures = run(config)["sensing"]
    assert figures["n_points"] == 63
    assert figures["objects"]["bird"]["n_points"] == 63
    # The tip touches the mesh itself (geometry error below a micrometre); the sensed
    # points lie within the sensor's error of it (micrometres).
    assert 0 <= figures["geometry_max_mm"] < 0.001
    assert 0 < figures["sensor_mean_mm"] < 0.01
    assert figures["total_mean_mm"] <= figures["sensor_mean_mm"] + figures["geometry_mean_mm"]
    warm = figures["probe_script_warm_s"]
    assert len(warm) == 3
    for run_ in warm:
        parts = sum(run_[k] for k in ("startup", "object", "database", "probing", "recognition"))
        assert 0 < parts <= run_["wall"]
    assert all(t > 0 for t in figures["session_total_s"])
    report = (tmp_path / "sim_sensing.md").read_text()
    assert "| bird | 63 |" in report and "geometry mean" in report
    assert json.loads((tmp_path / "sensing.json").read_text())["sensing"]["n_points"] == 63


def _write_user_meshes(directory: Path) -> None:
    """Two meshes in millimetres, in two of the accepted formats."""
    directory.mkdir()
    blob(subdivisions=4).apply_scale(1e3).export(directory / "blob.stl")
    ellipsoid(subdivisions=4).apply_scale(1e3).export(directory / "egg.ply")


def _mesh_config(tmp_path: Path, argv: list[str]) -> BenchmarkConfig:
    """The benchmark's config of ``argv`` with its caches and records under ``tmp_path``."""
    config = load_script("benchmark").parse_args(argv)
    return _replace(
        config,
        meshes={"cache_dir": tmp_path / "runs" / "mesh_databases"},
        run={"records_dir": tmp_path / "runs" / "benchmark"},
    )


def test_user_meshes_in_millimetres_are_benchmarked(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    _write_user_meshes(tmp_path / "meshes")
    argv = ["--mesh-dir", str(tmp_path / "meshes"), "--units", "mm", "--per-model", "2"]
    argv += ["--n-points", "21", "--spacing-mm", "1.2", "--method", "fast", "--workers", "1"]
    argv += ["--out-dir", str(tmp_path / "out"), "--json", str(tmp_path / "summary.json")]
    config = _mesh_config(tmp_path, argv)
    assert run_cli(lambda: run(config)) == 0
    summary = json.loads((tmp_path / "summary.json").read_text())["fast"]
    assert summary["instances"] == 4
    assert summary["success_rate"] == 1.0
    records = [json.loads(line) for f in (tmp_path / "runs").rglob("*.jsonl") for line in open(f)]
    # the egg is a symmetric ellipsoid: its curves fit equally well at mirrored places
    assert all(r["localization_error_mm"] < 1.0 for r in records if r["model"] == "blob")
    report = (tmp_path / "out" / "meshes.md").read_text()
    assert "| blob |" in report and "| egg |" in report
    assert report.startswith("# Recognition benchmark: meshes\n\nCommand: `python scripts/")
    assert "--units mm --per-model 2" in report
    # the database is cached: a second run loads it instead of building it again
    assert "building a database of 2 meshes" in capsys.readouterr().out
    assert len([p for p in (tmp_path / "runs" / "mesh_databases").iterdir() if p.is_dir()]) == 1
    assert run_cli(lambda: run(config)) == 0
    assert "building a database" not in capsys.readouterr().out


def test_an_edited_mesh_or_another_folder_of_the_same_name_never_reuses_records(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    first, second = tmp_path / "a" / "meshes", tmp_path / "b" / "meshes"
    first.parent.mkdir()
    second.parent.mkdir()
    _write_user_meshes(first)
    _write_user_meshes(second)
    blob(subdivisions=4).apply_scale(1.1e3).export(second / "blob.stl")  # the same name
    argv = ["--units", "mm", "--per-model", "1", "--method", "fast", "--workers", "1"]
    argv += ["--out-dir", str(tmp_path / "out")]

    def run_on(folder: Path) -> tuple[str, list[dict]]:
        assert run_cli(lambda: run(_mesh_config(tmp_path, ["--mesh-dir", str(folder), *argv]))) == 0
        files = sorted((tmp_path / "runs" / "benchmark").rglob("*.jsonl"))
        return capsys.readouterr().out, files

    out, files = run_on(first)
    assert "building a database of 2 meshes" in out and len(files) == 1
    out, files = run_on(second)
    assert "building a database of 2 meshes" in out and len(files) == 2  # its own records
    ellipsoid(subdivisions=4).apply_scale(0.9e3).export(first / "egg.ply")  # edited in place
    out, files = run_on(first)
    assert "building a database of 2 meshes" in out and len(files) == 3
    out, files = run_on(first)
    assert "building a database" not in out and len(files) == 3  # unchanged: reused


def test_millimetre_meshes_read_as_metres_are_named(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    _write_user_meshes(tmp_path / "meshes")
    config = _mesh_config(tmp_path, ["--mesh-dir", str(tmp_path / "meshes"), "--method", "fast"])
    assert run_cli(lambda: run(config)) == 2
    last = capsys.readouterr().err.splitlines()[-1]  # after the progress bar
    assert last.startswith("error: blob") and "millimetres read as metres" in last
    assert "--units mm" in last


def test_a_sweep_writes_one_point_per_value_with_its_figure(tmp_path: Path) -> None:
    _write_user_meshes(tmp_path / "meshes")
    out = tmp_path / "out"
    argv = ["--mesh-dir", str(tmp_path / "meshes"), "--units", "mm", "--per-model", "2"]
    argv += ["--sweep", "length", "--workers", "1", "--out-dir", str(out)]
    assert run_cli(lambda: run(_mesh_config(tmp_path, argv))) == 0
    payload = json.loads((out / "sweep_length.json").read_text())
    assert payload["figure"] == "Fig. 4.12"
    assert [p["value"] for p in payload["points"]] == list(SWEEPS["length"].values)
    assert all(p["instances"] == 4 for p in payload["points"])
    # 30 mm curves tell the blob from the egg
    assert payload["points"][-1]["success_rate"] == 1.0
    assert (out / "sweep_length.png").stat().st_size > 10_000
    assert "![Fig. 4.12](sweep_length.png)" in (out / "sweep_length.md").read_text()


@pytest.mark.slow
def test_the_database_size_sweep_reports_success_time_and_footprint(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """Two sizes (the catalog, and it with two generated models): the same catalog
    instances at both, one on each generated model, each size's load time and memory."""
    sizes = dataclasses.replace(SWEEPS["database-size"], values=(10.0, 12.0))
    monkeypatch.setitem(SWEEPS, "database-size", sizes)
    out = tmp_path / "out"
    argv = ["--sweep", "database-size", "--per-model", "1", "--per-generated", "1"]
    argv += ["--n-points", "21", "--spacing-mm", "1.2", "--workers", "1", "--out-dir", str(out)]
    assert run_cli(lambda: run(_mesh_config(tmp_path, argv))) == 0
    payload = json.loads((out / "sweep_database_size.json").read_text())
    assert [p["value"] for p in payload["points"]] == [10.0, 12.0]
    assert [p["instances"] for p in payload["points"]] == [10, 12]
    for point in payload["points"]:
        footprint = point["footprint"]
        assert footprint["models"] == point["value"]
        assert footprint["load_s"] > 0 and footprint["rss_mb"] > footprint["baseline_rss_mb"]
        assert footprint["in_use_rss_mb"] > footprint["rss_mb"]
        assert footprint["arrays_mb"]["distance field"] > 0
    report = (out / "sweep_database_size.md").read_text()
    assert "## Load time, memory and build time" in report
    assert "| 12 |" in report


def test_curves_without_local_geometry_are_a_failed_record(
    database_dir: Path, jobs: list[bench.Job], monkeypatch: pytest.MonkeyPatch
) -> None:
    from recognition.errors import DegenerateGeometry

    database = ModelDatabase.load(database_dir)

    def degenerate(*args: Any, **kwargs: Any) -> None:
        raise DegenerateGeometry("two data curves have the same tangent direction at p")

    monkeypatch.setattr(database, "recognize", degenerate)
    (record,) = bench.run_job(database, jobs[0])
    assert record.success is False and record.recognized is None
    assert record.error is not None
    assert record.error.startswith("DegenerateGeometry: two data curves")
    summary = bench.summarize([record])["fast"]
    assert summary.instances == 1 and summary.success_rate == 0.0


def test_sampling_planes_that_coincide_are_refused_before_any_instance(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    script = load_script("benchmark")
    argv = ["--plane-angle", "90", "--method", "fast", "--out-dir", str(tmp_path)]
    assert script.main(argv) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "sampling planes 0 and 2 coincide" in err


def test_touching_jobs_record_their_touches_under_their_own_settings(
    database_dir: Path, jobs: list[bench.Job], tmp_path: Path
) -> None:
    touching = [bench.Job(j.spec, j.source, j.configs, touches=2) for j in jobs[:4]]
    path = tmp_path / "records.jsonl"
    records = bench.run(database_dir, touching, path, progress=False)
    assert len(records) == 4
    assert {r.settings for r in records}.isdisjoint({j.settings(FastConfig()) for j in jobs})
    for record in records:
        assert record.confidence is not None and 0.0 <= record.confidence <= 1.0
        touches = record.touches
        assert touches is not None and 0 <= touches["made"] <= 2
        assert len(touches["recognition_times_s"]) == touches["made"]
        # a sure answer after the curves makes no touch
        if record.confidence >= 0.99:
            assert touches["made"] == 0 and touches["stop"] == "sure"
        # a wrong answer carries its diagnosis, a right one none
        for right, fit in (
            (record.answered_right(), record.truth_fit),
            (record.answered_right(True), touches.get("truth_fit")),
        ):
            assert (fit is None) == right, (right, fit)
    # resumed, not redone: the same records read back
    assert bench.run(database_dir, touching, path, progress=False) == records


def test_a_results_file_shared_by_two_databases_resumes_each_ones_records_only(
    database_dir: Path, jobs: list[bench.Job], tmp_path: Path
) -> None:
    """A database-size sweep given one --results file runs every size into it: a record
    made against one database must not count as done against another."""
    path = tmp_path / "records.jsonl"
    first = [dataclasses.replace(j, models="size-10") for j in jobs[:2]]
    other = [dataclasses.replace(j, models="size-100") for j in jobs[:2]]
    made = bench.run(database_dir, first, path, progress=False)
    assert len(made) == 2
    both = bench.run(database_dir, other, path, progress=False)
    assert len(both) == 4
    settings = [{j.settings(FastConfig()) for j in js} for js in (first, other)]
    assert settings[0].isdisjoint(settings[1])
    assert {r.settings for r in made} == settings[0]
    assert {r.settings for r in both} == settings[0] | settings[1]
    # the benchmark keys its jobs by the database folder it loads
    planned = plan_jobs(
        [j.spec for j in jobs[:1]], SOURCE, {"fast": FastConfig()}, 0, 0, database_dir
    )
    assert planned[0].models == database_dir.name
