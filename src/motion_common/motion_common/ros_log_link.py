"""A race-free ``latest`` link in the ROS log directory.

Every rospy node (and roslaunch) points ``<log dir>/latest`` at the run's folder as it
starts: rosgraph removes the old link, then creates the new one. A session starts its nodes
at the same moment, so two of them often collide between the two steps and one prints
"INFO: cannot create a symlink to latest log directory: [Errno 17] File exists" on every run.
``install()`` gives rosgraph a replacement that swaps the link atomically (a new link under
a unique name, then rename), which cannot collide. Importing motion_common.ros_interface
installs it, so every node of this framework does before ``rospy.init_node``.
"""

import os

__all__ = ["install", "renew_latest_link"]


def renew_latest_link(logfile_dir: str) -> bool:
    """Point ``<parent of logfile_dir>/latest`` at ``logfile_dir`` atomically; False when
    something other than a link is in the way (rosgraph's contract)."""
    latest = os.path.join(os.path.dirname(logfile_dir), "latest")
    if os.path.lexists(latest) and not os.path.islink(latest):
        return False
    temporary = f"{latest}.{os.getpid()}.tmp"
    if os.path.lexists(temporary):
        os.remove(temporary)
    os.symlink(logfile_dir, temporary)
    os.replace(temporary, latest)
    return True


def install() -> None:
    """Use ``renew_latest_link`` in rosgraph's logging set-up (idempotent)."""
    import rosgraph.roslogging

    rosgraph.roslogging.renew_latest_logdir = renew_latest_link
