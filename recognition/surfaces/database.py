"""A database of mesh models and recognition by registration (thesis Sections 4.1.3, 4.3)."""

from __future__ import annotations

import os
import time
from collections.abc import Mapping
from dataclasses import replace
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np
import trimesh
from numpy.typing import ArrayLike

from recognition.errors import InvalidArgument, InvalidCurveData, InvalidModel
from recognition.surfaces.belief import Belief, BeliefConfig, curve_points
from recognition.surfaces.data_curves import DataCurves
from recognition.surfaces.database_files import DATABASE_FORMAT, read_models, write_models
from recognition.surfaces.distance import FieldStack
from recognition.surfaces.mesh_model import MeshModel, MeshModelConfig
from recognition.surfaces.noise_model import NoiseModel
from recognition.surfaces.registration import (
    ALIGNED_SEARCH,
    CONFIGS,
    CandidateIndex,
    FastConfig,
    IcpConfig,
    Recognition,
    RegistrationMode,
    ThesisConfig,
    data_geometry,
    data_noise_m,
    outlier_threshold_m,
    rank,
    register_all,
    registration_mode,
)
from recognition.surfaces.registration.contact_pairs import N_KEPT, N_REFINED, pair_search

__all__ = ["DATABASE_FORMAT", "MeshRegistrationConfig", "ModelDatabase", "Recognition"]

#: A broader search's pose that misses a touch by more than this, metres, is left out: a
#: pose uncertain by 0.3 mm along the touch's normal loses more than 5 nats on it
#: (:mod:`~recognition.surfaces.touch_evidence`) against one that meets it.
RIVAL_MISS_M = 1.0e-3
#: A broader search also pairs p with the last this many touches that sensed a normal
#: (:func:`~recognition.surfaces.registration.contact_pairs.pair_search`) ...
PAIRED_TOUCHES = 1
#: ... on this many models: the hypotheses' (most probable first), then those the
#: broader search fits best.
PAIRED_MODELS = 3
#: A search whose answer may end the touches (``broaden(..., final=True)``: after the
#: touch that made the belief sure, or after the last touch) refines this many of each
#: model's pair poses and keeps every distinct one: no touch follows to test a rival that
#: the curves rank low, so the belief judges them all on all the contact.
FINAL_REFINED = 64

if TYPE_CHECKING:
    from recognition.surfaces.touch_planning import TouchLimits, TouchPlan

MeshRegistrationConfig = FastConfig | ThesisConfig | IcpConfig
"""The settings of a registration mode on mesh models."""

