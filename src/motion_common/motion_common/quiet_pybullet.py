"""pybullet without its console chatter.

pybullet's C code prints "pybullet build time: ..." on import and "argv[0]=" on connect,
straight to the process's file descriptors (the first to stderr): every session console then
shows lines that look like diagnostics and mean nothing. Python's sys.stdout cannot catch C
output, so the descriptors themselves point at /dev/null for the import and each connect
(``native_output``; start-up only: nothing else of the process prints then).
"""

from .native_output import native_output_silenced

__all__ = ["pybullet", "connect", "bullet_client"]


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
