"""pybullet without its console chatter.

pybullet's C code prints "pybullet build time: ..." on import and "argv[0]=" on connect,
straight to the process's file descriptors (the first to stderr): every session console then
shows lines that look like diagnostics and mean nothing. Python's sys.stdout cannot catch C
output, so the descriptors themselves point at /dev/null for the import and each connect
(start-up only: nothing else of the process prints then; Python's buffers are flushed
before, C's before the descriptors are restored).
"""

import contextlib
import ctypes
import os
import sys

__all__ = ["native_output_silenced", "pybullet", "connect", "bullet_client"]


_LIBC = ctypes.CDLL(None)


@contextlib.contextmanager
def native_output_silenced():
    """File descriptors 1 and 2 go to /dev/null inside the block (C-level prints included);
    a Python exception raised inside still propagates, and is printed after the block."""
    sys.stdout.flush()
    sys.stderr.flush()
    saved = [os.dup(1), os.dup(2)]
    try:
        with open(os.devnull, "wb") as devnull:
            os.dup2(devnull.fileno(), 1)
            os.dup2(devnull.fileno(), 2)
        yield
    finally:
        # What was printed inside, still in Python's or C's buffers, goes to /dev/null too.
        sys.stdout.flush()
        sys.stderr.flush()
        _LIBC.fflush(None)
        for fd, copy in zip((1, 2), saved):
            os.dup2(copy, fd)
            os.close(copy)


with native_output_silenced():
    import pybullet
    from pybullet_utils import bullet_client as _bullet_client


def connect(mode, *args, **kwargs) -> int:
    """pybullet.connect, silently."""
    with native_output_silenced():
        return pybullet.connect(mode, *args, **kwargs)


def bullet_client(mode):
    """A pybullet_utils BulletClient connected with ``mode``, silently."""
    with native_output_silenced():
        return _bullet_client.BulletClient(connection_mode=mode)
