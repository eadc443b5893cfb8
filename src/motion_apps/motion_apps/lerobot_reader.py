"""Reads a dataset back with LeRobot's own loader (``LeRobotDataset``), offline, and writes
what it got into one ``.npz`` the framework's venv can open (run in ``.venv-lerobot``):

    python lerobot_reader.py DATASET OUT.npz [--episodes 0,2] [--video] [--repo-id ID]

Keys: ``meta`` (JSON: fps, episodes, frames, features, tasks, the loader's video backend,
LeRobot's version), and per episode ``e<N>/<feature>`` (stacked, as LeRobot returns them:
float32 numbers, video frames as float32 CHW in 0..1 with ``--video``), ``e<N>/task``.
Used by the round-trip test, ``replay_episode`` and ``scripts/record_demo``; see
``read_dataset`` for the caller's side.
"""

import argparse
import json
import os
import sys

os.environ.setdefault("HF_HUB_OFFLINE", "1")
os.environ.setdefault("HF_DATASETS_OFFLINE", "1")

import numpy as np  # noqa: E402

__all__ = ["main"]


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("dataset")
    parser.add_argument("out")
    parser.add_argument("--episodes", default="", help="comma-separated episode indices (default: all)")
    parser.add_argument("--video", action="store_true", help="decode the camera frames too")
    parser.add_argument("--repo-id", default="local/dataset")
    args = parser.parse_args(argv)

    import lerobot  # noqa: PLC0415 - heavy (torch)
    from lerobot.datasets.lerobot_dataset import LeRobotDataset  # noqa: PLC0415

    root = os.path.realpath(args.dataset)
    if not os.path.isdir(os.path.join(root, "meta")):
        print(f"{args.dataset}: not a LeRobot dataset (no meta/)", file=sys.stderr)
        return 2
    wanted = [int(e) for e in args.episodes.split(",") if e.strip()] or None
    dataset = LeRobotDataset(args.repo_id, root=root, episodes=wanted)
    video_keys = list(dataset.meta.video_keys)
    numeric = [k for k, f in dataset.features.items() if f["dtype"] not in ("video", "image", "string")]
    columns = dataset.hf_dataset.with_format("numpy")
    episode_column = np.asarray(columns["episode_index"])
    out = {}
    for episode in sorted(set(episode_column.tolist())):
        rows = np.flatnonzero(episode_column == episode)
        for key in numeric:
            out[f"e{episode}/{key}"] = np.stack([np.asarray(v) for v in columns[key][rows[0] : rows[-1] + 1]])
        task_index = int(np.asarray(columns["task_index"])[rows[0]])
        out[f"e{episode}/task"] = np.array(dataset.meta.tasks.index[task_index])
        if args.video and video_keys:
            first = int(np.flatnonzero(np.asarray(columns["index"]) >= 0)[0])
            positions = [int(np.flatnonzero(episode_column == episode)[i]) for i in range(len(rows))]
            frames = {k: [] for k in video_keys}
            for position in positions:
                item = dataset[position - first if wanted else position]
                for key in video_keys:
                    frames[key].append(item[key].numpy())
            for key in video_keys:
                out[f"e{episode}/{key}"] = np.stack(frames[key]).astype(np.float32)
    meta = {
        "fps": dataset.fps,
        "episodes": dataset.meta.total_episodes,
        "frames": dataset.meta.total_frames,
        "features": dataset.features,
        "video_keys": video_keys,
        "video_backend": dataset.video_backend,
        "lerobot_version": getattr(lerobot, "__version__", ""),
    }
    out["meta"] = np.array(json.dumps(meta, default=str))
    temp = args.out + ".tmp.npz"
    np.savez(temp, **out)
    os.replace(temp, args.out)
    return 0


if __name__ == "__main__":
    sys.exit(main())
