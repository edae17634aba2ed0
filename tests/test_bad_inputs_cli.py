"""Bad input to every script: exit status 2 and one line on stderr that says what is wrong,
before any database load or probing; Ctrl-C: status 130 and one line.

Each case runs the script's ``main(argv)`` in this process; the interrupt cases run the
script in a process group of its own and send it SIGINT, as a terminal's Ctrl-C does.
"""

from __future__ import annotations

import json
import os
import signal
import socket
import subprocess
import sys
import threading
import time
from collections.abc import Iterator
from pathlib import Path

import pytest
from testing_processes import running
from testing_scripts import SCRIPTS, load_script

from recognition.evaluation import Record

ROOT = SCRIPTS.parent

#: (script, arguments, a fragment of the message). In the arguments, {tmp} is an empty
#: directory, {file} a plain file, {records} a records file with a good first line,
#: {busy} a port something listens on.
CASES = [
    # probe.py
    ("probe", "--seed -1", "argument --seed: expected an integer >= 0, got -1"),
    ("probe", "--seed 1.5", "argument --seed: expected an integer >= 0, got '1.5'"),
    ("probe", "--n-points 4", "argument --n-points: expected an integer >= 5, got 4"),
    ("probe", "--n-points ten", "argument --n-points: expected an integer >= 5, got 'ten'"),
    ("probe", "--n-points 101", "make curves of 120 mm; expected at most 100 mm"),
    ("probe", "--spacing-mm 50", "argument --spacing-mm: expected a finite number in (0, 20)"),
    ("probe", "--spacing-mm nan", "argument --spacing-mm: expected a finite number"),
    ("probe", "--spacing-mm inf", "argument --spacing-mm: expected a finite number"),
    ("probe", "--spacing-mm 0", "argument --spacing-mm: expected a finite number in (0, 20)"),
    ("probe", "--plane-angle 0", "argument --plane-angle: expected a finite number in [5, 85]"),
    ("probe", "--plane-angle 90", "argument --plane-angle: expected a finite number in [5, 85]"),
    ("probe", "--plane-angle nan", "argument --plane-angle: expected a finite number"),
    ("probe", "--model-error-mm -0.1", "argument --model-error-mm: expected a finite number"),
    ("probe", "--model-error-correlation-mm 0", "argument --model-error-correlation-mm"),
    ("probe", "--touches -1", "argument --touches: expected an integer >= 0, got -1"),
    ("probe", "--rerun live", "argument --rerun: invalid choice: 'live'"),
    ("probe", "--rerun serve --web-port 9100 --grpc-port 9100", "must differ, both are 9100"),
    ("probe", "--rerun serve --web-port 70000", "--web-port 70000: expected a port in 1-65535"),
    ("probe", "--rerun serve --grpc-port -5", "--grpc-port -5: expected a port in 1-65535"),
    ("probe", "--rerun serve --web-port {busy}", "in use; pass --web-port"),
    ("probe", "--web-port 9100", "--web-port applies only with --rerun serve"),
    ("probe", "--out {file}", "is a file; expected a directory"),
    ("probe", "--out {file}/runs", "is a file, not a directory"),
    ("probe", "--json {tmp}", "--json {tmp}: {tmp} is a directory; expected a file"),
    ("probe", "--json {file}/summary.json", "--json {file}/summary.json: cannot create"),
    ("probe", "--object unicorn --out {tmp}", "unknown object 'unicorn'; known objects: pear"),
    ("probe", "--mesh {tmp}/missing.ply", "--mesh {tmp}/missing.ply is not a file"),
    ("probe", "--mesh {tmp}", "is not a file"),
    ("probe", "--units furlong", "argument --units: invalid choice: 'furlong'"),
    ("probe", "--database {tmp}", "is not a saved model database (no manifest.json)"),
    # benchmark_curves.py
    ("calibration", "runs/no_such_records.jsonl", "records file runs/no_such_records.jsonl"),
    ("calibration", "{records} --out-dir {tmp}", "{records}, line 2"),
    ("benchmark_curves", "--curves 0", "argument --curves: expected an integer >= 1, got 0"),
    ("benchmark_curves", "--contacts 2", "argument --contacts: expected an integer >= 3, got 2"),
    ("benchmark_curves", "--precision -1", "argument --precision: expected a finite number"),
    ("benchmark_curves", "--out {file}/curves", "--out {file}/curves.json: cannot create"),
    ("benchmark_curves", "--noise 0.01", "--noise, --window and --decide-by need --spacing"),
    ("benchmark_curves", "--spacing 0.05 --window 20", "--window must be odd, got 20"),
    ("benchmark_curves", "--spacing 0", "argument --spacing: expected a finite number"),
    # benchmark_mesh_distance.py
    ("benchmark_mesh_distance", "--queries 0", "argument --queries: expected an integer >= 1"),
    ("benchmark_mesh_distance", "--out-dir {file}", "--out-dir {file}:"),
    # user_meshes.py
    ("user_meshes", "{file}", "is a file; expected a directory"),
    ("user_meshes", "{tmp} --units ft", "argument --units: invalid choice: 'ft'"),
    ("user_meshes", "{tmp} --seed -2", "argument --seed: expected an integer >= 0, got -2"),
    # replay.py
    ("replay", "{tmp}", "is a directory; expected an .rrd recording file"),
    ("replay", "{tmp}/missing.rrd", "the file does not exist"),
    ("replay", "{file}", "is truncated or not an .rrd recording"),
    ("replay", "{file} --web --port 70000", "--web-port 70000: expected a port in 1-65535"),
    ("replay", "{file} --web --port 9200 --grpc-port 9200", "must differ, both are 9200"),
    ("replay", "{file} --web --port {busy}", "in use; pass --web-port"),
    ("replay", "{file} --grpc-port 9200", "--grpc-port applies only with --web"),
    ("replay", "{file} --web --port x", "argument --port/--web-port: invalid int value: 'x'"),
    # benchmark.py
    ("benchmark", "--results {tmp}/empty.jsonl", "empty.jsonl, line 1: keys missing: instance"),
    ("benchmark", "--results {tmp}/list.jsonl", "list.jsonl, line 1: a JSON list, not an object"),
    ("benchmark", "--results {records}", "records.jsonl, line 2: not JSON"),
    ("benchmark", "--results {tmp}/binary.jsonl", "binary.jsonl is not a records file"),
    ("benchmark", "--results {tmp}", "--results {tmp}: {tmp} is a directory; expected a file"),
    ("benchmark", "--per-model 0", "argument --per-model: expected an integer >= 1, got 0"),
    ("benchmark", "--n-points 3", "argument --n-points: expected an integer >= 5, got 3"),
    ("benchmark", "--spacing-mm -1", "argument --spacing-mm: expected a finite number > 0"),
    (
        "benchmark",
        "--plane-angle 180",
        "argument --plane-angle: expected a finite number in (0, 180)",
    ),
    ("benchmark", "--plane-angle 90", "sampling planes 0 and 2 coincide at a plane angle of 90"),
    ("benchmark", "--noise-mm nan", "argument --noise-mm: expected a finite number >= 0"),
    ("benchmark", "--delta 0", "argument --delta: expected a finite number > 0, got '0'"),
    ("benchmark", "--delta inf", "argument --delta: expected a finite number > 0, got 'inf'"),
    ("benchmark", "--thesis-instances -1", "argument --thesis-instances: expected an integer >= 0"),
    ("benchmark", "--workers 0", "argument --workers: expected an integer >= 1, got 0"),
    ("benchmark", "--workers -1", "argument --workers: expected an integer >= 1, got -1"),
    ("benchmark", "--seed -1", "argument --seed: expected an integer >= 0, got -1"),
    ("benchmark", "--method best", "argument --method: invalid choice: 'best'"),
    ("benchmark", "--sweep length --spacing-mm 2", "the length sweep at 6: expected at least 5"),
    ("benchmark", "--sessions 2", "--sessions applies to --source sim only"),
    ("benchmark", "--source sim --per-model 2", "--per-model applies to --source synthetic only"),
    ("benchmark", "--source sim --sessions 0", "argument --sessions: expected an integer >= 1"),
    ("benchmark", "--source sim --first-session -1", "argument --first-session: expected"),
    ("benchmark", "--source sim --sim-spacing-mm 0", "argument --sim-spacing-mm: expected"),
    ("benchmark", "--source sim --sim-spacing-mm 10", "a sweep of 21 points 0.01 m apart"),
    ("benchmark", "--source sim --model-error-mm 5", "argument --model-error-mm: expected"),
    ("benchmark", "--source sim --object unicorn --out-dir {tmp}", "unknown object 'unicorn'"),
    ("benchmark", "--ray-address 127.0.0.1:1", "--ray-address applies to --backend ray only"),
    (
        "benchmark",
        "--backend ray --ray-address 127.0.0.1:1",
        "no Ray cluster at 127.0.0.1:1 (connection refused)",
    ),
    ("benchmark", "--backend ray --ray-address nonsense", "Ray address 'nonsense' is not host"),
    ("benchmark", "--units mm", "--units applies to the meshes of --mesh-dir only"),
    ("benchmark", "--mesh-dir {tmp}/meshes", "--mesh-dir {tmp}/meshes is not a directory"),
    ("benchmark", "--tag a/b", "--tag 'a/b': expected a file-name suffix"),
    ("benchmark", "--out-dir {file}", "--out-dir {file}: {file} is a file; expected a directory"),
    ("benchmark", "--json {tmp}", "--json {tmp}: {tmp} is a directory; expected a file"),
    ("benchmark", "--database-size 0", "argument --database-size: expected an integer >= 1"),
    ("benchmark", "--per-generated 0", "argument --per-generated: expected an integer >= 1"),
    (
        "benchmark",
        "--mesh-dir {tmp} --database-size 20",
        "--mesh-dir and a database of generated models exclude each other",
    ),
    # reproduce_thesis.py
    ("reproduce_thesis", "--workers 0", "argument --workers: expected an integer >= 1, got 0"),
    ("reproduce_thesis", "--workers -1", "argument --workers: expected an integer >= 1, got -1"),
    ("reproduce_thesis", "--seed -1", "argument --seed: expected an integer >= 0, got -1"),
    ("reproduce_thesis", "--curves 0", "argument --curves: expected an integer >= 1, got 0"),
    ("reproduce_thesis", "--table 9.9", "argument --table: invalid choice: '9.9'"),
    ("reproduce_thesis", "--source sim --sim-trials 0", "argument --sim-trials: expected"),
    ("reproduce_thesis", "--sim-trials 5", "--sim-trials applies to --source sim only"),
    ("reproduce_thesis", "--source sim --table 4.2", "--source sim applies to table 3.4, 3.5"),
    ("reproduce_thesis", "--json {tmp}", "--json {tmp}: {tmp} is a directory; expected a file"),
    ("reproduce_thesis", "--json {file}/t.json", "--json {file}/t.json: cannot create"),
    ("reproduce_thesis", "--figures {file}", "--figures {file}: {file} is a file"),
    # render_objects.py
    ("render_objects", "--faces 5", "argument --faces: expected an integer >= 100, got 5"),
    ("render_objects", "--out {file}", "--out {file}: {file} is a file; expected a directory"),
    ("render_objects", "--objects cat unicorn --out {tmp}", "unknown object 'unicorn'"),
]


