"""Figures and plot of a teleop session: how well the tool followed the scaled hand path
and how long commands took from sensor to driver. Pure Python (numpy, matplotlib Agg)."""

import json
from collections import deque
from dataclasses import dataclass

import numpy as np

from .lag_estimate import trailing_lag
from .latency_stats import LatencyStats

#: Samples of each path a monitor keeps (about 3 minutes of a 110 Hz stream, ~13 MB in all):
#: a session that runs all day keeps bounded memory, and the tracking figures cover its last
#: window.
WINDOW_SAMPLES = 20_000


@dataclass
class SessionData:
    """What a monitor collected during a session (times in seconds, positions in metres),
    in bounded memory however long it runs.

    ``targets`` rows are (sensor stamp, x, y, z) of the mapped tool target (the scaled
    hand path in the robot base frame); ``tools`` rows are (stamp, x, y, z) of the measured
    tool; ``hands`` and ``raw_hands`` the same of the sequencer's filtered hand and the
    device's raw one, in the device frame. They keep the last ``window`` samples each; the
    counts, the hand path length and the latency figures (``LatencyStats``, exact to 10 us)
    cover the whole session.
    """

    frames_in: int = 0
    frames_out: int = 0
    frames_dropped: int = 0
    commands_refused: int = 0
    targets: deque = None
    tools: deque = None
    latencies: LatencyStats = None
    stage_latencies: tuple = None  # LatencyStats of (sequencer, core, driver), s
    hands: deque = None
    raw_hands: deque = None
    window: int = WINDOW_SAMPLES
    commands_sent: int = 0
    path_length: float = 0.0  # m of target path, the whole session

    def __post_init__(self):
        # Lists given to the constructor (tests, tools) are taken as the first samples.
        given_targets = list(self.targets or [])
        self.targets = deque(maxlen=self.window)
        for row in given_targets:
            self.add_target(row)
        for name in ("tools", "hands", "raw_hands"):
            setattr(self, name, deque(getattr(self, name) or [], maxlen=self.window))
        if not isinstance(self.latencies, LatencyStats):
            self.latencies = LatencyStats(self.latencies or [])
        rows = self.stage_latencies if self.stage_latencies is not None else []
        if not (isinstance(rows, tuple) and rows and all(isinstance(r, LatencyStats) for r in rows)):
            stages = (LatencyStats(), LatencyStats(), LatencyStats())
            for row in rows:
                for stage, value in zip(stages, row):
                    stage.append(value)
            self.stage_latencies = stages

    def add_target(self, row) -> None:
        """One command's target (stamp, x, y, z): counted, and the path length grows."""
        if self.targets:
            last = self.targets[-1]
            self.path_length += float(np.linalg.norm(np.subtract(row[1:], last[1:])))
        self.targets.append(tuple(row))
        self.commands_sent += 1

    def add_stage_latency(self, sequencer: float, core: float, driver: float) -> None:
        for stage, value in zip(self.stage_latencies, (sequencer, core, driver)):
            stage.append(value)


def tracking_errors(targets: np.ndarray, tools: np.ndarray) -> np.ndarray:
    """Distance (m) from each tool sample to the target interpolated at the same time.

    Only tool samples inside the span of the target stream count: before engage and after
    the last command there is nothing to follow.
    """
    if len(targets) < 2 or len(tools) == 0:
        return np.zeros(0)
    inside = (tools[:, 0] >= targets[0, 0]) & (tools[:, 0] <= targets[-1, 0])
    t = tools[inside, 0]
    wanted = np.column_stack([np.interp(t, targets[:, 0], targets[:, axis]) for axis in (1, 2, 3)])
    return np.linalg.norm(tools[inside, 1:] - wanted, axis=1)


def overshoot(targets: np.ndarray, tools: np.ndarray, prominence: float = 0.005) -> float:
    """Largest distance (m) the tool goes past an extremum of the commanded target.

    Per base axis, every maximum and minimum of the target with at least ``prominence``
    (m) is an extremum; the tool overshoots a maximum by how far it rises above the
    target's value there before the target's next extremum on that axis (a minimum: how
    far it falls below). The tool is allowed its lag: only going beyond counts. 0 when
    it never goes past.
    """
    from scipy.signal import find_peaks

    if len(targets) < 3 or len(tools) == 0:
        return 0.0
    worst = 0.0
    for axis in (1, 2, 3):
        values = targets[:, axis]
        maxima, _ = find_peaks(values, prominence=prominence)
        minima, _ = find_peaks(-values, prominence=prominence)
        extrema = sorted([(i, 1.0) for i in maxima] + [(i, -1.0) for i in minima])
        for k, (index, sign) in enumerate(extrema):
            start = targets[index, 0]
            end = targets[extrema[k + 1][0], 0] if k + 1 < len(extrema) else np.inf
            window = tools[(tools[:, 0] >= start) & (tools[:, 0] < end), axis]
            if len(window):
                worst = max(worst, float(np.max(sign * (window - values[index]))))
    return worst


