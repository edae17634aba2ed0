"""A database of mesh models and recognition by registration (thesis Sections 4.1.3, 4.3)."""

from __future__ import annotations

import functools
import json
import os
import time
from collections.abc import Mapping
from dataclasses import asdict
from pathlib import Path
from typing import IO, Any

import numpy as np
import trimesh

from recognition.errors import InvalidModel
from recognition.files import write_atomic
from recognition.surfaces.data_curves import DataCurves
from recognition.surfaces.distance import DistanceField, FieldStack
from recognition.surfaces.lookup import CurvatureTable
from recognition.surfaces.mesh_model import MeshModel, MeshModelConfig
from recognition.surfaces.registration import (
    CONFIGS,
    FastConfig,
    IcpConfig,
    Recognition,
    RegistrationMode,
    ThesisConfig,
    data_geometry,
    rank,
    register_all,
    registration_mode,
)

__all__ = ["DATABASE_FORMAT", "MeshRegistrationConfig", "ModelDatabase", "Recognition"]

MeshRegistrationConfig = FastConfig | ThesisConfig | IcpConfig
"""The settings of a registration mode on mesh models."""

#: Version of the on-disk format; a different version is rebuilt, never read.
DATABASE_FORMAT = 5
#: Default largest registration error (metres) of a recognised model: data that fit no
#: model better than this are not recognised (name None).
MAX_ERROR_M = 0.5e-3


def _savez(f: IO[bytes], arrays: dict[str, np.ndarray]) -> None:
    # uncompressed: a database loads at the speed of the disk, not of zlib
    np.savez(f, allow_pickle=False, **arrays)


class ModelDatabase:
    """Mesh models with their curvature tables; recognises data curves (4.9).

    Parameters
    ----------
    models : mapping of str to MeshModel
    registration : FastConfig, ThesisConfig or IcpConfig
        The default registration of :meth:`recognize` (its class names the mode).
    threads : int
        Thesis and ICP modes: models registered concurrently by :meth:`recognize` (numpy
        releases the GIL in the heavy array work); results do not depend on it. The fast
        mode searches all models in one batch.
    """

    def __init__(
        self,
        models: Mapping[str, MeshModel],
        registration: MeshRegistrationConfig = FastConfig(),
        threads: int = 1,
    ) -> None:
        if not models:
            raise InvalidModel("a model database needs at least one model")
        self.models = dict(models)
        self.registration = registration
        self.threads = threads
        #: Where the database was loaded from (None if built in memory).
        self.directory: Path | None = None
        self._stack: FieldStack | None = None

    @property
    def names(self) -> list[str]:
        """The model names, in database order."""
        return list(self.models)

    def prepare(self) -> ModelDatabase:
        """Build the structures every fast-mode recognition searches now (the candidate
        maps, the field stack); returns the database. The exact-distance trees of a model
        are built when a recognition first polishes a pose on it (about 0.1 s for a
        100k-vertex model), the KD-trees when a mode needs them."""
        for model in self.models.values():
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
        registration: MeshRegistrationConfig = FastConfig(),
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

    def save(self, directory: str | os.PathLike[str]) -> Path:
        """Write every model (mesh, table, distance field) as .npz and a JSON manifest.

        Files are written atomically; the manifest records each model's mesh hash and
        table settings so that :meth:`load` can refuse a stale or corrupt file.
        """
        directory = Path(directory)
        models: dict[str, dict[str, Any]] = {}
        manifest: dict[str, object] = {"format": DATABASE_FORMAT, "models": models}
        for name, model in self.models.items():
            table, df, dense = model.table, model.distance_field, model.candidate_curvatures
            assert table.d1 is not None and dense.d1 is not None
            file = f"{_safe(name)}.npz"
            arrays = {
                "vertices": model.vertices,
                "faces": model.faces,
                "normals": model.normals,
                "table_vertex": table.site,
                "table_k1": table.k1,
                "table_k2": table.k2,
                "table_d1": table.d1,
                "vertex_index": dense.site,
                "vertex_k1": dense.k1.astype(np.float32),
                "vertex_k2": dense.k2.astype(np.float32),
                "vertex_d1": dense.d1.astype(np.float32),
                "field_origin": df.origin,
                "field_voxel": np.array(df.voxel),
                "field_band": np.array(df.band),
                "field_values": df.values,
            }

            write_atomic(directory / file, functools.partial(_savez, arrays=arrays))
            models[name] = {
                "file": file,
                "mesh_hash": model.hash,
                "config": _config_json(model.config),
                "timings_s": model.timings,
            }
        write_atomic(
            directory / "manifest.json",
            lambda f: f.write(json.dumps(manifest, indent=2).encode()),
        )
        return directory

    @classmethod
    def load(
        cls,
        directory: str | os.PathLike[str],
        *,
        registration: MeshRegistrationConfig = FastConfig(),
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
                name,
                mesh,
                model_config,
                table,
                df,
                validate=False,
                candidate_curvatures=dense,
                normals=a["normals"],
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
        registration: MeshRegistrationConfig | None = None,
        *,
        mode: RegistrationMode | str | None = None,
        max_error_m: float = MAX_ERROR_M,
        models: list[str] | None = None,
    ) -> Recognition:
        """Register the curves on every model; the smallest error names the object (4.9).

        Parameters
        ----------
        curves : DataCurves
        registration : FastConfig, ThesisConfig or IcpConfig, optional
            The registration (default: the database's).
        mode : {"fast", "thesis", "icp-baseline"}, optional
            Another mode than the database's, with its defaults but the database's
            table-lookup tolerance and data geometry settings (ignored with
            ``registration``).
        max_error_m : float
            A best error above this means the curves fit no model: ``name`` is None.
        models : list of str, optional
            Restrict recognition to these models.
        """
        start = time.perf_counter()
        config = registration or self._config_of(mode)
        geometry = data_geometry(curves, config.geometry)
        names = models or self.names
        chosen = [self.models[n] for n in names]
        if isinstance(config, FastConfig):
            index = {n: i for i, n in enumerate(self.names)}
            found = register_all(
                chosen,
                curves,
                config,
                geometry=geometry,
                stack=self.field_stack,
                which_field=np.array([index[n] for n in names]),
            )
        else:
            found = register_all(chosen, curves, config, geometry=geometry, threads=self.threads)
        registrations = dict(zip(names, found, strict=True))
        return rank(registrations, geometry, time.perf_counter() - start, max_error_m)

    def _config_of(self, mode: RegistrationMode | str | None) -> MeshRegistrationConfig:
        """The database's registration, or ``mode``'s with the database's shared fields."""
        own = self.registration
        if mode is None or registration_mode(mode) is own.mode:
            return own
        config = CONFIGS[registration_mode(mode)](delta=own.delta, geometry=own.geometry)
        if not isinstance(config, FastConfig | ThesisConfig | IcpConfig):
            raise InvalidModel(f"mode {mode!r} does not register mesh models")
        return config


def _safe(name: str) -> str:
    """``name`` with every character but letters, digits, '-' and '_' replaced by '_'."""
    return "".join(ch if ch.isalnum() or ch in "-_" else "_" for ch in name)


def _config_json(config: MeshModelConfig) -> dict[str, Any]:
    """The config as JSON-ready values (the fit sizes as a list)."""
    d = asdict(config)
    d["fit_sizes"] = list(d["fit_sizes"])
    return d


def _config_from_json(d: dict[str, Any]) -> dict[str, Any]:
    """The keyword arguments of a :class:`MeshModelConfig` read back from JSON."""
    d = dict(d)
    d["fit_sizes"] = tuple(d["fit_sizes"])
    return d
