"""Files written whole or not at all (a temporary file in the same folder, then a rename),
and paths checked writable before the work that writes them."""

from __future__ import annotations

import errno
import hashlib
import json
import os
import tempfile
from collections.abc import Callable
from pathlib import Path
from typing import IO, Any

import numpy as np

__all__ = ["array_checksum", "check_writable", "write_atomic", "write_json_atomic"]


def write_atomic(path: str | os.PathLike[str], writer: Callable[[IO[bytes]], object]) -> Path:
    """Writes ``path`` through ``writer`` (given the open binary file) into a temporary
    file beside it, then renames it into place (readable by all, as a plain file): a
    reader never sees a partial file, and a failure leaves the old one. Returns the path.
    """
    path = Path(path)
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=f".{path.name}-", suffix=".tmp")
    except OSError as exc:
        # name the file asked for, not the temporary one
        raise _naming(exc, f"cannot write {path}") from exc
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


def check_writable(path: str | os.PathLike[str], *, directory: bool = False) -> None:
    """Checks, before any work, that ``path`` can be written: a file (replaced if it
    exists), or with ``directory`` a directory to hold files; either may not exist yet.
    Creates nothing but a temporary file in the nearest existing directory, removed at once.

    Raises
    ------
    OSError
        ``IsADirectoryError`` (a file asked for, a directory there), ``NotADirectoryError``
        (a file in the way), ``PermissionError`` or another: the message names the path.
    """
    path = Path(path)
    if directory and path.exists() and not path.is_dir():
        raise NotADirectoryError(errno.ENOTDIR, f"{path} is a file; expected a directory")
    if not directory and path.is_dir():
        raise IsADirectoryError(errno.EISDIR, f"{path} is a directory; expected a file")
    if not directory and path.exists() and not os.access(path, os.W_OK):
        raise PermissionError(errno.EACCES, f"{path} is read-only")
    target = path if directory else path.parent
    existing = target
    while not existing.exists():
        existing = existing.parent
    if not existing.is_dir():
        raise NotADirectoryError(
            errno.ENOTDIR, f"cannot create {target}: {existing} is a file, not a directory"
        )
    try:
        fd, tmp = tempfile.mkstemp(dir=existing, prefix=".write-check-")
    except OSError as exc:
        raise _naming(exc, f"cannot write in {existing}") from exc
    os.close(fd)
    os.unlink(tmp)


def _naming(exc: OSError, what: str) -> OSError:
    """``exc`` again (same class and errno), its message saying ``what`` failed."""
    return type(exc)(exc.errno, f"{what}: {exc.strerror or exc}")