@pytest.fixture
def busy_port() -> Iterator[int]:
    """A port something listens on."""
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        s.listen()
        yield s.getsockname()[1]


def _paths(tmp: Path) -> dict[str, str]:
    """The {tmp}, {file} and {records} of :data:`CASES`, made under ``tmp``."""
    tmp.mkdir()
    file = tmp.parent / "notes.txt"
    file.write_text("not a recording, not a directory\n")
    (tmp / "empty.jsonl").write_text("{}\n")
    (tmp / "list.jsonl").write_text("[1, 2]\n")
    (tmp / "binary.jsonl").write_bytes(b"\xff\xfe\x00\n")
    record = Record("cat/0", "cat", 0, None, 1, {}, 0.1, "fast", "cat", True, 0.2)
    records = tmp.parent / "records.jsonl"
    records.write_text(json.dumps(record.to_json()) + "\n{'instance': 'cat/1'}\n")
    return {"tmp": str(tmp), "file": str(file), "records": str(records)}


@pytest.mark.parametrize(
    ("script", "arguments", "fragment"),
    CASES,
    ids=[f"{script}: {arguments}" for script, arguments, _ in CASES],
)
def test_bad_input_exits_2_with_one_line_naming_it(
    script: str,
    arguments: str,
    fragment: str,
    tmp_path: Path,
    busy_port: int,
    capsys: pytest.CaptureFixture[str],
) -> None:
    names = _paths(tmp_path / "case") | {"busy": str(busy_port)}
    argv = [a.format(**names) for a in arguments.split()]
    try:
        status = load_script(script).main(argv)
    except SystemExit as exit_:
        status = exit_.code
    captured = capsys.readouterr()
    assert status == 2
    assert "Traceback" not in captured.err
    assert captured.err.count("\n") == 1 and captured.err.endswith("\n"), captured.err
    assert fragment.format(**names) in captured.err


