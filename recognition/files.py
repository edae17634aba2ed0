"""Files written whole or not at all: a temporary file in the same folder, then a rename."""

from __future__ import annotations

import hashlib
import json
import os
import tempfile
from collections.abc import Callable
from pathlib import Path
from typing import IO, Any

import numpy as np

__all__ = ["array_checksum", "write_atomic", "write_json_atomic"]


def write_atomic(path: str | os.PathLike[str], writer: Callable[[IO[bytes]], object]) -> Path:
    """Writes ``path`` through ``writer`` (given the open binary file) into a temporary
    file beside it, then renames it into place (readable by all, as a plain file): a
    reader never sees a partial file, and a failure leaves the old one. Returns the path.
    """
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=f".{path.name}-", suffix=".tmp")
    try:
        with os.fdopen(fd, "wb") as f:
            writer(f)
        os.chmod(tmp, 0o644)
        os.replace(tmp, path)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise
    return path


def write_json_atomic(path: str | os.PathLike[str], payload: Any, indent: int = 2) -> Path:
    """Writes ``payload`` as JSON to ``path`` atomically (:func:`write_atomic`)."""
    text = json.dumps(payload, indent=indent) + "\n"
    return write_atomic(path, lambda f: f.write(text.encode()))


def array_checksum(arrays: dict[str, np.ndarray]) -> str:
    """Hex SHA-256 of the named arrays' dtypes, shapes and bytes, in name order."""
    digest = hashlib.sha256()
    for name in sorted(arrays):
        array = np.ascontiguousarray(arrays[name])
        digest.update(f"{name}:{array.dtype.str}:{array.shape};".encode())
        digest.update(array.tobytes())
    return digest.hexdigest()
