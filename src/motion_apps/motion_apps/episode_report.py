"""A recorded dataset's summary (episodes, frames, fps, size, outcomes) and the picture of one
episode: a strip of its camera frames above its joint traces (measured and commanded).
Plain Python (matplotlib's Agg backend); the data comes from ``lerobot_readback``."""

import os

import numpy as np

__all__ = ["dataset_size_bytes", "summarize_dataset", "velocity_agreement", "format_summary", "plot_episode"]


def dataset_size_bytes(dataset: str) -> int:
    """Bytes of the dataset's current version (the link followed; hard links counted once)."""
    seen, total = set(), 0
    for folder, _, files in os.walk(os.path.realpath(dataset)):
        for name in files:
            info = os.stat(os.path.join(folder, name))
            if (info.st_dev, info.st_ino) not in seen:
                seen.add((info.st_dev, info.st_ino))
                total += info.st_size
    return total


def summarize_dataset(dataset: str, meta: dict, records: list) -> dict:
    """The summary of a dataset read back by LeRobot (``meta``) and its episode records."""
    return {
        "dataset": os.path.abspath(dataset),
        "episodes": meta["episodes"],
        "frames": meta["frames"],
        "fps": meta["fps"],
        "size_mb": round(dataset_size_bytes(dataset) / 1e6, 2),
        "cameras": meta.get("video_keys", []),
        "video_backend": meta.get("video_backend", ""),
        "lerobot_version": meta.get("lerobot_version", ""),
        "successes": sum(1 for r in records if r.get("success")),
        "camera_loss_fraction": [r.get("camera_loss_fraction") for r in records],
        "dropped_frames": sum(int(r.get("dropped_frames", 0)) for r in records),
    }


def velocity_agreement(episode: dict, fps: float, moving: float = 0.05) -> dict:
    """How the recorded joint velocities agree with the rate of the recorded joint
    positions (central differences at the frame rate), over the frames where some joint
    moves faster than ``moving`` rad/s: the RMS of each, and the least-squares gain of the
    velocities on that rate (1: the same; 0: velocities missing)."""
    state = np.asarray(episode["observation.state"], dtype=float)
    velocity = np.asarray(episode["observation.velocity"], dtype=float)
    joints = velocity.shape[1]
    if len(state) < 3:
        return {"moving_frames": 0, "velocity_rms": None, "state_rate_rms": None, "gain": None}
    rate = (state[2:, :joints] - state[:-2, :joints]) * fps / 2.0
    recorded = velocity[1:-1]
    keep = np.abs(rate).max(axis=1) > moving
    if not keep.any():
        return {"moving_frames": 0, "velocity_rms": None, "state_rate_rms": None, "gain": None}
    rate, recorded = rate[keep], recorded[keep]
    return {
        "moving_frames": int(keep.sum()),
        "velocity_rms": round(float(np.sqrt(np.mean(recorded**2))), 4),
        "state_rate_rms": round(float(np.sqrt(np.mean(rate**2))), 4),
        "gain": round(float(np.sum(recorded * rate) / np.sum(rate * rate)), 3),
    }


def format_summary(summary: dict) -> str:
    lines = [
        "=== recorded dataset ===",
        f"dataset                  : {summary['dataset']}",
        f"episodes                 : {summary['episodes']} ({summary['successes']} successful)",
        f"frames                   : {summary['frames']} at {summary['fps']} fps",
        f"size                     : {summary['size_mb']} MB",
        f"cameras                  : {', '.join(summary['cameras']) or 'none'}",
        f"frames dropped           : {summary['dropped_frames']}",
    ]
    losses = [f"{100 * v:.1f} %" for v in summary["camera_loss_fraction"] if v is not None]
    if losses:
        lines.append(f"camera frames not new    : {', '.join(losses)} (per episode)")
    if "replay" in summary:
        r = summary["replay"]
        if r.get("tool_error_mm_max") is not None:
            lines.append(
                f"replay of episode {r['episode']}       : tool error p50 {r['tool_error_mm_p50']:.2f} mm, "
                f"max {r['tool_error_mm_max']:.2f} mm ({'within' if r['within_tolerance'] else 'over'} "
                f"{r['tolerance_mm']:g} mm)"
            )
        else:
            lines.append(f"replay of episode {r.get('episode')}       : {r.get('reason') or 'not run'}")
    return "\n".join(lines)


def plot_episode(path: str, episode: dict, fps: float, title: str, strip: int = 6) -> str:
    """PNG of one episode: ``strip`` camera frames, then joints (measured solid, commanded
    dashed) over time; returns ``path``."""
    import matplotlib  # noqa: PLC0415 - only when plotting

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt  # noqa: PLC0415

    from motion_common.atomic_file import write_atomic  # noqa: PLC0415

    cameras = [k for k in episode if k.startswith("observation.images.")]
    state, action = episode["observation.state"], episode["action"]
    t = np.arange(len(state)) / fps
    rows = 2 if cameras else 1
    fig = plt.figure(figsize=(12, 7 if cameras else 4))
    if cameras:
        frames = episode[cameras[0]]
        picks = np.linspace(0, len(frames) - 1, strip).round().astype(int)
        for i, index in enumerate(picks):
            ax = fig.add_subplot(rows, strip, i + 1)
            ax.imshow(np.clip(frames[index].transpose(1, 2, 0), 0, 1))
            ax.set_title(f"{index / fps:.1f} s", fontsize=9)
            ax.axis("off")
    ax = fig.add_subplot(rows, 1, rows)
    colours = plt.rcParams["axes.prop_cycle"].by_key()["color"]
    for j in range(state.shape[1] - 1):
        colour = colours[j % len(colours)]
        ax.plot(t, state[:, j], color=colour, label=f"joint {j + 1}")
        ax.plot(t, action[:, j], color=colour, linestyle="--", linewidth=0.8)
    ax.step(t, state[:, -1], where="post", color="k", linewidth=1.5, label="gripper (1 closed)")
    ax.set_xlabel("time (s)")
    ax.set_ylabel("rad")
    ax.legend(loc="upper right", fontsize=8, ncol=4)
    ax.grid(alpha=0.3)
    fig.suptitle(title + "  (solid: measured, dashed: commanded)")
    fig.tight_layout()
    import io  # noqa: PLC0415

    buffer = io.BytesIO()
    fig.savefig(buffer, format="png", dpi=90)
    plt.close(fig)
    write_atomic(path, buffer.getvalue())
    return path
