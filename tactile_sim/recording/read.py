"""Reading a recording file back: what entities and rows it holds, or why it is broken."""

from __future__ import annotations

import warnings
from dataclasses import dataclass
from pathlib import Path

from tactile_sim.errors import InvalidRecording

__all__ = [
    "RecordingSummary",
    "read_recording",
]


@dataclass(frozen=True)
class RecordingSummary:
    """What a recording file holds.

    Attributes
    ----------
    path : Path
    application_id : str
    rows : dict of str to int
        Rows logged on a timeline, per entity path (leading "/" dropped).
    static : frozenset of str
        Entity paths with static data.
    has_blueprint : bool
        The file stores a blueprint.
    """

    path: Path
    application_id: str
    rows: dict[str, int]
    static: frozenset[str]
    has_blueprint: bool

    @property
    def entities(self) -> frozenset[str]:
        """Returns every entity path with data."""
        return frozenset(self.rows) | self.static


def read_recording(path: str | Path) -> RecordingSummary:
    """Reads a recording file back (``rerun.chunk.RrdReader``) and summarises it.

    Raises
    ------
    InvalidRecording
        The file is missing (or a directory), not an .rrd file, truncated (no footer, or a chunk cut
        short) or holds no recording.
    """
    from rerun.chunk import RrdReader

    path = Path(path)
    if path.is_dir():
        raise InvalidRecording(f"{path} is a directory; expected an .rrd recording file")
    if not path.is_file():
        raise InvalidRecording(f"no recording at {path}: the file does not exist")
    try:
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            reader = RrdReader(path)
            recordings = reader.recordings()
            blueprints = reader.blueprints()
            if not recordings:
                raise InvalidRecording(f"{path} holds no recording (an empty or blueprint file)")
            rows: dict[str, int] = {}
            static: set[str] = set()
            for chunk in reader.stream():
                entity = chunk.entity_path.lstrip("/")
                if chunk.is_static:
                    static.add(entity)
                else:
                    rows[entity] = rows.get(entity, 0) + chunk.num_rows
    except (RuntimeError, ValueError, OSError) as error:
        if isinstance(error, InvalidRecording):
            raise
        reason = str(error).splitlines()[0].split(f"{path}: ", 1)[-1]
        raise InvalidRecording(f"{path} is truncated or not an .rrd recording: {reason}") from error
    if any("footer" in str(w.message) for w in caught):
        raise InvalidRecording(
            f"{path} is truncated: it has no footer (the writer did not finish; record it again)"
        )
    return RecordingSummary(
        path=path,
        application_id=str(recordings[0].application_id),
        rows=rows,
        static=frozenset(static),
        has_blueprint=bool(blueprints),
    )
