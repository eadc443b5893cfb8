"""The framework's side of ``lerobot_reader``: reads a dataset with LeRobot's own loader in
``.venv-lerobot`` and returns what it got as NumPy arrays."""

import json
import os
import subprocess
import tempfile

import numpy as np

from .episode_writer_client import LEROBOT_PYTHON, WriterError

__all__ = ["read_dataset", "READER_SCRIPT"]

READER_SCRIPT = os.path.join(os.path.dirname(os.path.realpath(__file__)), "lerobot_reader.py")


def read_dataset(dataset: str, episodes=None, video: bool = False, python: str = LEROBOT_PYTHON, timeout_s=600):
    """(meta, {episode: {feature: array, "task": str}}) of ``dataset`` as LeRobot loads it."""
    if not os.path.exists(python):
        raise WriterError(f"{python} is missing: LeRobot is installed by `scripts/setup --datasets`")
    env = dict(os.environ, HF_HUB_OFFLINE="1", HF_DATASETS_OFFLINE="1", OMP_NUM_THREADS="1")
    env.pop("PYTHONPATH", None)
    with tempfile.TemporaryDirectory(prefix="lerobot-read-") as folder:
        out = os.path.join(folder, "dataset.npz")
        command = [python, READER_SCRIPT, dataset, out]
        if episodes is not None:
            command += ["--episodes", ",".join(str(int(e)) for e in episodes)]
        if video:
            command.append("--video")
        done = subprocess.run(command, capture_output=True, text=True, env=env, timeout=timeout_s, check=False)
        if done.returncode != 0:
            raise WriterError(f"LeRobot could not read {dataset}:\n" + "\n".join(done.stderr.splitlines()[-12:]))
        with np.load(out) as data:
            meta = json.loads(str(data["meta"]))
            result = {}
            for key in data.files:
                if key == "meta":
                    continue
                episode, feature = key.split("/", 1)
                value = data[key]
                result.setdefault(int(episode[1:]), {})[feature] = str(value) if feature == "task" else value
    return meta, result
