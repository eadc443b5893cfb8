"""Ending a hand-started ``roslaunch`` session cleanly once its report is written.

roslaunch ends a launch when a ``required`` node exits, but prints a red "REQUIRED process
has died" banner even when all went well. A finishing node (the session monitor, the teach
demo, the kitting campaign) instead asks the roslaunch that started it to stop, as Ctrl-C
does: ``end_parent_roslaunch`` sends SIGINT to its parent process when that process is
roslaunch, and does nothing otherwise (scripts/run_session, rostest, a user's own parent).
"""

import os
import signal

__all__ = ["end_parent_roslaunch"]


def _cmdline(pid: int) -> list[str]:
    try:
        with open(f"/proc/{pid}/cmdline", "rb") as stream:
            return [part.decode(errors="replace") for part in stream.read().split(b"\0") if part]
    except OSError:
        return []


def end_parent_roslaunch(parent=os.getppid, cmdline=_cmdline, kill=os.kill) -> bool:
    """SIGINT to the parent process if it runs roslaunch; True when sent."""
    pid = parent()
    words = cmdline(pid)
    if pid <= 1 or not any(os.path.basename(word) == "roslaunch" for word in words[:2]):
        return False
    kill(pid, signal.SIGINT)
    return True
