"""A database of mesh models and recognition by registration (thesis Sections 4.1.3, 4.3)."""

from __future__ import annotations

import json
import os
import tempfile
import time
from collections.abc import Callable, Mapping
from concurrent.futures import ThreadPoolExecutor
from dataclasses import asdict, dataclass, field
from pathlib import Path

import numpy as np
import trimesh

from recognition.errors import InvalidModel
from recognition.surfaces.data_curves import DataCurves
from recognition.surfaces.distance import DistanceField, FieldStack
from recognition.surfaces.local_geometry import LocalSurfaceGeometry
from recognition.surfaces.mesh_model import CurvatureTable, MeshModel, MeshModelConfig
from recognition.surfaces.registration import (
    Registration,
    RegistrationConfig,
    RegistrationMode,
    data_geometry,
    register,
    register_fast,
    registration_mode,
)

__all__ = ["DATABASE_FORMAT", "ModelDatabase", "Recognition"]

#: Version of the on-disk format; a different version is rebuilt, never read.
DATABASE_FORMAT = 4
#: Thesis and ICP modes: models whose registration error is computed exactly (the best
#: by their own error); the fast mode decides which models to polish itself.
EXACT_TOP = 3
#: Default largest registration error (metres) of a recognised model: data that fit no
#: model better than this are not recognised (name None).
MAX_ERROR_M = 0.5e-3


@dataclass(frozen=True)
class Recognition:
    """Result of recognising data curves against a database (thesis Eq. (4.9)).

    Attributes
    ----------
    name : str or None
        Best model, or None when every model was rejected or fits worse than
        ``max_error_m``.
    ranking : list of (str, float)
        (model, registration error in metres), ascending; rejected models: inf.
    pose : (4, 4) float
        T_model_from_data of the best model (NaN when ``name`` is None).
    location : (3,) float
        The curves' common point p on the best model, model frame.
    margin_m : float
        Second-best error minus best error, metres (inf if only one model fits).
    registrations : dict of str to Registration
    timings_s : dict of str to float
        Registration time per model (fast mode: each model's share of the batched
        search, in proportion to the point evaluations made for it).
    time_s : float
        Total time, local geometry included.
    geometry : LocalSurfaceGeometry
        The data's normal and principal curvatures at p.
    """

    name: str | None
    ranking: list[tuple[str, float]]
    pose: np.ndarray
    location: np.ndarray
    margin_m: float
    registrations: dict[str, Registration]
    timings_s: dict[str, float]
    time_s: float
    geometry: LocalSurfaceGeometry = field(repr=False)

    @property
    def best(self) -> Registration | None:
        """The best model's registration (even when it fits worse than the threshold)."""
        return self.registrations.get(self.ranking[0][0]) if self.ranking else None


def _write_atomic(path: Path, writer: Callable) -> None:
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=path.name, suffix=".tmp")
    try:
        with os.fdopen(fd, "wb") as f:
            writer(f)
        os.replace(tmp, path)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise


