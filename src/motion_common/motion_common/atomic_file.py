"""Atomic file writes: a file a user saves (a program, a template, a summary) is either the
old one or the new one, never truncated or mixed, even if the process is killed mid-write
or the power fails."""

import os
import re
import tempfile
import time

__all__ = ["write_atomic", "remove_stale_temp_files", "STALE_TEMP_AGE_S"]

# A temporary file older than this was left by a writer that was killed: no live save takes
# that long (they are fsynced small files), so removing it cannot race a save in progress.
STALE_TEMP_AGE_S = 60.0


def _current_umask() -> int:
    """The process umask, read without changing it (os.umask would race other threads)."""
    try:
        with open("/proc/self/status", encoding="ascii") as status:
            for line in status:
                if line.startswith("Umask:"):
                    return int(line.split()[1], 8)
    except OSError:
        pass
    return 0o022


def _temp_pattern(name: str):
    return re.compile(r"^\." + re.escape(name) + r"\.[A-Za-z0-9_]+\.tmp$")


def remove_stale_temp_files(
    folder: str, name: str = "", older_than_s: float = STALE_TEMP_AGE_S, now: float = None
) -> list:
    """Remove the temporary files that killed writers of ``write_atomic`` left in ``folder``
    (``.NAME.XXXX.tmp``; of one file ``name``, or of every file when empty) once they are
    older than ``older_than_s``; return the paths removed. A missing folder removes nothing."""
    now = time.time() if now is None else now
    pattern = _temp_pattern(name) if name else re.compile(r"^\..+\.[A-Za-z0-9_]+\.tmp$")
    removed = []
    try:
        entries = list(os.scandir(folder))
    except OSError:
        return removed
    for entry in entries:
        if not pattern.match(entry.name) or not entry.is_file(follow_symlinks=False):
            continue
        try:
            if now - entry.stat(follow_symlinks=False).st_mtime >= older_than_s:
                os.unlink(entry.path)
                removed.append(entry.path)
        except OSError:
            continue  # another process removed or replaced it: nothing left to clean
    return removed


def write_atomic(path: str, text) -> str:
    """Write ``text`` (str, or bytes such as a PNG) to ``path`` atomically; return the
    absolute path.

    The text goes to a temporary file in the same folder (same file system), is flushed and
    fsynced, then renamed over ``path`` (os.replace); the folder is fsynced so the rename
    itself survives a power cut. On any failure the temporary file is removed and the old
    file is left as it was; one a killed process left is removed by the next save of the
    same file once it is STALE_TEMP_AGE_S old.
    """
    path = os.path.abspath(path)
    folder = os.path.dirname(path)
    os.makedirs(folder, exist_ok=True)
    # What an earlier, killed save of this file left behind goes now.
    remove_stale_temp_files(folder, os.path.basename(path))
    fd, temp = tempfile.mkstemp(prefix="." + os.path.basename(path) + ".", suffix=".tmp", dir=folder)
    try:
        # mkstemp makes the file owner-only; a saved program or template is a normal file.
        os.fchmod(fd, 0o666 & ~_current_umask())
        binary = isinstance(text, (bytes, bytearray))
        with os.fdopen(fd, "wb") if binary else os.fdopen(fd, "w", encoding="utf-8") as stream:
            stream.write(text)
            stream.flush()
            os.fsync(stream.fileno())
        os.replace(temp, path)
    except BaseException:
        if os.path.exists(temp):
            os.unlink(temp)
        raise
    try:
        dir_fd = os.open(folder, os.O_RDONLY)
    except OSError:  # pragma: no cover - platforms without directory file descriptors
        return path
    try:
        os.fsync(dir_fd)
    finally:
        os.close(dir_fd)
    return path
