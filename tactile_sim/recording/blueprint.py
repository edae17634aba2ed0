"""The first view of a probing recording: the 3D scene, the stylus signals, the recognition."""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import ArrayLike

if TYPE_CHECKING:
    import rerun.blueprint as rrb

__all__ = [
    "probe_blueprint",
]


def probe_blueprint(target_in_world: ArrayLike | None = None) -> rrb.Blueprint:
    """Returns the recording's first view: the 3D scene, the stylus signals, the log, and
    the recognition (models with candidates, ranking).

    Parameters
    ----------
    target_in_world : (3,) float or None, metres
        Where the 3D camera looks (the probed point); None: rerun's default framing.
    """
    import rerun.blueprint as rrb

    history = [
        rrb.VisibleTimeRange(
            timeline,
            start=rrb.TimeRangeBoundary.infinite(),
            end=rrb.TimeRangeBoundary.cursor_relative(),
        )
        for timeline in ("step", "sim_time")
    ]
    eye = None
    if target_in_world is not None:
        target = np.asarray(target_in_world, dtype=np.float64)
        eye = rrb.EyeControls3D(position=target + np.array([0.07, -0.10, 0.08]), look_target=target)
    return rrb.Blueprint(
        rrb.Horizontal(
            rrb.Spatial3DView(
                origin="world", name="probing", time_ranges=history, eye_controls=eye
            ),
            rrb.Vertical(
                rrb.TimeSeriesView(origin="sensors/deflection", name="stylus deflection"),
                rrb.TimeSeriesView(origin="sensors/force", name="tip force"),
                rrb.Tabs(
                    rrb.Spatial3DView(origin="recognition/models", name="recognition"),
                    rrb.TextDocumentView(origin="recognition/ranking", name="ranking"),
                    rrb.TextLogView(origin="log", name="log"),
                ),
            ),
            column_shares=[3, 2],
        ),
        rrb.BlueprintPanel(state="collapsed"),
        rrb.SelectionPanel(state="collapsed"),
        rrb.TimePanel(timeline="sim_time"),
    )
