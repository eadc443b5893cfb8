"""Episodes written with LeRobot's own writer (in .venv-lerobot) and read back with LeRobot's
own loader, offline: shapes, rate and values (numbers exact to float32, camera frames within
the codec's tolerance); and a real kill -9 of the writer in the middle of an episode, which
loses that episode only.

Both start LeRobot's venv (a torch import, seconds each); scripts/setup --test installs it.
"""

import os
import signal

import numpy as np
import pytest

from motion_apps.dataset_store import DatasetStore
from motion_apps.episode_frames import EpisodeFrames, camera_key
from motion_apps.episode_recorder import EpisodeRecorder, read_episode_list
from motion_apps.episode_writer_client import LEROBOT_PYTHON, EpisodeWriterClient
from motion_apps.lerobot_readback import read_dataset

JOINTS = [f"joint_{i}" for i in range(6)]
W, H = 64, 48
FPS = 10

pytestmark = pytest.mark.skipif(
    not os.path.exists(LEROBOT_PYTHON) and not os.environ.get("CI"),
    reason="LeRobot's venv is missing: scripts/setup --datasets (CI always has it: --test)",
)


def _image(step: int) -> np.ndarray:
    """A smooth gradient with a bright bar that moves 3 px a frame (codec-friendly, yet each
    frame distinct)."""
    x = np.linspace(0, 200, W, dtype=np.float32)
    img = np.repeat(np.repeat(x[None, :, None], H, 0), 3, 2)
    img[:, :, 1] = np.linspace(0, 120, H, dtype=np.float32)[:, None]
    col = (step * 3) % (W - 8)
    img[:, col : col + 8, :] = 255
    return img.astype(np.uint8)


def _feed(frames: EpisodeFrames, rng, step: int) -> None:
    frames.on_joints(JOINTS, rng.normal(size=6), rng.normal(size=6))
    frames.on_tool(rng.normal(size=3), [0.0, 0.0, 0.0, 1.0])
    frames.on_gripper(step % 2 == 0)
    frames.on_hand(True, rng.normal(size=3), [0.0, 0.0, 0.0, 1.0], rng.uniform(), rng.uniform())
    frames.on_command(JOINTS, rng.normal(size=6), rng.normal(size=6))
    frames.on_target(rng.normal(size=3), [0.0, 0.0, 0.0, 1.0])
    frames.on_image(_image(step))


def _record(recorder, frames, rng, n, sent):
    ok, why = recorder.start()
    assert ok, why
    episode = []
    for step in range(n):
        _feed(frames, rng, step)
        before = frames.counts.frames
        recorder.tick()
        if frames.counts.frames > before:
            episode.append({k: np.array(v, copy=True) for k, v in frames.sample_last.items()})
    sent.append(episode)


class _Keeping(EpisodeFrames):
    """EpisodeFrames that keeps the last frame it made, for the comparison."""

    def sample(self):
        frame = super().sample()
        if frame is not None:
            self.sample_last = frame
        return frame


def _recorder(tmp_path, frames):
    return EpisodeRecorder(
        frames,
        lambda: EpisodeWriterClient(timeout_s=180),
        str(tmp_path / "demo_set"),
        "local/demo_set",
        FPS,
        "pick the part",
        robot_type="ur5e",
    )


def test_round_trip_through_lerobots_loader_and_a_kill_9_mid_episode(tmp_path):
    """One dataset over two writer sessions: saved, discarded, marked and killed episodes,
    then everything read back by LeRobot (one test: each LeRobot process costs seconds)."""
    rng = np.random.default_rng(7)
    frames = _Keeping(camera="scene")
    recorder = _recorder(tmp_path, frames)
    sent = []
    _feed(frames, rng, 0)
    _record(recorder, frames, rng, 12, sent)
    ok, why = recorder.stop(success=True)
    assert ok, why
    _record(recorder, frames, rng, 9, sent)
    ok, why = recorder.discard()  # a discarded episode leaves no trace
    assert ok, why
    sent.pop()
    _record(recorder, frames, rng, 15, sent)
    assert recorder.mark_success(False)[0]
    ok, why = recorder.stop()
    assert ok, why

    # A real kill -9 of the writer in the middle of the next episode.
    _record(recorder, frames, rng, 6, [])
    recorder.writer.flush()
    process = recorder.writer.process
    os.kill(process.pid, signal.SIGKILL)
    process.wait()
    versions = tmp_path / ".demo_set.versions"
    assert any(name.startswith("staging-") for name in os.listdir(versions))  # what it left

    # The next session finds the two saved episodes intact, cleans up, and adds one.
    frames = _Keeping(camera="scene")
    recorder = _recorder(tmp_path, frames)
    try:
        _feed(frames, rng, 0)
        _record(recorder, frames, rng, 5, sent)
        ok, why = recorder.stop()
        assert ok, why
    finally:
        recorder.close()
    assert not any(name.startswith("staging-") for name in os.listdir(versions))
    assert DatasetStore(str(tmp_path / "demo_set")).current().endswith("000002")  # one version per saved episode

    meta, episodes = read_dataset(str(tmp_path / "demo_set"), video=True)
    assert meta["fps"] == FPS and meta["episodes"] == 3 and meta["frames"] == 32
    assert meta["video_keys"] == [camera_key("scene")]
    assert sorted(episodes) == [0, 1, 2]
    for index, expected in enumerate(sent):
        got = episodes[index]
        assert got["task"] == "pick the part"
        np.testing.assert_allclose(got["timestamp"], np.arange(len(expected)) / FPS, atol=1e-6)
        for key in ("observation.state", "observation.velocity", "observation.tool_pose", "action"):
            want = np.stack([f[key] for f in expected])
            assert got[key].dtype == np.float32 and got[key].shape == want.shape
            np.testing.assert_array_equal(got[key], want)  # exact to float32
        for key in ("observation.hand", "tool_target", "command_velocity"):
            np.testing.assert_array_equal(got[key], np.stack([f[key] for f in expected]))
        video = got[camera_key("scene")]
        want = np.stack([f[camera_key("scene")] for f in expected]).transpose(0, 3, 1, 2) / 255.0
        assert video.shape == (len(expected), 3, H, W)
        error = np.abs(video - want)
        assert error.mean() < 0.03, error.mean()  # lossy codec: mean error under 3 % of full scale
        # Each decoded frame is closest to the frame it was made from (none shifted or repeated).
        for i in range(len(expected)):
            distances = [np.abs(video[i] - want[j]).mean() for j in range(len(expected))]
            assert int(np.argmin(distances)) == i
    record = read_episode_list(str(tmp_path / "demo_set"))
    assert [r["success"] for r in record] == [True, False, False]
    assert [r["frames"] for r in record] == [12, 15, 5]
    assert record[0]["camera_new_frames"] == 12 and record[0]["camera_repeated_frames"] == 0
    assert record[0]["dropped_frames"] == 0
