"""Recognition against databases of growing size: the instances, and each database's load
time, memory and build time."""

from __future__ import annotations

import json
import subprocess
import sys
from dataclasses import replace
from pathlib import Path
from typing import Any

from recognition import ModelDatabase, RecognitionError
from recognition.evaluation.instances import InstanceSpec
from recognition.evaluation.synthetic_source import SyntheticSource, instance_specs
from recognition.reproduction.tables import markdown_table
from tactile_sim.objects.catalog import object_names

__all__ = ["database_footprint", "footprint_table", "sized_specs"]


def sized_specs(
    database: ModelDatabase, source: SyntheticSource, per_generated: int
) -> list[InstanceSpec]:
    """``source.per_model`` instances on each catalog model of ``database`` and
    ``per_generated`` on each other model; an instance depends only on its model and
    the seed, so every database size shares its models' instances."""
    catalog = [n for n in database.names if n in object_names()]
    others = [n for n in database.names if n not in catalog]
    specs = instance_specs(ModelDatabase({n: database[n] for n in catalog}), source)
    if others:
        generated = ModelDatabase({n: database[n] for n in others})
        specs += instance_specs(generated, replace(source, per_model=per_generated))
    return specs


#: Source of ``rss_mb()``, the resident memory (MB, Linux) of the interpreter that runs it:
#: for the measurements made in a fresh interpreter.
RSS_MB_SOURCE = """
def rss_mb():
    for line in open("/proc/self/status"):
        if line.startswith("VmRSS:"):
            return int(line.split()[1]) / 1024
"""

# Run in a fresh interpreter: what a worker pays to load the database, and what it holds.
_FOOTPRINT = (
    RSS_MB_SOURCE
    + """
import json, resource, sys, time
from recognition import ModelDatabase
before = rss_mb()
start = time.perf_counter()
db = ModelDatabase.load(sys.argv[1])
load_s = time.perf_counter() - start
parts = {"mesh": 0, "distance field": 0, "candidate map and rings": 0, "lookup table": 0}
for m in db.models.values():
    parts["mesh"] += m.vertices.nbytes + m.faces.nbytes + m.normals.nbytes
    parts["distance field"] += m.distance_field.values.nbytes  # views into the field stack
    c = m.candidate_curvatures
    parts["candidate map and rings"] += c.site.nbytes + c.k1.nbytes + c.k2.nbytes
    parts["candidate map and rings"] += c.d1.nbytes + m.rings.nbytes
    parts["lookup table"] += m.table.site.nbytes + 2 * m.table.k1.nbytes + m.table.d1.nbytes
index = db.candidate_index
arrays = (index.owner, index.row, index.k1, index.k2, index.rings)
parts["candidate index"] = sum(a.nbytes for a in arrays)
timings = [sum(m.timings.values()) for m in db.models.values()]
loaded_mb = rss_mb()
in_use_mb = None
if int(sys.argv[2]):  # then recognise curves on every model: the exact grids it builds
    import numpy as np
    import trimesh
    from recognition import RecognitionError
    from recognition.synthetic import mesh_data_curves
    for i, m in enumerate(db.models.values()):
        rng = np.random.default_rng(i)
        # the curves are cut from a copy of the mesh: the caches that cutting leaves on a
        # mesh (its triangles, about 5 MB a model) are the benchmark's, not the search's
        mesh = trimesh.Trimesh(m.vertices, m.faces, process=False)
        for v in rng.permutation(len(m.vertices))[:20]:  # the first that has curves
            try:
                curves = mesh_data_curves(mesh, int(v), normal=m.normals[v], rng=rng).curves
            except RecognitionError:
                continue
            db.recognize(curves)
            break
    in_use_mb = rss_mb()
print(json.dumps({
    "models": len(db), "load_s": load_s, "rss_mb": loaded_mb, "baseline_rss_mb": before,
    "in_use_rss_mb": in_use_mb, "arrays_mb": {k: v / 2**20 for k, v in parts.items()},
    "build_s_per_model": sum(timings) / len(timings),
}))
"""
)


def database_footprint(directory: Path, repeats: int = 2) -> dict[str, Any]:
    """Load time (s, warm: the best of ``repeats`` loads, each in a fresh interpreter),
    resident memory after the load and before it (MB), resident memory after one
    recognition on each model (MB: the exact-distance grids that polishing builds), the
    arrays by kind (MB) and the mean table build time per model (s, from the manifest)
    of the database in ``directory``."""
    runs = []
    for repeat in range(repeats):
        done = subprocess.run(
            [sys.executable, "-c", _FOOTPRINT, str(directory), str(int(repeat == 0))],
            capture_output=True,
            text=True,
        )
        if done.returncode:
            last = (done.stderr.strip().splitlines() or ["no message"])[-1]
            raise RecognitionError(f"cannot measure the database in {directory}: {last}")
        runs.append(json.loads(done.stdout))
    return {**min(runs, key=lambda r: r["load_s"]), "in_use_rss_mb": runs[0]["in_use_rss_mb"]}


def footprint_table(footprints: dict[int, dict[str, Any]]) -> str:
    """Markdown table of :func:`database_footprint` per database size."""
    kinds = list(next(iter(footprints.values()))["arrays_mb"])
    rows = []
    for size, f in footprints.items():
        arrays = f["arrays_mb"]
        rows.append(
            [
                size,
                f["load_s"],
                f["rss_mb"] - f["baseline_rss_mb"],
                f["rss_mb"],
                f["in_use_rss_mb"],
                *(arrays[k] for k in kinds),
                f["build_s_per_model"],
            ]
        )
    return markdown_table(
        [
            "models",
            "load s (warm)",
            "memory of the load MB",
            "process MB",
            "process MB after a recognition on each model",
            *(f"{k} MB" for k in kinds),
            "table build s per model",
        ],
        rows,
    )
