"""Atomic file writes: the content goes to a temporary file beside the target, is flushed to disk (fsync) and
renamed onto the target with `os.replace`, so a reader sees the old file or the new one, never a part of one,
and a killed writer leaves the target as it was.

The temporary file is `.<target name>.<random>.<pid>.tmp<suffix>` in the target's directory (a rename is atomic
only within one file system): hidden, unique per call (two processes or two threads writing the same target
never share one; the name is reserved with O_EXCL) and naming the writing process, so that a cleaner can tell a
live write from a killed one's leftover (`writer_pid`; `policies.run_dir.RunDir.clean_stale`). It is removed
when the write fails. No maintained library does this (atomicwrites is archived).
"""

from __future__ import annotations

import contextlib
import os
import re
import uuid
from pathlib import Path
from typing import Iterator

TEMP_GLOB = ".*.tmp"
"""A glob matching the temporary files written without a suffix (`write_atomic`, `atomic_path(path)`)."""

_TEMP_NAME = re.compile(r"^\..+\.(\d+)\.tmp(\.[^.]*)?$")


def writer_pid(name: str) -> int | None:
    """The id of the process that writes the temporary file `name`, or None if the name is not one
    (`.<name>.<pid>.tmp` of earlier versions included)."""
    match = _TEMP_NAME.match(name)
    return int(match.group(1)) if match else None


def _reserve(path: Path, suffix: str) -> Path:
    """Create an empty temporary file for `path` under a name no other call uses; returns its path."""
    while True:
        tmp = path.with_name(f".{path.name}.{uuid.uuid4().hex[:12]}.{os.getpid()}.tmp{suffix}")
        try:
            os.close(os.open(tmp, os.O_CREAT | os.O_EXCL | os.O_WRONLY, 0o666))  # the umask applies, as with open()
            return tmp
        except FileExistsError:  # practically never: another call drew the same random part
            continue


def _fsync(path: Path) -> None:
    fd = os.open(path, os.O_RDWR)
    try:
        os.fsync(fd)
    finally:
        os.close(fd)


@contextlib.contextmanager
def atomic_path(path: str | Path, suffix: str = "") -> Iterator[Path]:
    """A temporary path beside `path` for a writer that takes a file name (np.savez, torch.onnx.export, ...).

    When the block ends normally the file is fsynced and renamed onto `path`; when it raises, the temporary file is
    removed and `path` is left as it was (so a block may also check what was written and raise to keep the old
    file). `suffix` ends the temporary name, for writers that need one (np.savez appends ".npz" to any other name).
    The parent directory must exist."""
    path = Path(path)
    tmp = _reserve(path, suffix)
    try:
        yield tmp
        _fsync(tmp)
        os.replace(tmp, path)
    except BaseException:
        tmp.unlink(missing_ok=True)
        raise


def write_atomic(path: str | Path, data: bytes | str) -> Path:
    """Write `data` (text is encoded as UTF-8) to `path` atomically (see the module docstring); returns `path`."""
    path = Path(path)
    with atomic_path(path) as tmp, open(tmp, "wb") as f:
        f.write(data.encode() if isinstance(data, str) else data)
    return path
