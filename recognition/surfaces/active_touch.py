"""Verification touches: touch where the hypotheses disagree most, until the answer is sure.

After the three curves, :func:`verify` repeats: plan the touch of greatest expected
information gain (:func:`~recognition.surfaces.touch_planning.plan_touch`), make it
(``touch``: the robot, or a ray cast on a known surface in a benchmark; its contact point,
with the surface normal when the sensor gives one), refine and re-score every hypothesis
with all the contact (:meth:`Belief.with_contacts`). When no hypothesis explains the
contact any more, when a touch has made the belief sure, and after the touches when it is
not, the curves and the touches' contact points are searched again more broadly
(:meth:`~recognition.surfaces.database.ModelDatabase.broaden`, at most once per touch):
poses the first search never proposed, but which fit all the contact as well (or better:
the hypotheses may all be wrong and still explain the contact), compete before an answer
is called sure or given. The last two may end the touches, with no touch left to test a
rival: they keep every pose their pair search refines (``ModelDatabase.broaden(...,
final=True)``). After a touch that met nothing, or while no hypothesis explains the
contact, the next touch is planned near the contact made (``LOST_WITHIN_M``), where the
object surely is, when a touch there can tell the hypotheses apart. A belief that the
broader search before a touch made sure is tested by that touch (planned with "none of
these" counted ``MAX_NONE_WEIGHT`` probable among its outcomes): the search chose the
poses that fit the contact best, and a pose so chosen may fit what it was chosen on and
nothing else. It stops once a touch leaves the belief's confidence (:attr:`Belief.
confidence`) at ``confidence`` or above, the touches are spent, or no allowed touch can
tell the hypotheses apart. A belief that is sure after the curves makes no touch.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass, replace

import numpy as np
from numpy.typing import NDArray

from recognition.errors import InvalidArgument
from recognition.surfaces.belief import Belief
from recognition.surfaces.database import ModelDatabase
from recognition.surfaces.touch_planning import MAX_NONE_WEIGHT, TouchLimits, TouchPlan

__all__ = [
    "BROADEN_AT",
    "LOST_WITHIN_M",
    "Contact",
    "NoReading",
    "TouchStep",
    "Verification",
    "verify",
]

Array = NDArray[np.float64]

#: When "none of these" is at least this probable, the search is broadened
#: (:meth:`~recognition.surfaces.database.ModelDatabase.broaden`) before the next touch.
BROADEN_AT = 0.5
#: After a touch that met nothing, or while "none of these" is at least ``BROADEN_AT``
#: probable, the next touch is planned within this distance of the contact made (the
#: curves' points and the touches'), where the object surely is, when a touch there can
#: tell the hypotheses apart: the hypotheses that placed the missed touch may all be
#: wrong, and a contact pairs with p for the broader search, a miss does not.
LOST_WITHIN_M = 8.0e-3


@dataclass(frozen=True)
class Contact:
    """What a touch sensed, data frame.

    Attributes
    ----------
    point : (3,) float
        The contact point, metres.
    normal : (3,) float or None
        The outward unit surface normal there, when the sensor gives one.
    """

    point: Array
    normal: Array | None = None


@dataclass(frozen=True)
class NoReading:
    """What a touch that met something returns when its reading is not the tip's contact
    (e.g. the force ran across the stylus: its shaft, not its tip, touched): the belief
    is not updated.

    Attributes
    ----------
    reason : str
        What the sensor saw, in words.
    """

    reason: str


@dataclass(frozen=True)
class TouchStep:
    """One verification touch.

    Attributes
    ----------
    plan : TouchPlan
    contact : (3,) float or None
        The sensed contact point, data frame, metres (None: nothing met within the travel,
        or no reading, see ``no_reading``).
    normal : (3,) float or None
        The sensed outward normal there, data frame (None: none sensed).
    confidence : float
        The best hypothesis's posterior after the update.
    best_model : str or None
        The best hypothesis's model after the update.
    recognition_time_s : float
        Planning and updating, seconds (the touch itself excluded; the last touch's
        includes the broader search after it).
    belief : Belief
        The belief after the update.
    no_reading : str or None
        Why the touch gave no contact to trust (:class:`NoReading`; the belief was not
        updated); None: it gave one, or met nothing.
    """

    plan: TouchPlan
    contact: Array | None
    confidence: float
    best_model: str | None
    recognition_time_s: float
    belief: Belief
    normal: Array | None = None
    no_reading: str | None = None


@dataclass(frozen=True)
class Verification:
    """The belief after the verification loop and its touches.

    Attributes
    ----------
    belief : Belief
    steps : tuple of TouchStep
    initial_confidence : float
        Confidence after the curves alone.
    stop : str
        Why the loop ended: ``"sure"``, ``"touches spent"`` or ``"no informative touch"``.
    broaden_s : float
        Time of the broader searches (:meth:`ModelDatabase.broaden`), seconds (also in
        the recognition time of the touch it preceded or, after the last, followed).
    """

    belief: Belief
    steps: tuple[TouchStep, ...]
    initial_confidence: float
    stop: str
    broaden_s: float = 0.0


def verify(
    database: ModelDatabase,
    belief: Belief,
    touch: Callable[[TouchPlan], Contact | NoReading | Array | None],
    limits: TouchLimits,
    *,
    max_touches: int = 5,
    confidence: float = 0.99,
    seed: int = 0,
) -> Verification:
    """Touch until sure (module docstring).

    Parameters
    ----------
    database : ModelDatabase
        The models the belief's hypotheses name.
    belief : Belief
        After the curves (:attr:`Recognition.belief`).
    touch : callable
        ``touch(plan) -> Contact`` (or its (3,) point alone) in the data frame, None (no
        contact within ``plan.travel_m`` of ``plan.start`` along ``plan.direction``), or
        :class:`NoReading` (a contact, but not one of the tip to trust).
    limits : TouchLimits
    max_touches : int
        At most this many touches (0: none, the thesis's behaviour).
    confidence : float
        Stop once the belief's confidence (:attr:`Belief.confidence`) reaches this.
    seed : int
        Seeds the candidate touches (same seed, same plans).
    """
    if isinstance(max_touches, bool) or not isinstance(max_touches, int) or max_touches < 0:
        raise InvalidArgument(f"max_touches must be an integer >= 0, got {max_touches!r}")
    if not 0 < confidence <= 1:
        raise InvalidArgument(f"confidence must lie in (0, 1], got {confidence!r}")
    initial = belief.confidence
    steps: list[TouchStep] = []
    stop = "touches spent"
    broaden_s = 0.0
    avoid = np.zeros((0, 3))  # where touches gave no reading: none is planned near them
    missed = False  # the last touch met nothing
    for k in range(max_touches):
        if belief.confidence >= confidence:
            stop = "sure"
            break
        start = time.perf_counter()
        doubt = 0.0
        if belief.unexplained >= BROADEN_AT:
            belief = database.broaden(belief)
            broaden_s += time.perf_counter() - start
            if belief.confidence >= confidence:  # made sure by the search: a touch tests it
                doubt = MAX_NONE_WEIGHT
        plan = None
        if missed or belief.unexplained >= BROADEN_AT:
            plan = database.plan_touch(
                belief, limits, seed=seed + k, avoid=avoid, within_m=LOST_WITHIN_M, doubt=doubt
            )
        if plan is None:  # not lost, or no touch near the contact tells anything
            plan = database.plan_touch(belief, limits, seed=seed + k, avoid=avoid, doubt=doubt)
        planned = time.perf_counter() - start
        if plan is None:
            stop = "no informative touch"
            break
        sensed = touch(plan)
        start = time.perf_counter()
        no_reading, contact = None, None
        if isinstance(sensed, NoReading):
            no_reading = sensed.reason
            avoid = np.concatenate([avoid, plan.point[None]])
        else:
            contact = sensed if sensed is None or isinstance(sensed, Contact) else Contact(sensed)
            missed = contact is None
            if contact is None:
                belief = database.update(
                    belief, misses=[(plan.start, plan.direction, plan.travel_m)]
                )
            else:
                normal = np.full(3, np.nan) if contact.normal is None else contact.normal
                belief = database.update(
                    belief,
                    np.asarray(contact.point, float)[None],
                    windows=[plan.travel_m],
                    normals=np.asarray(normal, float)[None],
                )
            if belief.confidence >= confidence:
                # sure after a touch: first look elsewhere for poses that fit all the contact
                # (thoroughly: a sure answer ends the touches)
                searched = time.perf_counter()
                belief = database.broaden(belief, final=True)
                broaden_s += time.perf_counter() - searched
        best = belief.best
        steps.append(
            TouchStep(
                plan,
                None if contact is None else np.asarray(contact.point, float),
                belief.confidence,
                None if best is None else best.model,
                planned + time.perf_counter() - start,
                belief,
                None if contact is None or contact.normal is None else belief.normals[-1],
                no_reading,
            )
        )
    if belief.confidence >= confidence:
        stop = "sure"
    elif steps and len(belief.windows):
        # not sure after the touches: a last look for poses that fit all the contact, the
        # belief judging every pose the pair search refines (its time counted with the
        # last touch's)
        start = time.perf_counter()
        belief = database.broaden(belief, final=True)
        searched = time.perf_counter() - start
        broaden_s += searched
        steps[-1] = replace(steps[-1], recognition_time_s=steps[-1].recognition_time_s + searched)
        if belief.confidence >= confidence:
            stop = "sure"
    return Verification(belief, tuple(steps), initial, stop, broaden_s)