def raw_hand_targets(targets: np.ndarray, hands: np.ndarray, raw_hands: np.ndarray) -> np.ndarray:
    """The raw (unfiltered) hand path mapped into the target's frame: rows (stamp, x, y, z).

    The teleop mapping is affine in position (reference offset, rotation, speed ratio)
    while engaged, so it is recovered by least squares from the filtered hand and the
    target at the same sensor stamps, and applied to the raw frames inside the targets'
    span. Tracking against this judges filters on what the operator did, not on their
    own output.
    """
    if len(targets) < 4 or len(hands) < 4 or len(raw_hands) == 0:
        return np.zeros((0, 4))
    order = np.argsort(hands[:, 0])
    hands = hands[order]
    inside = (targets[:, 0] >= hands[0, 0]) & (targets[:, 0] <= hands[-1, 0])
    t = targets[inside, 0]
    if len(t) < 4:
        return np.zeros((0, 4))
    filtered = np.column_stack([np.interp(t, hands[:, 0], hands[:, a]) for a in (1, 2, 3)] + [np.ones(len(t))])
    mapping, *_ = np.linalg.lstsq(filtered, targets[inside, 1:], rcond=None)
    raw = raw_hands[(raw_hands[:, 0] >= targets[0, 0]) & (raw_hands[:, 0] <= targets[-1, 0])]
    mapped = np.column_stack([raw[:, 1:], np.ones(len(raw))]) @ mapping
    return np.column_stack([raw[:, 0], mapped])


def hand_to_tool_ms(targets: np.ndarray, raw_hands: np.ndarray, tools: np.ndarray):
    """How far (ms) the measured tool trails the raw hand while engaged (the span of the
    targets): the delay of the affine map that best explains the tool path from the delayed
    hand path (lag_estimate). None when it cannot be told (a still hand, too few samples, or
    a tool that does not follow within 300 ms)."""
    if len(targets) < 2 or len(raw_hands) < 2 or len(tools) < 2:
        return None
    start, end = targets[0, 0], targets[-1, 0]
    hands = raw_hands[(raw_hands[:, 0] >= start) & (raw_hands[:, 0] <= end)]
    tools = tools[(tools[:, 0] >= start) & (tools[:, 0] <= end)]
    return trailing_lag(hands, tools)


def final_error(targets: np.ndarray, tools: np.ndarray) -> float:
    """Distance (m) between the last target and the last tool sample (settled error)."""
    if len(targets) == 0 or len(tools) == 0:
        return float("nan")
    return float(np.linalg.norm(tools[-1, 1:] - targets[-1, 1:]))


def summarize(data: SessionData) -> dict:
    """The session's figures as a JSON-ready dict (errors in mm, latencies in ms)."""
    targets = np.asarray(data.targets, dtype=float).reshape(-1, 4)
    tools = np.asarray(data.tools, dtype=float).reshape(-1, 4)
    errors = tracking_errors(targets, tools) * 1000.0
    raw_targets = raw_hand_targets(
        targets,
        np.asarray(data.hands, dtype=float).reshape(-1, 4),
        np.asarray(data.raw_hands, dtype=float).reshape(-1, 4),
    )
    raw_errors = tracking_errors(raw_targets, tools) * 1000.0
    settled = final_error(targets, tools)

    def pct(values, q):
        return round(float(np.percentile(values, q)), 3) if len(values) else None

    def ms(stats, q):
        value = stats.percentile(q)
        return None if value is None else round(value * 1000.0, 3)

    return {
        "frames_in": data.frames_in,
        "frames_out": data.frames_out,
        "frames_dropped": data.frames_dropped,
        "commands_sent": data.commands_sent,
        "commands_refused": data.commands_refused,
        "hand_path_length_mm": round(data.path_length * 1000.0, 1),
        "tracking_error_rms_mm": round(float(np.sqrt(np.mean(errors**2))), 3) if len(errors) else None,
        "tracking_error_p95_mm": pct(errors, 95),
        "tracking_error_max_mm": round(float(errors.max()), 3) if len(errors) else None,
        "final_error_mm": round(settled * 1000.0, 3) if np.isfinite(settled) else None,
        "overshoot_mm": round(overshoot(targets, tools) * 1000.0, 3),
        "hand_to_tool_ms": hand_to_tool_ms(targets, np.asarray(data.raw_hands, dtype=float).reshape(-1, 4), tools),
        "raw_tracking_error_rms_mm": round(float(np.sqrt(np.mean(raw_errors**2))), 3) if len(raw_errors) else None,
        "raw_tracking_error_p95_mm": pct(raw_errors, 95),
        "latency_p50_ms": ms(data.latencies, 50),
        "latency_p99_ms": ms(data.latencies, 99),
        "latency_samples": len(data.latencies),
        "stage_latency_ms": _stage_figures(data.stage_latencies),
        "window_samples": data.window,
    }


def _stage_figures(stages):
    """p50/p99 (ms) of each stage's cumulative latency from the sensor stamp."""
    if not len(stages[0]):
        return {}
    return {
        name: {"p50": round(stage.percentile(50) * 1000.0, 3), "p99": round(stage.percentile(99) * 1000.0, 3)}
        for stage, name in zip(stages, ("sequencer", "core", "driver"))
    }