class ModelDatabase:
    """Mesh models with their curvature tables; recognises data curves (4.9).

    Parameters
    ----------
    models : mapping of str to MeshModel
    registration : RegistrationConfig
    mode : {"fast", "thesis", "icp-baseline"}
        Default registration mode of :meth:`recognize`.
    threads : int
        Thesis and ICP modes: models registered concurrently by :meth:`recognize` (numpy
        releases the GIL in the heavy array work); results do not depend on it. The fast
        mode searches all models in one batch.
    """

    def __init__(
        self,
        models: Mapping[str, MeshModel],
        registration: RegistrationConfig = RegistrationConfig(),
        mode: RegistrationMode | str = RegistrationMode.FAST,
        threads: int = 1,
    ):
        if not models:
            raise InvalidModel("a model database needs at least one model")
        self.models = dict(models)
        self.registration = registration
        self.mode = RegistrationMode(mode)
        self.threads = threads
        #: Where the database was loaded from (None if built in memory).
        self.directory: Path | None = None
        self._stack: FieldStack | None = None

    @property
    def names(self) -> list[str]:
        return list(self.models)

    def prepare(self) -> ModelDatabase:
        """Build every search structure now (KD-trees, exact distances, the field stack),
        so that no recognition pays for a lazy build; returns the database."""
        for model in self.models.values():
            model.tree  # noqa: B018
            model.distance  # noqa: B018
            model.candidate_curvatures  # noqa: B018
        self.field_stack  # noqa: B018
        return self

    @property
    def field_stack(self) -> FieldStack:
        """Every model's distance field in one stack, in :attr:`names` order (cached)."""
        if self._stack is None:
            self._stack = FieldStack.of([m.distance_field for m in self.models.values()])
        return self._stack

    def __len__(self) -> int:
        return len(self.models)

    def __getitem__(self, name: str) -> MeshModel:
        return self.models[name]

    @classmethod
    def from_meshes(
        cls,
        meshes: Mapping[str, trimesh.Trimesh],
        *,
        config: MeshModelConfig = MeshModelConfig(),
        registration: RegistrationConfig = RegistrationConfig(),
        progress: bool = False,
    ) -> ModelDatabase:
        """Validate each mesh (metres) and build its lookup table, curvature map and field."""
        models = {}
        items = list(meshes.items())
        if progress:
            from tqdm import tqdm

            items = tqdm(items, desc="building curvature tables", unit="model")
        for name, mesh in items:
            model = MeshModel(name, mesh, config)
            model.table  # noqa: B018 - build now, not at the first recognition
            model.candidate_curvatures  # noqa: B018
            model.distance_field  # noqa: B018
            models[name] = model
        return cls(models, registration).prepare()

    # --- persistence ------------------------------------------------------------------

    def save(self, directory) -> Path:
        """Write every model (mesh, table, distance field) as .npz and a JSON manifest.

        Files are written atomically; the manifest records each model's mesh hash and
        table settings so that :meth:`load` can refuse a stale or corrupt file.
        """
        directory = Path(directory)
        manifest = {"format": DATABASE_FORMAT, "models": {}}
        for name, model in self.models.items():
            table, df, dense = model.table, model.distance_field, model.candidate_curvatures
            file = f"{_safe(name)}.npz"
            arrays = {
                "vertices": model.vertices,
                "faces": model.faces,
                "normals": model.normals,
                "table_vertex": table.vertex,
                "table_k1": table.k1,
                "table_k2": table.k2,
                "table_d1": table.d1,
                "vertex_index": dense.vertex,
                "vertex_k1": dense.k1.astype(np.float32),
                "vertex_k2": dense.k2.astype(np.float32),
                "vertex_d1": dense.d1.astype(np.float32),
                "field_origin": df.origin,
                "field_voxel": np.array(df.voxel),
                "field_band": np.array(df.band),
                "field_values": df.values,
            }
            _write_atomic(directory / file, lambda f, a=arrays: np.savez_compressed(f, **a))
            manifest["models"][name] = {
                "file": file,
                "mesh_hash": model.hash,
                "config": _config_json(model.config),
                "timings_s": model.timings,
            }
        _write_atomic(
            directory / "manifest.json",
            lambda f: f.write(json.dumps(manifest, indent=2).encode()),
        )
        return directory

    @classmethod
    def load(
        cls,
        directory,
        *,
        registration: RegistrationConfig = RegistrationConfig(),
        config: MeshModelConfig | None = None,
    ) -> ModelDatabase:
        """Read a database written by :meth:`save`.

        Raises :class:`~recognition.errors.InvalidModel` when the directory is missing,
        written in another format, corrupt, its mesh hash does not match its content, or
        (with ``config``) it was built with other table settings.
        """
        directory = Path(directory)
        try:
            manifest = json.loads((directory / "manifest.json").read_text())
        except (OSError, ValueError) as exc:
            raise InvalidModel(f"no readable model database in {directory}: {exc}") from exc
        if manifest.get("format") != DATABASE_FORMAT:
            raise InvalidModel(
                f"model database in {directory} has format {manifest.get('format')!r}; "
                f"expected {DATABASE_FORMAT}: rebuild it"
            )
        models = {}
        for name, entry in manifest["models"].items():
            model_config = MeshModelConfig(**_config_from_json(entry["config"]))
            if config is not None and model_config != config:
                raise InvalidModel(f"{name}: built with other table settings; rebuild it")
            try:
                with np.load(directory / entry["file"], allow_pickle=False) as z:
                    a = {k: z[k] for k in z.files}
            except (OSError, ValueError, KeyError) as exc:
                raise InvalidModel(f"{name}: cannot read {entry['file']}: {exc}") from exc
            mesh = trimesh.Trimesh(a["vertices"], a["faces"], process=False)
            table = CurvatureTable(a["table_vertex"], a["table_k1"], a["table_k2"], a["table_d1"])
            df = DistanceField(
                a["field_origin"],
                float(a["field_voxel"]),
                a["field_values"],
                float(a["field_band"]),
            )
            dense = CurvatureTable(
                a["vertex_index"],
                a["vertex_k1"].astype(float),
                a["vertex_k2"].astype(float),
                a["vertex_d1"].astype(float),
            )
            model = MeshModel(
                name, mesh, model_config, table, df, validate=False, candidate_curvatures=dense
            )
            if model.hash != entry["mesh_hash"]:
                raise InvalidModel(f"{name}: mesh content does not match its hash; rebuild it")
            model.timings.update(entry.get("timings_s", {}))
            models[name] = model
        database = cls(models, registration).prepare()
        database.directory = directory
        return database

    # --- recognition ------------------------------------------------------------------

    def recognize(
        self,
        curves: DataCurves,
        *,
        mode: RegistrationMode | str | None = None,
        max_error_m: float = MAX_ERROR_M,
        models: list[str] | None = None,
    ) -> Recognition:
        """Register the curves on every model; the smallest error names the object (4.9).

        Parameters
        ----------
        curves : DataCurves
        mode : {"fast", "thesis", "icp-baseline"}, optional
            Registration mode (default: the database's).
        max_error_m : float
            A best error above this means the curves fit no model: ``name`` is None.
        models : list of str, optional
            Restrict recognition to these models.
        """
        start = time.perf_counter()
        mode = registration_mode(mode or self.mode)
        geometry = data_geometry(curves, self.registration)
        names = models or self.names
        if mode is RegistrationMode.FAST:
            index = {n: i for i, n in enumerate(self.names)}
            found = register_fast(
                [self.models[n] for n in names],
                curves,
                geometry,
                self.registration,
                stack=self.field_stack,
                which_field=np.array([index[n] for n in names]),
            )
            registrations = dict(zip(names, found, strict=True))
        else:
            registrations = self._register_each(curves, names, mode, geometry)
        ranking = sorted(
            ((n, r.error_m) for n, r in registrations.items()), key=lambda item: item[1]
        )
        best_name, best_error = ranking[0]
        second = ranking[1][1] if len(ranking) > 1 else float("inf")
        fits = np.isfinite(best_error) and best_error <= max_error_m
        best = registrations[best_name]
        return Recognition(
            best_name if fits else None,
            ranking,
            best.T_model_from_data if fits else np.full((4, 4), np.nan),
            best.location if fits else np.full(3, np.nan),
            float(second - best_error) if np.isfinite(best_error) else float("inf"),
            registrations,
            {n: r.time_s for n, r in registrations.items()},
            time.perf_counter() - start,
            geometry,
        )

    def _register_each(self, curves, names, mode, geometry) -> dict[str, Registration]:
        """Thesis and ICP modes: each model on its own; the best few get exact errors."""

        def one(name):
            return register(
                self.models[name],
                curves,
                mode=mode,
                config=self.registration,
                geometry=geometry,
                exact=False,
            )

        if self.threads > 1 and len(names) > 1:
            with ThreadPoolExecutor(self.threads) as pool:
                registrations = dict(zip(names, pool.map(one, names), strict=True))
        else:
            registrations = {name: one(name) for name in names}
        order = sorted(registrations.items(), key=lambda kv: kv[1].error_m)[:EXACT_TOP]
        for rank, (name, _) in enumerate(order):
            registrations[name] = registrations[name].with_exact_error(
                self.models[name], curves, refine=rank == 0, point=geometry.point
            )
        return registrations


def _safe(name: str) -> str:
    return "".join(ch if ch.isalnum() or ch in "-_" else "_" for ch in name)


def _config_json(config: MeshModelConfig) -> dict:
    d = asdict(config)
    d["fit_sizes"] = list(d["fit_sizes"])
    return d


def _config_from_json(d: dict) -> dict:
    d = dict(d)
    d["fit_sizes"] = tuple(d["fit_sizes"])
    return d
