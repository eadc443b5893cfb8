"""Atomic file writes: a file a user saves (a program, a template, a summary) is either the
old one or the new one, never truncated or mixed, even if the process is killed mid-write
or the power fails."""
import os
import tempfile


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


def write_atomic(path: str, text) -> str:
    """Write ``text`` (str, or bytes such as a PNG) to ``path`` atomically; return the
    absolute path.

    The text goes to a temporary file in the same folder (same file system), is flushed and
    fsynced, then renamed over ``path`` (os.replace); the folder is fsynced so the rename
    itself survives a power cut. On any failure the temporary file is removed and the old
    file is left as it was.
    """
    path = os.path.abspath(path)
    folder = os.path.dirname(path)
    os.makedirs(folder, exist_ok=True)
    fd, temp = tempfile.mkstemp(prefix="." + os.path.basename(path) + ".", suffix=".tmp", dir=folder)
    try:
        # mkstemp makes the file owner-only; a saved program or template is a normal file.
        os.fchmod(fd, 0o666 & ~_current_umask())
        binary = isinstance(text, (bytes, bytearray))
        with (os.fdopen(fd, "wb") if binary else os.fdopen(fd, "w", encoding="utf-8")) as stream:
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
