"""Asset locations and the content-keyed, atomically written cache of generated assets.

Recipes are read from ``<repo>/assets/objects/``. Generated assets go under
``<repo>/assets/generated/``, or under the directory named by the environment variable
``TACTILE_ASSETS_DIR`` when it is set (read on every call). The generated directory
holds a ``.gitignore`` that ignores everything in it.

Every cache file is named after the hash of everything it was made from, written to a
temporary file in the same directory and moved into place with ``os.replace``, and
carries a checksum of its arrays: a file that is missing, unreadable, corrupt or made
from other inputs is rebuilt, never trusted.
"""

from __future__ import annotations

import contextlib
import json
import os
import sys
import zipfile
import zlib
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import numpy as np

from recognition.files import array_checksum, write_atomic

__all__ = [
    "ENV_ASSETS_DIR",
    "array_checksum",
    "build_lock",
    "generated_dir",
    "read_npz",
    "recipes_dir",
    "write_npz_atomic",
]

#: Environment variable overriding the generated-assets directory.
ENV_ASSETS_DIR = "TACTILE_ASSETS_DIR"

_REPO_ASSETS = Path(__file__).resolve().parents[2] / "assets"


def recipes_dir() -> Path:
    """Directory of the object recipe JSON files."""
    return _REPO_ASSETS / "objects"


def generated_dir(kind: str) -> Path:
    """Directory for generated assets of one kind (e.g. ``"objects"``), created if missing."""
    override = os.environ.get(ENV_ASSETS_DIR)
    root = Path(override).expanduser() if override else _REPO_ASSETS / "generated"
    path = root / kind
    path.mkdir(parents=True, exist_ok=True)
    ignore = root / ".gitignore"
    if not ignore.exists():
        with contextlib.suppress(OSError):
            ignore.write_text("# Generated assets: rebuilt on demand, never committed.\n*\n")
    return path


def write_npz_atomic(path: Path, arrays: dict[str, np.ndarray], meta: dict[str, Any]) -> None:
    """Write arrays and a JSON metadata dict (plus the arrays' checksum) to ``path`` atomically.

    Parameters
    ----------
    path : Path
        Destination ``.npz`` file.
    arrays : dict of str to ndarray
        Numeric arrays (no object dtype).
    meta : dict
        JSON-serialisable metadata, stored as the string array ``meta``.
    """
    _REPORTED.discard(path)
    meta = {**meta, "checksum": array_checksum(arrays)}
    payload = {**arrays, "meta": np.array(json.dumps(meta, sort_keys=True))}
    write_atomic(path, lambda handle: np.savez_compressed(handle, **payload))


def read_npz(path: Path, names: tuple[str, ...]) -> tuple[dict[str, np.ndarray], dict] | None:
    """Arrays ``names`` and the metadata of a cache file; None if missing or damaged.

    A file whose arrays do not match the checksum stored with them is damaged; a damaged
    file is reported in one line on stderr (the caller builds it again).
    """
    try:
        with np.load(path, allow_pickle=False) as data:
            arrays = {name: data[name] for name in names}
            meta = json.loads(str(data["meta"]))
    except FileNotFoundError:
        return None
    except (OSError, KeyError, ValueError, EOFError, zipfile.BadZipFile, zlib.error) as exc:
        _damaged(path, f"{type(exc).__name__}: {exc}")
        return None
    if not isinstance(meta, dict) or meta.get("checksum") != array_checksum(arrays):
        _damaged(path, "its arrays do not match their checksum")
        return None
    return arrays, meta


#: Damaged files already reported (a cache is read twice around its build lock).
_REPORTED: set[Path] = set()


def _damaged(path: Path, why: str) -> None:
    if path not in _REPORTED:
        _REPORTED.add(path)
        why = " ".join(why.split())
        print(f"tactile_sim: {path} is damaged ({why}); building it again", file=sys.stderr)


def is_triangle_arrays(vertices: np.ndarray, faces: np.ndarray) -> bool:
    """True if ``vertices`` is (n, 3) float and ``faces`` (m, 3) integer (a cached mesh)."""
    return (
        vertices.ndim == 2
        and vertices.shape[1:] == (3,)
        and faces.ndim == 2
        and faces.shape[1:] == (3,)
        and np.issubdtype(vertices.dtype, np.floating)
        and np.issubdtype(faces.dtype, np.integer)
    )


@contextlib.contextmanager
def build_lock(path: Path) -> Iterator[None]:
    """Hold an exclusive lock on ``path`` (a lock file) while building what it guards.

    Parallel processes (e.g. test workers) that need the same asset then build it once;
    the others wait and read the cache. Without ``fcntl`` (Windows) this does nothing.
    """
    try:
        import fcntl
    except ImportError:
        yield
        return
    with open(path, "a") as handle:
        fcntl.flock(handle, fcntl.LOCK_EX)
        try:
            yield
        finally:
            fcntl.flock(handle, fcntl.LOCK_UN)