def test_the_catalogue_covers_every_script() -> None:
    scripts = {path.stem for path in SCRIPTS.glob("*.py")}
    assert {script for script, _, _ in CASES} == scripts
    assert len(CASES) >= 30


def _processes_with_parent(pid: int) -> list[int]:
    """Processes whose parent is ``pid`` (Linux /proc)."""
    children = []
    for stat in Path("/proc").glob("[0-9]*/stat"):
        try:
            fields = stat.read_text().rpartition(")")[2].split()
        except OSError:
            continue
        if int(fields[1]) == pid:
            children.append(int(stat.parent.name))
    return children


def _interrupt(argv: list[str], *, until: str | None = None, children: int = 0) -> tuple[int, str]:
    """Runs a script in a process group of its own; once ``until`` is on its stderr and it
    has ``children`` child processes, sends the group SIGINT (a terminal's Ctrl-C).
    Returns the exit status and stderr; checks that no child outlives the script."""

    def restore_sigint() -> None:  # a background shell may have started us ignoring it
        signal.signal(signal.SIGINT, signal.SIG_DFL)

    path = os.pathsep.join(filter(None, [str(ROOT), os.environ.get("PYTHONPATH")]))
    process = subprocess.Popen(
        [sys.executable, *argv],
        cwd=ROOT,
        env={**os.environ, "PYTHONPATH": path, "PYTHONFAULTHANDLER": "1"},
        stdout=subprocess.DEVNULL,
        stderr=subprocess.PIPE,
        start_new_session=True,
        preexec_fn=restore_sigint,
    )
    err = bytearray()

    def read_stderr() -> None:
        while chunk := process.stderr.read1(4096):
            err.extend(chunk)

    reader = threading.Thread(target=read_stderr, daemon=True)
    reader.start()
    try:
        deadline = time.monotonic() + 60.0
        while not (
            (until is None or until.encode() in err)
            and len(_processes_with_parent(process.pid)) >= children
        ):
            assert process.poll() is None, err.decode()
            assert time.monotonic() < deadline, err.decode()
            time.sleep(0.05)
        workers = _processes_with_parent(process.pid)
        os.killpg(process.pid, signal.SIGINT)
        try:
            status = process.wait(timeout=20)
        except subprocess.TimeoutExpired:
            os.kill(process.pid, signal.SIGABRT)  # faulthandler shows where it hangs
            process.wait(timeout=10)
            reader.join(timeout=5)
            raise AssertionError(f"no exit 20 s after SIGINT:\n{err.decode()}") from None
        reader.join(timeout=5)
        assert not [w for w in workers if running(w)], "a worker outlived the script"
    finally:
        if process.poll() is None:
            os.killpg(process.pid, signal.SIGKILL)
            process.wait()
    return status, err.decode()


