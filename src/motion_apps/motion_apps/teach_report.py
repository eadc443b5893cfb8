"""The teach demo's result: placement error, summary JSON and the taught-path plot (no ROS).

``placement_error`` compares, in the table plane (base x, y), where the part lies after the
program's replay with the taught place pose: the tool position of the program's
``release`` waypoint (the suction cup holds the part under the tool).
"""

import json
import os

import numpy as np

from motion_commander.program import Program
from motion_common.atomic_file import write_atomic


def taught_place(program: Program) -> np.ndarray | None:
    """Tool position (m) of the last ``release`` waypoint, or None without one."""
    releases = [w for w in program.waypoints if w.action == "release"]
    return np.asarray(releases[-1].position, dtype=float) if releases else None


def placement_error(program: Program, part_position) -> float | None:
    """Table-plane distance (m) from the taught place to the part, or None (no release)."""
    place = taught_place(program)
    if place is None:
        return None
    return float(np.linalg.norm(np.asarray(part_position, dtype=float)[:2] - place[:2]))


def write_summary(path: str, summary: dict) -> str:
    """Write ``summary`` as JSON atomically (temp file, fsync, rename); return the path."""
    return write_atomic(path, json.dumps(summary, indent=2) + "\n")


def format_summary(summary: dict) -> str:
    """The lines printed at the end of the demo."""
    error = summary.get("placement_error_mm")
    lines = [
        "=== teach demo summary ===",
        f"gestures recognised      : {summary['gestures_recognised']} ({', '.join(summary['gesture_names'])})",
        f"teach commands done      : {summary['commands_understood']}",
        f"waypoints taught         : {summary['waypoints']}",
        f"program                  : {summary['program']}",
        f"replay                   : {summary['replay_result']} ({summary['replay_waypoints_done']}/"
        f"{summary['waypoints']} waypoints, {summary['replay_seconds']:.1f} s)",
        "placement error          : " + ("n/a (no release taught)" if error is None else f"{error:.2f} mm"),
        f"plot                     : {summary.get('plot', '')}",
    ]
    return "\n".join(lines)


def plot_taught_path(
    path: str,
    tool_path: list[tuple],
    program: Program,
    part_start=None,
    part_end=None,
    title: str = "taught pick-and-place",
) -> str:
    """PNG: the tool's path while teaching (top view and height over time) with the taught
    waypoints marked (grip / release highlighted) and the part before and after the replay."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    samples = np.array(tool_path, dtype=float).reshape(-1, 4)
    waypoints = np.array([w.position for w in program.waypoints], dtype=float).reshape(-1, 3)
    figure, (top, height) = plt.subplots(1, 2, figsize=(12, 5))
    if len(samples):
        top.plot(samples[:, 1] * 1000, samples[:, 2] * 1000, color="0.6", lw=1, label="tool while teaching")
        height.plot(samples[:, 0] - samples[0, 0], samples[:, 3] * 1000, color="0.6", lw=1, label="tool z")
    labels = {}  # waypoints stacked above each other (above, at, grip) share one label
    for index, waypoint in enumerate(program.waypoints):
        marker, color = {"grip": ("v", "tab:red"), "release": ("^", "tab:green")}.get(
            waypoint.action, ("o", "tab:blue")
        )
        top.scatter(waypoint.position[0] * 1000, waypoint.position[1] * 1000, marker=marker, color=color, zorder=3)
        key = tuple(np.round(np.asarray(waypoint.position[:2]) * 1000 / 5))  # 5 mm cells
        labels.setdefault(key, (waypoint.position, []))[1].append(str(index))
    for position, indices in labels.values():
        top.annotate(
            ",".join(indices),
            (position[0] * 1000, position[1] * 1000),
            textcoords="offset points",
            xytext=(6, 4),
            fontsize=8,
        )
    if len(waypoints):
        top.plot(
            waypoints[:, 0] * 1000,
            waypoints[:, 1] * 1000,
            color="tab:blue",
            lw=1.5,
            alpha=0.6,
            label="program (waypoints: o move, v grip, ^ release)",
        )
    if part_start is not None:
        top.scatter(
            part_start[0] * 1000,
            part_start[1] * 1000,
            marker="s",
            s=80,
            facecolors="none",
            edgecolors="k",
            label="part at start",
        )
    if part_end is not None:
        top.scatter(
            part_end[0] * 1000, part_end[1] * 1000, marker="s", s=80, color="goldenrod", label="part after the replay"
        )
    top.set_xlabel("x (mm, base frame)")
    top.set_ylabel("y (mm)")
    top.set_title("top view")
    # A square window around everything drawn: true proportions, and room for the labels.
    drawn = [samples[:, 1:3]] if len(samples) else []
    drawn += [waypoints[:, :2]] if len(waypoints) else []
    drawn += [np.asarray(p, dtype=float)[None, :2] for p in (part_start, part_end) if p is not None]
    if drawn:
        xy = np.vstack(drawn) * 1000
        centre, half = (xy.max(axis=0) + xy.min(axis=0)) / 2, np.ptp(xy, axis=0).max() / 2 + 40
        top.set_xlim(centre[0] - half, centre[0] + half)
        top.set_ylim(centre[1] - half, centre[1] + half)
    top.set_aspect("equal", adjustable="box")
    top.legend(fontsize=8, loc="upper center", bbox_to_anchor=(0.5, -0.12), ncol=2)
    height.set_xlabel("time while teaching (s)")
    height.set_ylabel("tool z (mm)")
    height.set_title("height")
    figure.suptitle(title)
    figure.tight_layout()
    os.makedirs(os.path.dirname(os.path.abspath(path)), exist_ok=True)
    figure.savefig(path, dpi=100)
    plt.close(figure)
    return path
