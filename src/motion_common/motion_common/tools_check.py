"""Optional external programs a launch argument needs, checked before anything starts.

``rviz:=true`` on a machine without RViz used to fail only when roslaunch reached the rviz
node, after the rest of the session was already up. A pre-flight check calls
``missing_tool_message`` for each program the chosen arguments need and refuses the launch
with its message. Plain Python (``shutil.which``), no ROS import, so it is unit-tested
without a roscore.
"""

import shutil

__all__ = ["DEBIAN_PACKAGES", "missing_tool_message"]

# Program on PATH -> the Debian package that installs it (the framework's ROS comes from
# Debian's archive, so apt is the one install route to suggest).
DEBIAN_PACKAGES = {
    "rviz": "rviz",
    "xvfb-run": "xvfb",
}


def missing_tool_message(tool: str, which=shutil.which) -> str | None:
    """Return ``None`` when ``tool`` is on PATH, else the one-line refusal naming the
    install command, e.g. ``"rviz is not installed: sudo apt-get install rviz"``.

    ``which`` is ``shutil.which`` unless a test passes its own lookup."""
    if which(tool) is not None:
        return None
    package = DEBIAN_PACKAGES.get(tool, tool)
    return f"{tool} is not installed: sudo apt-get install {package}"