def session_failure(summary: dict, max_refused_fraction: float) -> str:
    """Why a finished session did not do its job, or "" when it did: no hand frame, no
    command reaching the robot, or more than ``max_refused_fraction`` of the commands
    refused (a start pose that does not fit the robot, a workspace too small...)."""
    if summary["frames_in"] == 0:
        return "no hand frame arrived from the device"
    sent, refused = summary["commands_sent"], summary["commands_refused"]
    if sent == 0:
        return "no command was sent to the robot: the clutch never engaged"
    if refused > max_refused_fraction * sent:
        return (
            f"{refused} of {sent} commands were refused ({refused / sent:.0%}, more than {max_refused_fraction:.0%}); "
            "the log above says why (e.g. JOINT_LIMIT_MARGIN, IK_FAILED): check the robot's start pose "
            "(robot_config:=) and workspace"
        )
    return ""


def format_summary(summary: dict, plot_path: str = "") -> str:
    """Human-readable summary block for the end of a run."""

    def show(value, unit):
        return "n/a" if value is None else f"{value} {unit}"

    lines = [
        "=== teleop session summary ===",
        f"frames in (device)       : {summary['frames_in']}",
        f"frames out (sequencer)   : {summary['frames_out']}",
        f"frames dropped           : {summary['frames_dropped']}",
        f"commands sent / refused  : {summary['commands_sent']} / {summary['commands_refused']}",
        f"hand path (scaled)       : {summary['hand_path_length_mm']} mm",
        f"tracking error rms / p95 / max : {show(summary['tracking_error_rms_mm'], 'mm')} / "
        f"{show(summary['tracking_error_p95_mm'], 'mm')} / {show(summary['tracking_error_max_mm'], 'mm')}",
        f"tracking vs raw hand rms / p95 : {show(summary.get('raw_tracking_error_rms_mm'), 'mm')} / "
        f"{show(summary.get('raw_tracking_error_p95_mm'), 'mm')}",
        f"overshoot at reversals   : {show(summary.get('overshoot_mm'), 'mm')}",
        f"hand to tool (delay)     : {show(summary.get('hand_to_tool_ms'), 'ms')}",
        f"final error (settled)    : {show(summary['final_error_mm'], 'mm')}",
        f"latency sensor->driver p50 / p99 : {show(summary['latency_p50_ms'], 'ms')} / "
        f"{show(summary['latency_p99_ms'], 'ms')} ({summary['latency_samples']} commands)",
    ]
    for stage, figures in summary.get("stage_latency_ms", {}).items():
        lines.append(f"  sensor->{stage:<9} p50 / p99 : {figures['p50']} ms / {figures['p99']} ms")
    if plot_path:
        lines.append(f"plot                     : {plot_path}")
    return "\n".join(lines)


def plot_session(data: SessionData, path: str, title: str = "teleop session") -> str:
    """Write a PNG of the scaled hand path against the tool path; return its path."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    targets = np.asarray(data.targets, dtype=float).reshape(-1, 4)
    tools = np.asarray(data.tools, dtype=float).reshape(-1, 4)
    t0 = targets[0, 0] if len(targets) else (tools[0, 0] if len(tools) else 0.0)
    if len(targets):  # show the tool only around the commanded span
        tools = tools[(tools[:, 0] >= t0 - 0.5) & (tools[:, 0] <= targets[-1, 0] + 1.0)]
    fig = plt.figure(figsize=(12, 7))
    grid = fig.add_gridspec(3, 2, width_ratios=[1.4, 1])
    for axis, name in enumerate("xyz"):
        ax = fig.add_subplot(grid[axis, 0])
        if len(targets):
            ax.plot(targets[:, 0] - t0, targets[:, axis + 1] * 1000, label="hand path (scaled, robot frame)", lw=1.5)
        if len(tools):
            ax.plot(tools[:, 0] - t0, tools[:, axis + 1] * 1000, "--", label="tool path (simulated arm)", lw=1.2)
        ax.set_ylabel(f"{name} [mm]")
        ax.grid(alpha=0.3)
        if axis == 0:
            if len(targets) or len(tools):
                ax.legend(loc="best", fontsize=8)
            ax.set_title(title)
    ax.set_xlabel("time since engage [s]")
    top = fig.add_subplot(grid[:, 1])
    if len(targets):
        top.plot(targets[:, 1] * 1000, targets[:, 2] * 1000, label="hand path (scaled)")
    if len(tools):
        top.plot(tools[:, 1] * 1000, tools[:, 2] * 1000, "--", label="tool path")
    top.set_xlabel("x [mm]")
    top.set_ylabel("y [mm]")
    top.set_title("top view (robot base frame)")
    top.axis("equal")
    top.grid(alpha=0.3)
    if len(targets) or len(tools):
        top.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path


def write_summary_json(summary: dict, path: str) -> None:
    """Write the summary dict as JSON."""
    with open(path, "w", encoding="utf-8") as fh:
        json.dump(summary, fh, indent=2, sort_keys=True)