#: Default largest registration error (metres) of a recognised model: data that fit no
#: model better than this are not recognised (name None).
MAX_ERROR_M = 0.5e-3


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
        self._index: CandidateIndex | None = None

    @property
    def names(self) -> list[str]:
        """The model names, in database order."""
        return list(self.models)

    @property
    def field_of(self) -> dict[str, int]:
        """Each model's field in :attr:`field_stack` (its place in database order)."""
        return {n: i for i, n in enumerate(self.models)}

    def prepare(self) -> ModelDatabase:
        """Build the structures every fast-mode recognition searches now (the candidate
        maps, the models' symmetries, the field stack); returns the database. The
        exact-distance grid of a model is built when a recognition first polishes a pose
        on it (10-40 ms for a 100k-vertex model), the KD-trees when a mode needs them."""
        for model in self.models.values():
            model.candidate_curvatures  # noqa: B018
            model.symmetries  # noqa: B018
        self.field_stack  # noqa: B018
        self.candidate_index  # noqa: B018
        return self

    @property
    def field_stack(self) -> FieldStack:
        """Every model's distance field in one stack, in :attr:`names` order (cached).

        Each model then reads its field from the stack (a read-only view), so that the
        database's fields are held once (a model in two databases reads the stack built
        last)."""
        if self._stack is None:
            models = list(self.models.values())
            self._stack = FieldStack.of([m.distance_field for m in models])
            for i, model in enumerate(models):
                model.share_distance_field(self._stack.field(i))
        return self._stack

    @property
    def candidate_index(self) -> CandidateIndex:
        """Every model's candidate map and ring descriptors in one table, owners in
        :attr:`names` order (cached): the fast mode ranks candidates across the database."""
        if self._index is None:
            self._index = CandidateIndex.of(list(self.models.values()))
        return self._index

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
            model.rings  # noqa: B018
            models[name] = model
        return cls(models, registration).prepare()

    # --- persistence ------------------------------------------------------------------

    def save(self, directory: str | os.PathLike[str]) -> Path:
        """Write every model (mesh, tables, distance field) as .npz and a manifest of their
        digests (:mod:`~recognition.surfaces.database_files`), each file atomically."""
        return write_models(list(self.models.values()), Path(directory))

    @classmethod
    def load(
        cls,
        directory: str | os.PathLike[str],
        *,
        registration: MeshRegistrationConfig = FastConfig(),
        config: MeshModelConfig | None = None,
    ) -> ModelDatabase:
        """Read a database written by :meth:`save`, verified whole.

        Raises :class:`~recognition.errors.InvalidModel` when the folder holds no
        database, or one of another format, damaged in any way, referring outside the
        folder, or (with ``config``) built with other table settings; the message names
        the file.
        """
        directory = Path(directory)
        models = read_models(directory, config)
        database = cls({m.name: m for m in models}, registration).prepare()
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
        noise: NoiseModel | None = None,
        belief: BeliefConfig | None = None,
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
            A best error above this means the curves fit no model: ``name`` is None. It
            is a mean distance of the data from the model (4.8), not a test of the
            shape: over short curves similar shapes fit well within it (over 2 mm, a
            sphere of 100 mm radius lies within 0.01 mm of one of 33 mm).
        models : list of str, optional
            Restrict recognition to these models.
        noise : NoiseModel, optional
            The noise model of the result's belief (:mod:`recognition.surfaces.belief`);
            default: the curves' own scatter and the registration's
            ``model_mismatch_m`` (at least :class:`NoiseModel`'s default).
        belief : BeliefConfig, optional
            Which poses become the belief's hypotheses (default: its defaults).
        """
        start = time.perf_counter()
        names = self._checked_selection(curves, models, max_error_m)
        config = registration or self._config_of(mode)
        geometry = data_geometry(curves, config.geometry)
        noise_m = data_noise_m(curves)
        chosen = [self.models[n] for n in names]
        if isinstance(config, FastConfig):
            index = self.field_of
            found = register_all(
                chosen,
                curves,
                config,
                geometry=geometry,
                stack=self.field_stack,
                which_field=np.array([index[n] for n in names]),
                index=self.candidate_index,
                noise_m=noise_m,
            )
        else:
            found = register_all(chosen, curves, config, geometry=geometry, threads=self.threads)
        registrations = dict(zip(names, found, strict=True))
        result = rank(registrations, geometry, time.perf_counter() - start, max_error_m)
        if noise is None:
            mismatch = max(getattr(config, "model_mismatch_m", 0.0), NoiseModel.model_mismatch_m)
            noise = NoiseModel(model_mismatch_m=mismatch)
        candidates = [
            (r.model, T, float(e))
            for r in found
            if not r.rejected
            for T, e in zip(
                r.poses if len(r.poses) else r.T_model_from_data[None],
                r.pose_errors_m if len(r.pose_errors_m) else [r.error_m],
                strict=True,
            )
        ]
        settings = belief or BeliefConfig()
        hypotheses = Belief.of(
            self.models,
            candidates,
            curve_points(curves, settings.points_per_curve),
            geometry.point,
            noise_m,
            noise=noise,
            config=settings,
            curves=curves,
        )
        return replace(result, belief=hypotheses, time_s=time.perf_counter() - start)

    def update(
        self,
        belief: Belief,
        points: np.ndarray | None = None,
        misses: list[tuple[np.ndarray, np.ndarray, float]] | tuple = (),
        windows: np.ndarray | list[float] | None = None,
        normals: np.ndarray | None = None,
    ) -> Belief:
        """``belief`` after further contact (:meth:`Belief.with_contacts`): touched
        ``points`` (k, 3) in the curves' frame, metres, ``misses`` (start, direction,
        travel) that met nothing, each touch's approach length ``windows`` (k,) and the
        surface normal sensed there, ``normals`` (k, 3) (rows of NaN: none)."""
        return belief.with_contacts(self.models, points, misses, windows, normals)

    def broaden(self, belief: Belief, final: bool = False) -> Belief:
        """``belief`` with the poses of a broader search of its contact added: for when
        no hypothesis explains the contact (:attr:`Belief.unexplained`), to look for
        rivals of a sure answer, or for a better answer than an unsure one. Two searches:
        the fast mode's first fallback pass (candidates over every model's whole surface,
        more poses kept; the touches' contact points choose the poses with the curves),
        and, on ``PAIRED_MODELS`` models (the hypotheses', then those that pass fits
        best), poses from p paired with the last ``PAIRED_TOUCHES`` touches that sensed a
        normal (:func:`~recognition.surfaces.registration.contact_pairs.pair_search`,
        scored on the belief's curve points: where the curves leave the pose free, a
        touch elsewhere fixes it). A pose that misses a touch by more than
        ``RIVAL_MISS_M`` is left out (it could not compete); of the others, those a
        recognition would keep (:meth:`BeliefConfig.within_window`: within the window of
        the least error on the curves) join. Unchanged without curves, or when a broader
        search has already had all its touches (:attr:`Belief.touches`: those that met
        nothing too, which rule out poses the last search kept). ``final``: a search whose
        answer may end the touches (``FINAL_REFINED``)."""
        if belief.curves is None or belief.broadened == belief.touches:
            return belief
        touches = belief.points[belief.n_curve_points :]
        field_of = self.field_of
        config = self.registration if isinstance(self.registration, FastConfig) else FastConfig()
        mismatch = max(config.model_mismatch_m, belief.noise.model_mismatch_m)
        wide = replace(config, search=ALIGNED_SEARCH, fallbacks=(), model_mismatch_m=mismatch)
        geometry = data_geometry(belief.curves, wide.geometry)
        noise_m = data_noise_m(belief.curves)
        found = register_all(
            list(self.models.values()),
            belief.curves,
            wide,
            geometry=geometry,
            stack=self.field_stack,
            which_field=np.arange(len(self)),
            index=self.candidate_index,
            contact=touches,
            noise_m=noise_m,
        )
        poses = [
            (r.model, T, float(e))
            for r in found
            if not r.rejected
            for T, e in zip(r.poses, r.pose_errors_m, strict=True)
        ]
        sensed = np.flatnonzero(np.all(np.isfinite(belief.normals), axis=1))[-PAIRED_TOUCHES:]
        if len(sensed):
            weight: dict[str, float] = {}
            for h in belief.hypotheses:
                weight[h.model] = weight.get(h.model, 0.0) + h.posterior
            fitted = sorted((r for r in found if not r.rejected), key=lambda r: r.error_m)
            names = list(
                dict.fromkeys(sorted(weight, key=lambda n: -weight[n]) + [r.model for r in fitted])
            )[:PAIRED_MODELS]
            poses += pair_search(
                [self.models[n] for n in names],
                self.field_stack,
                np.array([field_of[n] for n in names], dtype=np.int64),
                belief.points[: belief.n_curve_points],
                geometry.point,
                geometry.normal,
                touches[sensed],
                belief.normals[sensed],
                outlier_threshold_m(noise_m, wide),
                seed=len(belief.windows),
                misses=belief.misses,
                refined=FINAL_REFINED if final else N_REFINED,
                kept=FINAL_REFINED if final else N_KEPT,
            )
        # a pose that misses a touch could not compete; of the others, as a recognition's
        # poses become hypotheses (Belief.of): those that fit the curves within the window
        # of the least error (all of them: a rival may fit the curves a little worse and
        # the touches better)
        if poses:
            T = np.array([pose for _, pose, _ in poses])
            placed = touches @ T[:, :3, :3].transpose(0, 2, 1) + T[:, None, :3, 3]
            which = np.array([field_of[name] for name, _, _ in poses])
            meets = np.all(np.abs(self.field_stack(placed, which)) <= RIVAL_MISS_M, axis=1)
            poses = [p for p, ok in zip(poses, meets, strict=True) if ok]
        return belief.with_poses(self.models, belief.config.within_window(poses))

    def plan_touch(
        self,
        belief: Belief,
        limits: TouchLimits,
        seed: int = 0,
        avoid: ArrayLike | None = None,
        within_m: float | None = None,
        doubt: float = 0.0,
    ) -> TouchPlan | None:
        """The next touch of greatest expected information gain, none near the points
        ``avoid`` (k, 3), with ``within_m`` near the contact made when it can, "none of
        these" at least ``doubt`` probable among its outcomes
        (:func:`recognition.surfaces.touch_planning.plan_touch`), or None."""
        from recognition.surfaces.touch_planning import plan_touch

        return plan_touch(
            belief,
            self.models,
            self.field_stack,
            self.field_of,
            limits,
            seed=seed,
            avoid=avoid,
            within_m=within_m,
            doubt=doubt,
        )

    def _checked_selection(
        self, curves: object, models: list[str] | None, max_error_m: float
    ) -> list[str]:
        """The models to search; typed errors for arguments outside their domains."""
        if not isinstance(curves, DataCurves):
            raise InvalidCurveData(
                f"curves must be a recognition.DataCurves, got {type(curves).__name__}: "
                "build one with DataCurves((curve_0, curve_1, curve_2))"
            )
        if isinstance(max_error_m, bool) or not isinstance(max_error_m, int | float):
            raise InvalidArgument(f"max_error_m must be a number of metres, got {max_error_m!r}")
        if not max_error_m > 0:
            raise InvalidArgument(f"max_error_m must be positive (metres), got {max_error_m}")
        if models is None:
            return list(self.names)
        if isinstance(models, str) or not len(models):
            raise InvalidArgument(
                f"models must be a non-empty list of model names (None: all), got {models!r}"
            )
        unknown = [n for n in models if n not in self.models]
        if unknown:
            raise InvalidArgument(
                f"unknown models {unknown}; the database holds {', '.join(self.names)}"
            )
        return list(models)

    def _config_of(self, mode: RegistrationMode | str | None) -> MeshRegistrationConfig:
        """The database's registration, or ``mode``'s with the database's shared fields."""
        own = self.registration
        if mode is None or registration_mode(mode) is own.mode:
            return own
        config = CONFIGS[registration_mode(mode)](delta=own.delta, geometry=own.geometry)
        if not isinstance(config, FastConfig | ThesisConfig | IcpConfig):
            raise InvalidModel(f"mode {mode!r} does not register mesh models")
        return config