def _one_line(err: str) -> str:
    """The only line of ``err`` as a terminal shows it (a progress bar redrawn with
    carriage returns and then cleared shares it)."""
    assert "Traceback" not in err
    assert err.count("\n") == 1 and err.endswith("\n"), err
    return err[:-1].split("\r")[-1]


@pytest.mark.parametrize("workers", ["1", "2"], ids=["in-process", "process-pool"])
def test_an_interrupted_benchmark_says_how_to_resume_and_exits_130(
    workers: str, tmp_path: Path
) -> None:
    argv = [str(SCRIPTS / "benchmark.py"), "--source", "sim", "--experiment", "solids"]
    argv += ["--sessions", "1", "--workers", workers, "--out-dir", str(tmp_path)]
    argv += ["--results", str(tmp_path / "records.jsonl")]
    # the progress bar is up: the jobs have started (in the process pool's workers)
    status, err = _interrupt(argv, until="benchmark:", children=0 if workers == "1" else 2)
    assert status == 130
    assert _one_line(err) == "interrupted; rerun the same command to resume"


def test_an_interrupted_reproduction_exits_130_without_worker_tracebacks() -> None:
    argv = [str(SCRIPTS / "reproduce_thesis.py"), "--table", "3.3", "--curves", "500"]
    status, err = _interrupt([*argv, "--workers", "2"], children=2)
    assert status == 130
    assert _one_line(err) == "interrupted"
