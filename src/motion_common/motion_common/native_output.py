"""Silencing what native libraries print straight to the process's file descriptors.

Some libraries' C/C++ code (pybullet's build-time banner, MediaPipe's TensorFlow Lite and
absl start-up warnings) writes to file descriptors 1 and 2 directly, where Python's
sys.stdout/sys.stderr cannot catch it. ``native_output_silenced`` points both descriptors
at /dev/null for a block: use it only around start-up calls whose output is known noise.
"""

import contextlib
import ctypes
import os
import sys

__all__ = ["native_output_silenced"]

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
