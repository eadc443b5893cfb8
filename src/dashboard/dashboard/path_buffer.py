"""The hand path (mapped into the robot base frame: /motion_commander/target) and the tool
path (/motion_controller/tool_pose), kept short and thinned for the page's plot."""

from collections import deque

__all__ = ["PathBuffer"]


class PathBuffer:
    """Two bounded paths of (t, x, y, z); a point closer than ``min_interval_s`` in time to
    the last kept one of its path is skipped, so a 100 Hz stream costs the plot 20 Hz."""

    NAMES = ("hand", "tool")

    def __init__(self, max_points: int = 400, min_interval_s: float = 0.05):
        if max_points < 2 or min_interval_s < 0:
            raise ValueError("PathBuffer needs max_points >= 2 and min_interval_s >= 0")
        self.min_interval_s = min_interval_s
        self._paths = {name: deque(maxlen=max_points) for name in self.NAMES}

    def add(self, name: str, t: float, position) -> bool:
        """Add a point to path ``name``; return whether it was kept."""
        path = self._paths[name]
        if path and t - path[-1][0] < self.min_interval_s:
            return False
        x, y, z = (float(v) for v in position)
        path.append((float(t), x, y, z))
        return True

    def clear(self) -> None:
        """Forget both paths (e.g. the operator's 'clear plot')."""
        for path in self._paths.values():
            path.clear()

    def series(self) -> dict[str, list[list[float]]]:
        """Top view for the plot: name -> [[x, y], ...] in mm, oldest first."""
        return {name: [[1000.0 * p[1], 1000.0 * p[2]] for p in path] for name, path in self._paths.items()}

    def points(self, name: str) -> list[list[float]]:
        """Path ``name`` in 3-D for the robot view: [[x, y, z], ...] in m, oldest first."""
        return [[p[1], p[2], p[3]] for p in self._paths[name]]
