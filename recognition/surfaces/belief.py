"""A belief over (model, pose): the hypotheses that fit near the best, and their posterior.

Three curves through one point can leave several answers that fit about equally well:
another model, the same model at another pose, or the right pose slid along a nearly
symmetric surface. :class:`Belief` keeps every distinct (model, pose) hypothesis of a
recognition that fits near the best, refines each on all the contact there is (the three
curves and any further touches) and weighs them by the likelihood of the data under a
stated noise model (:class:`NoiseModel`):

    residual r_i = signed distance of contact point i from the model at the pose,
    r ~ N(0, Sigma),  Sigma_ij = s^2 [i = j] + m^2 k(|x_i - x_j| / l),
    k(u) = (1 + sqrt(3) u) exp(-sqrt(3) u)   (Matern 3/2),

sensor noise s independent per point, the object's mismatch from its model m a field of
correlation length l along the surface (how a real object differs from its scan; the
simulator's ``--model-error-mm`` draws such a field). Correlated residuals carry less
evidence than as many independent ones, so the mismatch keeps near-equal fits from
looking certain. The Matern 3/2 field is once differentiable: a squared-exponential
kernel (infinitely smooth) calls micrometre roughness of the residuals impossible and
made the true model of a mismatched object look hundreds of log-units worse than it
is. Each residual is clipped at ``outlier_sigmas`` effective noise levels (a gross outlier
counts alike under every hypothesis, and is reported). With a uniform prior over the
hypotheses, the posterior of h is proportional to exp(-r_h^T Sigma^-1 r_h / 2) over the
curves' points (its whitened residuals counted by Huber's loss beyond ``huber_k``,
:class:`NoiseModel`), normalised over all hypotheses of all models and the alternative
that none of them is right (:attr:`BeliefConfig.unexplained_p`: a search can miss the
truth).

A touch counts as h predicted it before it was made, at its pose then and with that
pose's uncertainty (:mod:`recognition.surfaces.touch_evidence`; :attr:`Hypothesis.
touch_evidence`): its contact point against the uniform spread along the approach that
"none of these" predicts (:attr:`Belief.windows`), its sensed normal (:attr:`Belief.
normals`) against a uniform hemisphere. When no hypothesis predicted the touches, "none
of these" grows. A hypothesis whose refinement then moves p farther than its uncertainty
explains (:attr:`BeliefConfig.drift_sds`) has come to another place, for which the
predictions it made from where it was do not speak: its touches count again as it would
have predicted each in turn there.

Each hypothesis also carries the uncertainty of its pose (Laplace: the inverse of
J^T Sigma^-1 J, J the point-to-plane Jacobian of the residuals, with a weak prior) and so
of where it puts p. The belief's :attr:`~Belief.confidence` is the probability that the
answer is right: the best hypothesis's model, with p within ``radius_m`` of where the
best puts it, summed over that model's hypotheses.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field, replace

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.linalg import lapack
from scipy.special import gammaincinv

from recognition.errors import InvalidArgument
from recognition.rigid import point_to_plane_jacobian, pose_matrix, posed, skew
from recognition.surfaces.belief_config import BeliefConfig
from recognition.surfaces.closest_fit import refine_poses
from recognition.surfaces.data_curves import DataCurves
from recognition.surfaces.hypothesis import Hypothesis, within_probability
from recognition.surfaces.mesh_model import MeshModel
from recognition.surfaces.noise_model import NoiseModel, huber
from recognition.surfaces.registration.ambiguity import distinct_poses
from recognition.surfaces.registration.exact import smooth_normals
from recognition.surfaces.touch_evidence import (
    evidence_bounds,
    miss_evidence,
    predicted_evidence,
    sensed_normals,
)

__all__ = ["Belief", "BeliefConfig", "curve_points"]

Array = NDArray[np.float64]


def curve_points(curves: DataCurves, per_curve: int) -> Array:
    """The curves' points, at most ``per_curve`` of each curve, evenly spaced along it
    (both ends kept), (k, 3) metres."""
    chosen = []
    for c in curves.curves:
        index = np.unique(np.round(np.linspace(0, len(c) - 1, min(per_curve, len(c)))))
        chosen.append(c[index.astype(np.int64)])
    return np.concatenate(chosen)


@dataclass(frozen=True)
class Belief:
    """The posterior over (model, pose) given all contact so far (module docstring).

    Attributes
    ----------
    hypotheses : tuple of Hypothesis
        Most probable first.
    points : (n, 3) float
        Every contact point, data frame, metres: the curves' points (at most
        ``config.points_per_curve`` of each, :func:`curve_points`), then the touches.
    n_curve_points : int
        How many of ``points`` are the curves'.
    point : (3,) float
        The curves' common point p, data frame.
    sensor_m : float
        The sensor noise used, metres.
    noise : NoiseModel
    config : BeliefConfig
    misses : tuple of (start (3,), direction (3,), travel) per touch that met nothing
    windows : (k,) float
        The length of each touch's approach (``points`` after the curves'), metres: where
        its contact could have lain.
    normals : (k, 3) float
        Each touch's sensed outward unit normal, data frame (a row of NaN: none sensed).
    unexplained : float
        Posterior that none of the hypotheses is the truth (module docstring).
    curves : DataCurves or None
        The curves the belief started from (a broader search can start again from them).
    broadened : int or None
        How many touches (:attr:`touches`) the last broader search that added its poses
        (:meth:`with_poses`) had (None: none has).
    """

    hypotheses: tuple[Hypothesis, ...]
    points: Array
    n_curve_points: int
    point: Array
    sensor_m: float
    noise: NoiseModel = NoiseModel()
    config: BeliefConfig = BeliefConfig()
    misses: tuple[tuple[Array, Array, float], ...] = ()
    windows: Array = field(default_factory=lambda: np.zeros(0))
    normals: Array = field(default_factory=lambda: np.zeros((0, 3)))
    unexplained: float = 0.0
    curves: DataCurves | None = field(default=None, repr=False)
    broadened: int | None = None

    @property
    def touches(self) -> int:
        """How many touches the belief has had: those that met the surface and those that
        met nothing (:attr:`misses`)."""
        return len(self.windows) + len(self.misses)

    @property
    def best(self) -> Hypothesis | None:
        """The most probable hypothesis (None when there is none)."""
        return self.hypotheses[0] if self.hypotheses else None

    @property
    def confidence(self) -> float:
        """Probability that the best hypothesis is right: its model, with p within
        ``config.radius_m`` of where it puts p (summed over that model's hypotheses, each
        with its location's uncertainty); 0 when there is none."""
        if not self.hypotheses:
            return 0.0
        best = self.hypotheses[0]
        total = 0.0
        for h in self.hypotheses:
            if h.model == best.model:
                offset = h.nearest_location(best.location) - best.location
                total += h.posterior * within_probability(
                    offset, h.location_covariance, self.config.radius_m
                )
        return float(min(total, 1.0))

    @classmethod
    def of(
        cls,
        models: Mapping[str, MeshModel],
        candidates: Sequence[tuple[str, Array, float]],
        points: ArrayLike,
        point: ArrayLike,
        sensor_estimate_m: float,
        *,
        noise: NoiseModel = NoiseModel(),
        config: BeliefConfig = BeliefConfig(),
        curves: DataCurves | None = None,
    ) -> Belief:
        """The belief from candidate poses ``(model, T_model_from_data, error_m)`` (e.g.
        every pose a recognition ended with): those within the configured window of the
        least error, refined on ``points`` (n, 3) and scored. ``point``: the curves'
        common point p; ``sensor_estimate_m``: the curves' own scatter; ``curves``: the
        curves themselves (kept for a broader search)."""
        usable = [(n, T, e) for n, T, e in candidates if n in models]
        points = np.asarray(points, dtype=np.float64)
        belief = cls(
            (),
            points,
            len(points),
            np.asarray(point, dtype=np.float64),
            noise.sensor_m(sensor_estimate_m),
            noise,
            config,
            curves=curves,
        )
        kept = config.within_window(usable, config.max_hypotheses)
        if not kept:
            return belief
        return belief._rescored([(n, np.asarray(T, float), 0.0) for n, T in kept], models)

    def with_contacts(
        self,
        models: Mapping[str, MeshModel],
        points: ArrayLike | None = None,
        misses: Sequence[tuple[ArrayLike, ArrayLike, float]] = (),
        windows: ArrayLike | None = None,
        normals: ArrayLike | None = None,
    ) -> Belief:
        """The belief after further contact: ``points`` (k, 3) touched (data frame,
        metres) and ``misses`` (start, unit direction, travel in metres) that met no
        surface; ``windows`` (k,): each touch's approach length, metres, along which its
        contact could have lain (default ``config.touch_window_m``); ``normals`` (k, 3):
        the outward surface normal sensed at each (a row of NaN, or None for all: none).
        Every hypothesis is refined on all the points and scored again."""
        new = np.zeros((0, 3)) if points is None else np.asarray(points, float).reshape(-1, 3)
        if not np.all(np.isfinite(new)):
            raise InvalidArgument("contact points must be finite (n, 3) metres")
        sensed = sensed_normals(normals, len(new))
        if windows is None:
            lengths = np.full(len(new), self.config.touch_window_m)
        else:
            lengths = np.asarray(windows, float).reshape(-1)
        if lengths.shape != (len(new),) or not np.all(np.isfinite(lengths) & (lengths > 0)):
            raise InvalidArgument(
                f"windows must be one positive length (metres) per contact point, got {windows!r}"
            )
        moved = [
            (np.asarray(s, float), np.asarray(d, float) / np.linalg.norm(d), float(t))
            for s, d, t in misses
        ]
        belief = replace(
            self,
            hypotheses=(),
            points=np.concatenate([self.points, new]),
            misses=(*self.misses, *moved),
            windows=np.concatenate([self.windows, lengths]),
            normals=np.concatenate([self.normals, sensed]),
        )
        whitening = belief._whitening()
        scores = belief._predicted(self.hypotheses, models, whitening, len(self.windows))
        return belief._rescored(
            [
                (h.model, h.T_model_from_data, h.touch_evidence + score)
                for h, score in zip(self.hypotheses, scores, strict=True)
            ],
            models,
            whitening,
            [self.config.drift_reach_m(h.location_sd_m) for h in self.hypotheses],
        )

    def with_poses(
        self, models: Mapping[str, MeshModel], poses: Sequence[tuple[str, Array]]
    ) -> Belief:
        """The belief with further candidate poses ``(model, T_model_from_data)`` (a
        broader search's), refined and scored with its hypotheses on all the contact;
        marked ``broadened`` with the touches it had. A new pose's touches count as it
        would have predicted each in turn (:meth:`_in_turn`), as the hypotheses' did."""
        known = [(h.model, h.T_model_from_data, h.touch_evidence) for h in self.hypotheses]
        usable = [(n, np.asarray(T, float), 0.0) for n, T in poses if n in models]
        if usable and len(self.windows):
            likeliest = max([h.log_likelihood for h in self.hypotheses], default=-np.inf)
            usable = self._in_turn(usable, models, likeliest)
        return replace(self._rescored([*known, *usable], models), broadened=self.touches)

    def _in_turn(
        self,
        poses: Sequence[tuple[str, Array, float]],
        models: Mapping[str, MeshModel],
        likeliest: float = -np.inf,
    ) -> list[tuple[str, Array, float]]:
        """New poses ``(model, T_model_from_data, _)`` with their touches' evidence as
        each touch would have been predicted when it was made: touch i at the pose
        refined on the curves and the touches before it, with that fit's uncertainty
        (the chain rule, p(t_1 .. t_k) = prod_i p(t_i | curves, t_<i)). Each pose ends
        refined on the contact before the last touch. A pose that cannot come within
        the posterior floor (:attr:`BeliefConfig.min_posterior`) of ``likeliest`` (the
        log-likelihood of a hypothesis that stays), even if it predicted each touch still
        to count perfectly (:meth:`_touch_bounds`), is left out as soon as that is so:
        it would be dropped."""
        n = self.n_curve_points
        current = [poses[k] for k in _fitted_order([name for name, _, _ in poses])]
        total = np.zeros(len(current))
        with np.errstate(divide="ignore"):  # min_posterior 0: no floor
            floor = likeliest + np.log(self.config.min_posterior)
        still = np.r_[np.cumsum(self._touch_bounds()[::-1])[::-1], 0.0]  # touch i on, at most
        for i in range(len(self.windows) + 1):
            alive = total + still[i] >= floor
            current = [pose for pose, ok in zip(current, alive, strict=True) if ok]
            total = total[alive]
            if not current or i == len(self.windows):
                break
            before = replace(
                self,
                points=self.points[: n + i],
                misses=(),
                windows=self.windows[:i],
                normals=self.normals[:i],
            )
            fitted = before._fitted(current, models, before._whitening())
            upto = replace(
                self,
                points=self.points[: n + i + 1],
                windows=self.windows[: i + 1],
                normals=self.normals[: i + 1],
            )
            total += np.array(upto._predicted(fitted, models, upto._whitening(), i))
            current = [(h.model, h.T_model_from_data, 0.0) for h in fitted]
        return [(name, T, float(e)) for (name, T, _), e in zip(current, total, strict=True)]

    def _rescored(
        self,
        hypotheses: Sequence[tuple[str, Array, float]],
        models: Mapping[str, MeshModel],
        whitening: Array | None = None,
        reach: Sequence[float] | None = None,
    ) -> Belief:
        """This belief with ``hypotheses`` (model, T_model_from_data, touch evidence)
        refined on all the points (one that moves p farther than its ``reach``, metres,
        counts its touches again where it came to, :meth:`_recounted`), the valleys of
        the most probable explored
        (:meth:`_explored`; a new pose found there counts the touches as it would have
        predicted each in turn, :meth:`_in_turn`), near-duplicates merged, scored and
        normalised; ``whitening``: :meth:`_whitening`, when already computed."""
        config = self.config
        whitening = self._whitening() if whitening is None else whitening
        found = self._fitted(hypotheses, models, whitening)
        if not found:
            return self
        if reach is not None and len(self.windows):
            found = self._recounted(hypotheses, found, reach, models, whitening)
        starts = self._explored(found)
        if starts and len(self.windows):
            likeliest = max(h.log_likelihood for h in found)
            starts = self._in_turn(
                self._new_minima(starts, found, models, whitening), models, likeliest
            )
        found += self._fitted(starts, models, whitening)
        found = _merged(found, self.point)
        logs = np.array([h.log_likelihood for h in found])
        # "none of these": as likely as a fit whose curves' whitened residuals sit at the
        # (1 - unexplained_p) quantile of their chi-square law (n - 6 degrees of freedom);
        # the touches score each hypothesis against what "none" predicts (_predicted)
        dof = max(self.n_curve_points - 6, 1)
        other = -float(gammaincinv(dof / 2.0, 1.0 - config.unexplained_p))
        top = max(float(logs.max()), other)
        weights = np.exp(logs - top)
        total = weights.sum() + np.exp(other - top)
        weights /= total
        unexplained = float(np.exp(other - top) / total)
        order = np.argsort(-weights, kind="stable")[: config.max_hypotheses]
        kept = tuple(
            replace(found[i], posterior=float(weights[i]))
            for i in order
            if weights[i] >= config.min_posterior or i == order[0]
        )
        return replace(self, hypotheses=kept, unexplained=unexplained)

    def _recounted(
        self,
        hypotheses: Sequence[tuple[str, Array, float]],
        found: list[Hypothesis],
        reach: Sequence[float],
        models: Mapping[str, MeshModel],
        whitening: Array,
    ) -> list[Hypothesis]:
        """``found``, ``hypotheses`` refined (:meth:`_fitted`), with each that moved p
        farther than its ``reach`` (metres) counted again: it has come to another place,
        for which the touches it predicted from where it was do not speak, and there
        its touches count as it would have predicted each in turn (:meth:`_in_turn`)."""
        far, kept = [], []
        for h, k in zip(found, _fitted_order([name for name, _, _ in hypotheses]), strict=True):
            T = hypotheses[k][1]
            if np.linalg.norm(h.location - (T[:3, :3] @ self.point + T[:3, 3])) > reach[k]:
                far.append((h.model, h.T_model_from_data, 0.0))
            else:
                kept.append(h)
        if not far:
            return found
        return kept + self._fitted(self._in_turn(far, models), models, whitening)

    def _touch_bounds(self) -> Array:
        """The most each touch that met the surface can add to a hypothesis's log ratio
        against "none of these", (k,) (:func:`touch_evidence.evidence_bounds`)."""
        spread = 1.0 / np.diag(self._whitening())[self.n_curve_points :]
        return evidence_bounds(spread, self.windows, self.normals, self.noise.normal_sigma_rad())

    def _whitening(self) -> Array:
        """The inverse of the lower Cholesky factor of Sigma over :attr:`points`."""
        lower = np.linalg.cholesky(self.noise.covariance(self.points, self.sensor_m))
        whitening, info = lapack.dtrtri(lower, lower=1)  # the triangular inverse
        if info != 0:
            raise InvalidArgument(f"the residuals' covariance is singular (LAPACK info {info})")
        return np.asarray(whitening)

    def _fitted(
        self,
        hypotheses: Sequence[tuple[str, Array, float]],
        models: Mapping[str, MeshModel],
        whitening: Array,
    ) -> list[Hypothesis]:
        """``hypotheses`` (model, T_model_from_data, touch evidence) refined on all the
        points and scored (posterior 0: not normalised); ``whitening``:
        :meth:`_whitening`."""
        level = self.noise.outlier_level_m(self.sensor_m)
        found: list[Hypothesis] = []
        for name, rows in _by_model([name for name, _, _ in hypotheses]).items():
            model = models[name]
            T = np.asarray([hypotheses[k][1] for k in rows])
            R, t, signed, closest, face = refine_poses(
                model.distance,
                self.points,
                T[:, :3, :3],
                T[:, :3, 3],
                self.config.refine_iterations,
                1e-4,
                max(self.config.refine_clip_m, level),
                whitening,
                self.noise.huber_k,
            )
            moved = posed(R, t, self.points)
            errors = np.mean(np.minimum(np.abs(signed), level), axis=1)
            symmetries = model.symmetries
            locations = R @ self.point + t
            smooth = smooth_normals(model, closest, face).reshape(moved.shape)
            pivots, pose_covs, location_covs = self._laplace(
                moved, smooth, np.abs(signed) <= level, locations, whitening
            )
            whitened = np.clip(signed, -level, level) @ whitening[: self.n_curve_points].T
            for k in range(len(R)):
                evidence = hypotheses[rows[k]][2]
                log_likelihood = evidence - float(np.sum(huber(whitened[k], self.noise.huber_k)))
                log_likelihood += miss_evidence(
                    model.distance,
                    R[k],
                    t[k],
                    self.misses,
                    self.noise.point_sigma_m(self.sensor_m),
                    self.noise.huber_k,
                )
                found.append(
                    Hypothesis(
                        name,
                        pose_matrix(R[k], t[k]),
                        locations[k],
                        float(errors[k]),
                        log_likelihood,
                        0.0,
                        np.flatnonzero(np.abs(signed[k]) > level),
                        pivots[k],
                        pose_covs[k],
                        location_covs[k],
                        np.vstack(
                            [
                                locations[k],
                                symmetries[:, :3, :3] @ locations[k] + symmetries[:, :3, 3],
                            ]
                        ),
                        evidence,
                    )
                )
        return found

    def _explored(self, found: Sequence[Hypothesis]) -> list[tuple[str, Array, float]]:
        """Starts along the valleys of the most probable hypotheses: where the data leave
        a pose nearly free (a slide along a nearly symmetric surface), a model's mismatch
        makes several minima along it, far beyond what the Laplace covariance sees. Each
        of the ``explore_hypotheses`` most likely (within ``explore_log_gap`` of the best)
        is moved along its two least determined motions (the rotation scaled by the
        data's reach) by each of ``explore_steps_m`` either way. The starts carry no
        touch evidence: a pose along a valley can miss a touch its neighbour met
        (:meth:`_rescored` counts the touches for each new pose it comes to)."""
        config = self.config
        best = max(h.log_likelihood for h in found)
        top = sorted(found, key=lambda h: -h.log_likelihood)[: config.explore_hypotheses]
        starts: list[tuple[str, Array, float]] = []
        for h in top:
            if h.log_likelihood < best - config.explore_log_gap:
                continue
            if h.location_sd_m < config.explore_sd_m:
                continue  # a pose this well determined has no valley to explore
            for _, direction in self.loose_motions(h):
                for step in config.explore_steps_m:
                    starts += [
                        (h.model, h.moved(step * direction), 0.0),
                        (h.model, h.moved(-step * direction), 0.0),
                    ]
        return starts

    def _new_minima(
        self,
        starts: Sequence[tuple[str, Array, float]],
        found: Sequence[Hypothesis],
        models: Mapping[str, MeshModel],
        whitening: Array,
    ) -> list[tuple[str, Array, float]]:
        """``starts`` (model, T_model_from_data, _) refined on all the points; those
        that came to a pose of ``found`` (:func:`distinct_poses`) or of a start that fits
        the curves (and the misses) better are left out."""
        fitted = self._fitted([(n, T, 0.0) for n, T, _ in starts], models, whitening)
        out: list[tuple[str, Array, float]] = []
        for name, rows in _by_model([h.model for h in fitted]).items():
            known = [h for h in found if h.model == name]
            mine = [fitted[k] for k in rows]
            both = known + mine
            T = np.array([h.T_model_from_data for h in both])
            rank = np.r_[np.full(len(known), -np.inf), [-h.log_likelihood for h in mine]]
            kept = distinct_poses(T[:, :3, :3], T[:, :3, 3], rank, self.point, len(both))
            out += [(name, both[k].T_model_from_data, 0.0) for k in kept if k >= len(known)]
        return out

    def loose_motions(self, h: Hypothesis) -> list[tuple[float, Array]]:
        """The two least determined motions of ``h``'s pose, least determined first: the
        standard deviation along each (metres, a turn counted by how far it moves the
        data's farthest point from p) and the unit motion (turn (rad), shift (m)) (6,)
        per metre of it."""
        reach = max(float(np.max(np.linalg.norm(self.points - self.point, axis=1))), 1e-3)
        scale = np.r_[np.full(3, reach), np.ones(3)]
        C = h.pose_covariance * np.outer(scale, scale)
        values, vectors = np.linalg.eigh(0.5 * (C + C.T))
        return [(float(np.sqrt(max(values[k], 0.0))), vectors[:, k] / scale) for k in (5, 4)]

    def _laplace(
        self,
        moved: Array,
        normals: Array,
        inliers: NDArray[np.bool_],
        location: Array,
        whitening: Array,
    ) -> tuple[Array, Array, Array]:
        """The pivots (k, 3), pose (k, 6, 6) and location (k, 3, 3) covariances of k fits
        (``moved`` (k, n, 3) points, their surface's ``normals``, ``inliers`` (k, n), p's
        ``location`` (k, 3)): the inverse of J^T Sigma^-1 J plus the weak prior, J (n, 6) the
        residuals' change under a turn about the inliers' mean and a shift."""
        count = inliers.sum(axis=1, keepdims=True)
        mean = np.einsum("kn,kni->ki", inliers, moved) / np.maximum(count, 1)
        pivot = np.where(count > 0, mean, moved.mean(axis=1))
        J = point_to_plane_jacobian(moved, normals, pivot[:, None, :])
        J[~inliers] = 0.0
        rotation, translation = self.config.prior_rotation_rad, self.config.prior_translation_m
        prior = np.diag(np.repeat([rotation**-2, translation**-2], 3))
        Jw = whitening @ J
        pose = np.asarray(np.linalg.inv(np.swapaxes(Jw, 1, 2) @ Jw + prior), dtype=np.float64)
        pose = 0.5 * (pose + np.swapaxes(pose, 1, 2))
        Jp = np.concatenate(  # d location / d (turn, shift)
            [-skew(location - pivot), np.broadcast_to(np.eye(3), (len(pivot), 3, 3))], axis=2
        )
        return pivot, pose, Jp @ pose @ np.swapaxes(Jp, 1, 2)

    def _predicted(
        self,
        hypotheses: Sequence[Hypothesis],
        models: Mapping[str, MeshModel],
        whitening: Array,
        first: int,
    ) -> list[float]:
        """Each hypothesis's log ratio against "none of these" of the touches from the
        ``first`` on, as it predicted them at its pose (module docstring;
        :func:`~recognition.surfaces.touch_evidence.predicted_evidence`);
        ``whitening``: :meth:`_whitening` of all the points."""
        rows = whitening[self.n_curve_points + first :]
        out = np.zeros(len(hypotheses))
        for name, mine in _by_model([h.model for h in hypotheses]).items():
            out[mine] = predicted_evidence(
                models[name],
                np.array([hypotheses[k].T_model_from_data for k in mine]),
                np.array([hypotheses[k].pivot for k in mine]),
                np.array([hypotheses[k].pose_covariance for k in mine]),
                self.points,
                rows,
                self.windows[first:],
                self.normals[first:],
                self.noise,
                self.sensor_m,
            )
        return [float(e) for e in out]


def _by_model(names: Sequence[str]) -> dict[str, list[int]]:
    """The indices of each model's entries in ``names``, models in order of first
    appearance (the order in which :meth:`Belief._fitted` gives back their poses)."""
    groups: dict[str, list[int]] = {}
    for k, name in enumerate(names):
        groups.setdefault(name, []).append(k)
    return groups


def _fitted_order(names: Sequence[str]) -> list[int]:
    """The order in which :meth:`Belief._fitted` gives back poses of these models."""
    return [k for rows in _by_model(names).values() for k in rows]


def _merged(found: Sequence[Hypothesis], point: Array) -> list[Hypothesis]:
    """One hypothesis per distinct pose of each model (the likeliest of those that came
    to the same answer)."""
    out: list[Hypothesis] = []
    for rows in _by_model([h.model for h in found]).values():
        mine = [found[k] for k in rows]
        T = np.array([h.T_model_from_data for h in mine])
        score = -np.array([h.log_likelihood for h in mine])
        out += [mine[k] for k in distinct_poses(T[:, :3, :3], T[:, :3, 3], score, point, len(mine))]
    return out
