"""The next touch: the one whose outcome the current hypotheses disagree on most.

Candidate touches are points of the free surface of the most probable hypotheses (model
vertices placed by their poses, data frame), each approached along its inward normal
from ``standoff_m`` outside. Under every hypothesis h the approach line meets the surface
after a depth d_h (read off the models' signed distance fields), or not at all within the
travel. A touch's outcome is then a mixture of the predicted depths, each blurred by the
touch's noise sigma and weighted by its posterior w_h; its expected information gain, the
mutual information between outcome and hypothesis, is bounded below by the pairwise
Bhattacharyya bound (Kolchinsky and Tracey 2017):

    I >= -sum_i w_i log sum_j w_j exp(-(d_i - d_j)^2 / (8 sigma^2)),

exact when the predictions are far apart or equal; a miss counts as an outcome far from
every contact. The weights are the hypotheses' posteriors relative to their total, and
"none of these" (:attr:`Belief.unexplained`, counted at most ``MAX_NONE_WEIGHT``) is one
more outcome, a contact anywhere along the approach: a touch tests the hypotheses
against it even where they agree. The touch of greatest bound is chosen. Touches the
stylus cannot make (a surface tilted beyond ``max_tilt_rad`` from ``up``), below
``min_height_m`` (the table), too close to contact already made, occluded on the best
hypothesis or refused by the caller's ``reachable`` are never candidates.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.spatial import cKDTree

from recognition.errors import InvalidArgument
from recognition.surfaces.belief import Belief
from recognition.surfaces.distance import FieldStack
from recognition.surfaces.mesh_model import MeshModel

__all__ = [
    "TouchLimits",
    "TouchPlan",
    "information_gain",
    "plan_touch",
    "predicted_depths",
    "without_edges",
]

Array = NDArray[np.float64]

#: A predicted miss counts as a contact this far beyond the travel, metres.
MISS_DEPTH_M = 1.0
#: A touched part must be at least this thick along the approach, metres.
THICKNESS_M = 4.0e-3
#: Touches that outcomes this likely (relative to the likeliest) predict to miss are not
#: made while others tell the hypotheses apart (:func:`without_edges`).
LIKELY_WEIGHT = 0.05
#: Hypotheses less probable than this (of the hypotheses' total) are left out of a
#: touch's outcomes.
MIN_OUTCOME_WEIGHT = 1e-4
#: Hypotheses at least this probable (of the hypotheses' total) also show their pose's
#: uncertainty among the outcomes.
SPREAD_WEIGHT = 1e-3
#: "None of these" counts among a touch's outcomes at most this probable: beyond, the
#: touch serves the broader search its contact point joins, and still splits the
#: hypotheses.
MAX_NONE_WEIGHT = 0.5
#: A touch expected to gain less information than this (nats) is not made.
MIN_GAIN_NATS = 1e-3
#: A pose uncertain by more than this along a motion (metres at the data's reach) is
#: also represented by poses moved along it ...
SIGMA_FLOOR_M = 0.1e-3
#: ... by this many standard deviations either way.
SIGMA_SCALE = 1.5


@dataclass(frozen=True)
class TouchLimits:
    """What touches the sensor can make, data frame.

    Attributes
    ----------
    up : (3,) float
        Unit vector away from the table (the stylus's axis, pointing up).
    max_tilt_rad : float
        Largest angle between a touched surface's normal and ``up``.
    min_height_m : float
        Least height along ``up`` (from the data frame's origin) of a touched point: the
        table top plus a clearance.
    standoff_m : float
        The approach starts this far outside the predicted contact.
    travel_m : float
        ... and searches this far beyond it: hypotheses a few millimetres off disagree
        by as much about where a surface 20-30 mm from p lies, and a touch that meets the
        object, wherever along its approach, informs every later search where a miss
        pulls no pose.
    min_separation_m : float
        Least distance of a touch from contact already made.
    candidates : int
        Candidate touches drawn (split over the most probable hypotheses).
    scored : int
        Of the allowed ones, at most this many (drawn) are scored.
    reachable : callable or None
        ``reachable(starts (k, 3), directions (k, 3)) -> (k,) bool``: whether the robot
        can start there and move so (workspace, joint limits); None: everywhere.
    tip_radius_m, tool_radius_m, tool_length_m : float
        The sensor: a tip sphere on a straight shaft of this radius and length along
        ``up`` from the tip's centre. A touch is allowed only where, on the most probable
        hypothesis, the tip clears the surface (by ``clearance_m``) on its way down to the
        approach's start, and the shaft above the tip at the predicted contact clears it
        too (0: a point sensor, no check).
    clearance_m : float
    """

    up: Array
    max_tilt_rad: float = float(np.deg2rad(50.0))
    min_height_m: float = -np.inf
    standoff_m: float = 4.0e-3
    travel_m: float = 12.0e-3
    min_separation_m: float = 3.0e-3
    candidates: int = 1200
    scored: int = 300
    reachable: Callable[[Array, Array], NDArray[np.bool_]] | None = None
    tip_radius_m: float = 0.0
    tool_radius_m: float = 0.0
    tool_length_m: float = 0.0
    clearance_m: float = 0.5e-3

    def __post_init__(self) -> None:
        up = np.asarray(self.up, dtype=np.float64).reshape(-1)
        if up.shape != (3,) or not np.all(np.isfinite(up)) or np.linalg.norm(up) == 0:
            raise InvalidArgument(f"TouchLimits.up must be a non-zero 3-vector, got {self.up}")
        object.__setattr__(self, "up", up / np.linalg.norm(up))
        if not (0 < self.max_tilt_rad <= np.pi / 2):
            raise InvalidArgument("TouchLimits.max_tilt_rad must lie in (0, pi/2]")
        if not (self.standoff_m > 0 and self.travel_m > 0 and self.candidates > 0):
            raise InvalidArgument("TouchLimits: standoff, travel and candidates must be > 0")

    @property
    def depth_m(self) -> float:
        """Length of an approach: the standoff and the travel beyond, metres."""
        return self.standoff_m + self.travel_m


@dataclass(frozen=True)
class TouchPlan:
    """A planned touch, data frame.

    Attributes
    ----------
    point : (3,) float
        The contact the most probable hypothesis predicts, metres.
    direction : (3,) float
        Unit approach direction (into the surface).
    start : (3,) float
        Where the approach starts, ``standoff`` outside ``point``, metres.
    travel_m : float
        How far the approach may go from ``start``, metres.
    information_nats : float
        The expected information gain's lower bound (module docstring).
    depths_m : (K,) float
        Predicted depth of contact from ``start`` under each pose the touch was to tell
        apart (the hypotheses, with poses moved along their uncertain motions; NaN: no
        contact within the travel), metres.
    """

    point: Array
    direction: Array
    start: Array
    travel_m: float
    information_nats: float
    depths_m: Array


def predicted_depths(
    stack: FieldStack,
    which: NDArray[np.int64],
    poses: Array,
    starts: Array,
    directions: Array,
    length_m: float,
    step_m: float = 0.1e-3,
) -> Array:
    """Depth along each ray at which each posed model's surface is first met.

    ``which`` (H,) fields of ``stack``, ``poses`` (H, 4, 4) T_model_from_data; rays
    ``starts`` + s ``directions`` (C, 3), 0 <= s <= ``length_m``. Returns (H, C) depths
    in metres (linear between samples ``step_m`` apart; 0 when the start is inside; NaN
    when the ray meets nothing).
    """
    s = np.arange(0.0, length_m + step_m / 2, step_m)
    rays = starts[:, None, :] + s[None, :, None] * directions[:, None, :]  # (C, S, 3)
    out = np.full((len(poses), len(starts)), np.nan)
    for h, (field, T) in enumerate(zip(which, poses, strict=True)):
        X = rays.reshape(-1, 3) @ T[:3, :3].T + T[:3, 3]
        values = stack(X.reshape(len(starts), len(s), 3), np.full(len(starts), field))
        inside = values <= 0
        hit = inside.any(axis=1)
        first = np.argmax(inside, axis=1)
        prev = np.maximum(first - 1, 0)
        rows = np.arange(len(starts))
        v0, v1 = values[rows, prev], values[rows, first]
        frac = np.where(first > 0, v0 / np.maximum(v0 - v1, 1e-12), 0.0)
        depth = (prev + np.clip(frac, 0.0, 1.0) * (first > 0)) * step_m
        out[h] = np.where(hit, depth, np.nan)
    return out


def information_gain(
    depths: Array,
    weights: Array,
    sigma_m: float,
    none_weight: float = 0.0,
    window_m: float = 0.0,
) -> Array:
    """Lower bound of the expected information gain (nats) of each touch (module
    docstring): ``depths`` (H, C) predicted per hypothesis (NaN: a miss), ``weights``
    (H,) posteriors, ``sigma_m`` the touch's noise.

    With ``none_weight`` > 0, "none of these" is one more outcome, a contact anywhere
    along the approach's ``window_m``: its Bhattacharyya coefficient with a hypothesis's
    Gaussian contact there is sqrt(sigma sqrt(8 pi) / window) (0 against a predicted
    miss), so that a touch tests the hypotheses against it even where they agree.
    """
    from recognition.surfaces.planning_kernels import mixtures  # numba: when needed

    d = np.where(np.isnan(depths), MISS_DEPTH_M, depths)
    w = np.asarray(weights, float)
    none = none_weight if none_weight > 0 and window_m > 0 else 0.0
    total = np.sum(w) + none
    w, none = w / total, none / total
    mixture = mixtures(np.ascontiguousarray(d.T), w, 1.0 / (8.0 * sigma_m**2)).T  # (H, C)
    if none == 0:
        return np.asarray(-(w @ np.log(mixture)), dtype=np.float64)
    across = np.sqrt(min(sigma_m * np.sqrt(8.0 * np.pi) / window_m, 1.0))
    met = np.where(np.isnan(depths), 0.0, across)  # (H, C)
    gain = -(w @ np.log(mixture + none * met)) - none * np.log(w @ met + none)
    return np.asarray(gain, dtype=np.float64)


def without_edges(gain: Array, depths: Array, weights: Array) -> Array:
    """``gain`` (C,) with the touches that likely hypotheses (``weights`` (H,) at least
    ``LIKELY_WEIGHT`` of the likeliest's) predict to meet nothing (NaN in ``depths``
    (H, C)) set to -inf: such a touch is a guess at an edge, a miss pulls no pose, and the
    slightest error of them all turns a contact into one. Unless no other touch gains
    ``MIN_GAIN_NATS``: hypotheses far apart disagree only so (where a touch is planned,
    the most probable meets its own surface)."""
    likely = weights >= LIKELY_WEIGHT * weights.max()
    edge = np.isnan(depths[likely]).any(axis=0)
    if not np.any(~edge & (gain > MIN_GAIN_NATS)):
        return gain
    return np.where(edge, -np.inf, gain)


def _candidates(
    belief: Belief,
    models: Mapping[str, MeshModel],
    limits: TouchLimits,
    rng: np.random.Generator,
    clear_of: Array,
) -> tuple[Array, Array]:
    """Candidate touch points (k, 3) and outward normals (k, 3), data frame: vertices of the
    most probable hypotheses' models placed by their poses, within the limits and no
    nearer than ``limits.min_separation_m`` to the points ``clear_of`` (m, 3)."""
    top = [h for h in belief.hypotheses[:4] if h.posterior >= 0.01] or list(belief.hypotheses[:1])
    share = limits.candidates // len(top)
    points, normals = [], []
    for h in top:
        model = models[h.model]
        pick = rng.choice(len(model.vertices), size=min(share, len(model.vertices)), replace=False)
        R, t = h.T_model_from_data[:3, :3], h.T_model_from_data[:3, 3]
        points.append((model.vertices[pick] - t) @ R)  # R^T (v - t), row-wise
        normals.append(model.normals[pick] @ R)
    P, N = np.concatenate(points), np.concatenate(normals)
    keep = N @ limits.up >= np.cos(limits.max_tilt_rad)
    keep &= P @ limits.up >= limits.min_height_m
    if keep.any():
        near, _ = cKDTree(clear_of).query(P[keep])
        keep[np.flatnonzero(keep)[near < limits.min_separation_m]] = False
    return P[keep], N[keep]


def _tool_clear(
    stack: FieldStack,
    field: int,
    pose: Array,
    starts: Array,
    directions: Array,
    depths: Array,
    limits: TouchLimits,
) -> NDArray[np.bool_]:
    """Whether the sensor clears the posed model (``field``, T_model_from_data ``pose``)
    on each approach: the tip all the way down ``up`` to the start, the shaft above the
    tip at the predicted contact (``depths`` along ``directions`` from ``starts``)."""
    heights = np.linspace(0.0, limits.tool_length_m, 48)
    contact = starts + np.nan_to_num(depths, nan=0.0)[:, None] * directions
    out = np.ones(len(starts), bool)
    shaft_from = min(2 * limits.tip_radius_m, limits.tool_length_m)
    for base, lowest, radius in (
        (starts, 0.0, limits.tip_radius_m),
        (contact, shaft_from, limits.tool_radius_m),
    ):
        h = heights[heights >= lowest]
        X = base[:, None, :] + h[None, :, None] * limits.up
        X = X.reshape(-1, 3) @ pose[:3, :3].T + pose[:3, 3]
        values = stack(X.reshape(len(base), len(h), 3), np.full(len(base), field))
        out &= values.min(axis=1) >= radius + limits.clearance_m
    return out


def _outcomes(belief: Belief) -> tuple[list[str], Array, Array]:
    """The poses whose predicted contacts a touch should tell apart, with their weights:
    each hypothesis, and where its pose is uncertain by more than ``SIGMA_FLOOR_M`` (a
    slide along a nearly symmetric surface), its pose moved by +-``SIGMA_SCALE``
    standard deviations along its two most uncertain motions (the rotation scaled by the
    data's reach); the hypothesis's posterior split evenly among them. Weights are
    relative to the hypotheses' total. The most probable hypothesis's own pose comes
    first."""
    names: list[str] = []
    poses: list[Array] = []
    weights: list[float] = []
    total = sum(h.posterior for h in belief.hypotheses)
    for h in belief.hypotheses:
        share = h.posterior / total if total > 0 else 1.0 / len(belief.hypotheses)
        if share < MIN_OUTCOME_WEIGHT and poses:
            continue
        own = [h.T_model_from_data]
        if share >= SPREAD_WEIGHT:
            for sd, direction in belief.loose_motions(h):
                if sd < SIGMA_FLOOR_M:
                    break
                motion = SIGMA_SCALE * sd * direction
                own += [h.moved(motion), h.moved(-motion)]
        names += [h.model] * len(own)
        poses += own
        weights += [share / len(own)] * len(own)
    return names, np.array(poses), np.array(weights)


def plan_touch(
    belief: Belief,
    models: Mapping[str, MeshModel],
    stack: FieldStack,
    field_of: Mapping[str, int],
    limits: TouchLimits,
    *,
    seed: int = 0,
    avoid: ArrayLike | None = None,
    within_m: float | None = None,
    doubt: float = 0.0,
) -> TouchPlan | None:
    """The touch of greatest expected information gain (module docstring), or None when
    no candidate is allowed or none can tell the hypotheses apart.

    ``stack`` holds the models' distance fields, ``field_of`` maps a model name to its
    field in it. No touch is planned within ``limits.min_separation_m`` of contact made
    or of the points ``avoid`` (k, 3) (touches that gave no reading). With
    ``within_m``, only candidates within that distance of contact made are considered
    while there are any: where the hypotheses may all be wrong, the surface near the
    data is where a touch is sure to meet the object. ``doubt``: "none of these" counts
    at least this probable among the outcomes (a belief that a search, not a touch, made
    sure is tested by a touch first: the search chose the poses that fit the contact
    best, and a touch that the answer predicts sharply tells whether it also fits contact
    it has not seen). Same belief, seed, ``avoid``, ``within_m`` and ``doubt``, same
    plan.
    """
    if not belief.hypotheses:
        return None
    rng = np.random.default_rng(seed)
    near = belief.points
    if avoid is not None:
        near = np.concatenate([near, np.asarray(avoid, dtype=np.float64).reshape(-1, 3)])
    P, N = _candidates(belief, models, limits, rng, near)
    if within_m is not None and len(P):
        close = cKDTree(belief.points).query(P)[0] <= within_m
        if close.any():
            P, N = P[close], N[close]
    if not len(P):
        return None
    directions = -N
    starts = P - limits.standoff_m * directions
    if limits.reachable is not None:
        ok = np.asarray(limits.reachable(starts, directions), dtype=bool)
        P, directions, starts = P[ok], directions[ok], starts[ok]
        if not len(P):
            return None
    names, poses, weights = _outcomes(belief)
    which = np.array([field_of[n] for n in names], dtype=np.int64)
    # the most probable hypothesis must meet its own surface at the candidate: no
    # occluded approach, no grazing one
    own = predicted_depths(stack, which[:1], poses[:1], starts, directions, limits.depth_m)[0]
    clear = np.abs(own - limits.standoff_m) <= 0.5e-3
    # no thin parts (an ear, a tail, a fin): beyond the contact the model must stay
    # thick, or a pose a millimetre off makes the approach pass beside it
    inner = starts + (limits.standoff_m + THICKNESS_M) * directions
    inner = inner @ poses[0][:3, :3].T + poses[0][:3, 3]
    clear &= stack(inner[None], which[:1])[0] <= -0.5 * THICKNESS_M
    if limits.tool_length_m > 0:
        clear &= _tool_clear(stack, which[0], poses[0], starts, directions, own, limits)
    keep = np.flatnonzero(clear)
    if not keep.size:
        return None
    if keep.size > limits.scored:
        keep = np.sort(rng.choice(keep, size=limits.scored, replace=False))
    P, directions, starts = P[keep], directions[keep], starts[keep]
    others = predicted_depths(stack, which[1:], poses[1:], starts, directions, limits.depth_m)
    depths = np.concatenate([own[None, keep], others])
    sigma = belief.noise.point_sigma_m(belief.sensor_m)
    none = max(min(belief.unexplained, MAX_NONE_WEIGHT), doubt)
    gain = information_gain(depths, (1 - none) * weights, sigma, none, limits.depth_m)
    gain = without_edges(gain, depths, weights)
    k = int(np.argmax(gain))
    if not gain[k] > MIN_GAIN_NATS:
        return None
    return TouchPlan(
        P[k],
        directions[k],
        starts[k],
        limits.depth_m,
        float(gain[k]),
        depths[:, k],
    )
