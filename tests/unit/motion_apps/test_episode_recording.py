"""The recording pieces that need no LeRobot: the wire format between recorder and writer,
the versioned dataset folder (atomic commit, repairs after a kill), the dataset folder
check, the fixed-rate frames, and the recorder's state machine with a stand-in writer."""

import io
import os
import shutil
import struct

import numpy as np
import pytest

from motion_apps import dataset_store
from motion_apps.dataset_store import DatasetStore, DatasetStoreError, check_dataset_folder
from motion_apps.episode_frames import EpisodeFrames
from motion_apps.episode_recorder import EpisodeRecorder
from motion_apps.episode_wire import WireError, encode, read_message

JOINTS = ["a", "b", "c"]


def _framed(header: bytes) -> bytes:
    return struct.pack(">I", len(header)) + header


# -- wire -------------------------------------------------------------------------------
def test_wire_round_trip_keeps_dtypes_and_values():
    arrays = {"x": np.arange(6, dtype=np.float32).reshape(2, 3), "img": np.full((4, 5, 3), 7, np.uint8)}
    stream = io.BytesIO(encode({"cmd": "frame", "n": 1}, arrays) + encode({"cmd": "save"}))
    header, got = read_message(stream)
    assert header == {"cmd": "frame", "n": 1}
    for key, value in arrays.items():
        assert got[key].dtype == value.dtype
        np.testing.assert_array_equal(got[key], value)
    assert read_message(stream) == ({"cmd": "save"}, {})
    assert read_message(stream) is None


@pytest.mark.parametrize(
    "blob, reason",
    [
        (b"\x00\x00\x00\x03abc", "not JSON"),
        (b"\xff\xff\xff\xff", "header of"),
        (_framed(b'{"arrays":[[1]]}'), "not \\[name, dtype, shape, bytes\\]"),
        (_framed(b'{"arrays":[["x",4]]}') + b"abcd", "not \\[name, dtype, shape, bytes\\]"),
        (_framed(b'{"arrays":[["x","<f4",[2],4]]}') + b"abcd", "array 'x': 4 bytes for float32 \\[2\\]"),
        (_framed(b'{"arrays":[["x","|O",[1],8]]}') + b"abcdefgh", "array 'x': dtype object is not a plain number"),
        (_framed(b'{"arrays":[["x","zz",[1],1]]}') + b"a", "array 'x': dtype 'zz' is not NumPy's"),
    ],
)
def test_wire_rejects_malformed_messages_with_a_reason(blob, reason):
    with pytest.raises(WireError, match=reason):
        read_message(io.BytesIO(blob))


def test_wire_truncated_message_is_an_end_of_stream():
    blob = encode({"cmd": "frame"}, {"x": np.zeros(10)})
    with pytest.raises(EOFError):
        read_message(io.BytesIO(blob[:-3]))


# -- versioned dataset folder ---------------------------------------------------------------
def _fake_episode(root, n):
    os.makedirs(os.path.join(root, "meta"), exist_ok=True)
    os.makedirs(os.path.join(root, "data"), exist_ok=True)
    with open(os.path.join(root, "meta", "info.json"), "w") as f:
        f.write(f'{{"episodes": {n}}}')
    with open(os.path.join(root, "data", f"file-{n:03d}.parquet"), "w") as f:
        f.write(f"episode {n}")


def test_store_commits_versions_behind_one_link(tmp_path):
    store = DatasetStore(str(tmp_path / "set"))
    assert store.current() is None
    first = store.stage()
    assert not os.path.exists(first)  # LeRobot's create makes it
    _fake_episode(first, 0)
    store.commit(first)
    assert os.path.islink(tmp_path / "set")
    second = store.stage()
    # meta is a copy (LeRobot rewrites it), data files are hard links (never rewritten)
    assert os.stat(os.path.join(second, "meta", "info.json")).st_nlink == 1
    assert os.stat(os.path.join(second, "data", "file-000.parquet")).st_nlink == 2
    _fake_episode(second, 1)
    assert (tmp_path / "set" / "meta" / "info.json").read_text() == '{"episodes": 0}'  # untouched until commit
    store.commit(second)
    assert (tmp_path / "set" / "meta" / "info.json").read_text() == '{"episodes": 1}'
    assert sorted(os.listdir(tmp_path / "set" / "data")) == ["file-000.parquet", "file-001.parquet"]
    assert sorted(os.listdir(store.versions)) == ["000001"]  # the older version went


def test_store_marks_a_saved_episode_in_a_new_version(tmp_path):
    store = DatasetStore(str(tmp_path / "set"))
    staging = store.stage()
    _fake_episode(staging, 0)
    dataset_store.write_sidecar(staging, [{"episode_index": 0, "success": False}])
    store.commit(staging)
    assert store.mark(0, True) == {"episode_index": 0, "success": True}
    assert dataset_store.read_sidecar(str(tmp_path / "set")) == [{"episode_index": 0, "success": True}]
    assert store.current().endswith("000001")
    with pytest.raises(DatasetStoreError, match="episode 3 is not in"):
        store.mark(3, True)


def test_store_refuses_to_commit_a_staging_copy_without_metadata(tmp_path):
    store = DatasetStore(str(tmp_path / "set"))
    staging = store.stage()
    os.makedirs(staging)
    with pytest.raises(DatasetStoreError, match="no meta"):
        store.commit(staging)


def test_store_repairs_what_a_killed_writer_left(tmp_path, monkeypatch):
    store = DatasetStore(str(tmp_path / "set"))
    first = store.stage()
    _fake_episode(first, 0)
    store.commit(first)
    dead = os.path.join(store.versions, "staging-999999-1")
    os.makedirs(os.path.join(dead, "meta"))
    # killed between the rename into a version and the link: the link is re-made
    os.unlink(tmp_path / "set")
    monkeypatch.setattr(dataset_store, "_pid_alive", lambda pid: False)
    store2 = DatasetStore(str(tmp_path / "set"))
    assert not os.path.exists(dead)
    assert store2.current().endswith("000000")


def test_store_adopts_a_plain_lerobot_folder_and_refuses_other_folders(tmp_path):
    plain = tmp_path / "made_elsewhere"
    _fake_episode(str(plain), 0)
    store = DatasetStore(str(plain))
    assert os.path.islink(plain) and store.current().endswith("000000")
    other = tmp_path / "photos"
    other.mkdir()
    (other / "x.jpg").write_text("x")
    with pytest.raises(DatasetStoreError, match="not a LeRobot dataset"):
        DatasetStore(str(other))


def test_folder_check_names_unwritable_folders_and_full_disks(tmp_path, monkeypatch):
    assert check_dataset_folder(str(tmp_path / "sets" / "a"), 1) is None
    assert not (tmp_path / "sets").exists()  # a check creates nothing
    locked = tmp_path / "locked"
    locked.mkdir()
    locked.chmod(0o500)
    try:
        if os.access(locked, os.W_OK):  # root ignores the mode: make the check fail as a full mount would
            monkeypatch.setattr(
                dataset_store.tempfile,
                "NamedTemporaryFile",
                lambda **kw: (_ for _ in ()).throw(PermissionError(13, "Permission denied")),
            )
        message = check_dataset_folder(str(locked / "a"), 1)
        assert "not writable" in message and str(locked) in message
    finally:
        locked.chmod(0o700)
    monkeypatch.undo()
    monkeypatch.setattr(shutil, "disk_usage", lambda p: shutil._ntuple_diskusage(10**9, 10**9 - 10**6, 10**6))
    message = check_dataset_folder(str(tmp_path / "a"), 500)
    assert "only 1 MB free" in message and "500 MB" in message
    (tmp_path / "file").write_text("x")
    assert "not a folder" in check_dataset_folder(str(tmp_path / "file"), 0)
    assert "is not a folder" in check_dataset_folder(str(tmp_path / "file" / "set"), 0)


# -- frames -----------------------------------------------------------------------------
def test_frames_wait_for_state_and_count_repeated_camera_images():
    frames = EpisodeFrames(camera="scene")  # size unknown until the first image: waited for
    assert frames.sample() is None and frames.counts.skipped_not_ready == 1
    assert frames.missing() == ["joint_states", "tool pose", "camera scene"]
    frames.image_size = (8, 6)
    frames.on_joints(JOINTS, [1, 2, 3], [])
    frames.on_tool([0, 0, 1], [0, 0, 0, 1])
    frames.on_image(np.zeros((12, 16, 3), np.uint8))
    frames.reset_counts()
    first = frames.sample()
    assert first["observation.images.scene"].shape == (6, 8, 3)  # resized
    np.testing.assert_array_equal(first["action"], [1, 2, 3, 0])  # no command yet: hold still; gripper open
    np.testing.assert_array_equal(first["tool_target"], [0, 0, 1, 0, 0, 0, 1])
    np.testing.assert_array_equal(first["observation.velocity"], [0, 0, 0])
    frames.sample()  # no new image: repeated
    frames.on_image(np.zeros((12, 16, 3), np.uint8))
    frames.on_command(JOINTS, [4, 5, 6])
    frames.on_gripper(True)
    frame = frames.sample()
    np.testing.assert_array_equal(frame["action"], [4, 5, 6, 1])
    np.testing.assert_array_equal(frame["observation.state"], [1, 2, 3, 1])
    assert (frames.counts.camera_new, frames.counts.camera_repeated) == (2, 1)
    features = frames.features()
    assert features["observation.images.scene"]["shape"] == [6, 8, 3]
    assert features["action"]["names"] == JOINTS + ["gripper"]
    with pytest.raises(ValueError, match="HxWx3 uint8"):
        frames.on_image(np.zeros((4, 4), np.uint8))


def test_frames_of_a_camera_of_known_size_start_black_and_counted():
    frames = EpisodeFrames(camera="scene", image_size=(8, 6))
    frames.on_joints(JOINTS, [1, 2, 3], [0, 0, 0])
    frames.on_tool([0, 0, 1], [0, 0, 0, 1])
    assert frames.missing() == []
    assert frames.features()["observation.images.scene"]["shape"] == [6, 8, 3]
    frames.reset_counts()
    assert not frames.sample()["observation.images.scene"].any()
    frames.on_image(np.full((6, 8, 3), 9, np.uint8))
    assert frames.sample()["observation.images.scene"].max() == 9
    assert (frames.counts.camera_missing, frames.counts.camera_new) == (1, 1)


def test_frames_keep_the_last_hand_pose_when_the_hand_leaves():
    frames = EpisodeFrames()
    frames.on_hand(True, [0.1, 0.2, 0.3], [0, 0, 0, 1], 0.5, 0.25)
    frames.on_hand(False)
    np.testing.assert_allclose(frames.hand, [0.1, 0.2, 0.3, 0, 0, 0, 1, 0.5, 0.25, 0])


def test_frames_hold_the_hand_skeleton_by_joint_name():
    frames = EpisodeFrames()
    frames.on_joints(JOINTS, [1, 2, 3], [0, 0, 0])
    frames.on_tool([0, 0, 1], [0, 0, 0, 1])
    assert not frames.sample()["observation.hand_skeleton"].any()  # no device skeleton: zeros, not visible
    frames.on_skeleton(["palm", "thumb_tip", "no_such_joint"], [(1, 2, 3), (4, 5, 6), (7, 8, 9)])
    skeleton = frames.sample()["observation.hand_skeleton"]
    names = frames.features()["observation.hand_skeleton"]["names"]
    assert len(skeleton) == len(names) == 67
    assert skeleton[names.index("palm_y")] == 2 and skeleton[names.index("thumb_tip_z")] == 6
    assert skeleton[-1] == 1 and skeleton.sum() == 1 + 2 + 3 + 4 + 5 + 6 + 1
    frames.on_skeleton([], [])
    assert frames.sample()["observation.hand_skeleton"][-1] == 0


def test_frames_ignore_another_arms_joints():
    frames = EpisodeFrames()
    frames.on_joints(JOINTS, [1, 2, 3], [0, 0, 0])
    frames.on_joints(["x", "y"], [9, 9], [0, 0])
    np.testing.assert_array_equal(frames.joints, [1, 2, 3])


# -- recorder ---------------------------------------------------------------------------
class _Writer:
    """Stands in for the LeRobot writer process."""

    def __init__(self):
        self.commands = []
        self.frames = 0
        self.dropped = 0
        self.episodes = 0

    def command(self, cmd, **fields):
        self.commands.append((cmd, fields))
        if cmd == "start":
            return {"episode_index": self.episodes, "task": fields["task"]}
        if cmd == "save":
            self.episodes += 1
            return {"episode_index": self.episodes - 1, "frames": self.frames, "success": fields["success"]}
        return {}

    def frame(self, arrays):
        self.frames += 1
        return True

    def close(self):
        self.commands.append(("close", {}))


def _ready_recorder(tmp_path, **kwargs):
    frames = EpisodeFrames()
    frames.on_joints(JOINTS, [0, 0, 0], [0, 0, 0])
    frames.on_tool([0, 0, 0], [0, 0, 0, 1])
    now = [0.0]
    writer = _Writer()
    recorder = EpisodeRecorder(
        frames, lambda: writer, str(tmp_path / "set"), "local/set", 10.0, "task", clock=lambda: now[0], **kwargs
    )
    return recorder, writer, now


def test_recorder_refuses_out_of_order_commands_with_reasons(tmp_path):
    frames = EpisodeFrames()
    recorder = EpisodeRecorder(frames, _Writer, str(tmp_path / "set"), "local/set", 10.0, "task")
    assert recorder.start() == (False, "cannot start: no joint_states, tool pose yet")
    assert recorder.stop() == (False, "no episode is being recorded")
    assert recorder.discard() == (False, "no episode is being recorded")
    assert recorder.mark_success(True) == (False, "no episode to mark")


def test_recorder_gesture_toggles_and_long_episodes_are_saved(tmp_path):
    recorder, writer, now = _ready_recorder(tmp_path, toggle_gesture="swipe_right", max_episode_s=1.0)
    assert recorder.on_gesture("fist") is None
    ok, why = recorder.on_gesture("swipe_right")
    assert ok and recorder.recording, why
    recorder.tick()
    ok, why = recorder.on_gesture("swipe_right")
    assert ok and not recorder.recording and "saved episode 0" in why
    assert [c for c, _ in writer.commands] == ["open", "start", "save"]
    recorder.start("another task")
    assert writer.commands[-1] == ("start", {"task": "another task"})
    for _ in range(5):
        recorder.tick()
    now[0] = 1.0
    recorder.tick()
    assert not recorder.recording and "max_episode_s 1 s reached" in recorder.last_result
    save = writer.commands[-1][1]
    assert save["info"]["frames_sampled"] == 6 and save["info"]["duration_s"] == 0.6


def test_first_frame_is_not_one_held_up_by_the_start(tmp_path):
    """A tick that waited for the start (the writer's import) holds values from before it:
    they do not make the episode's first frame; later ticks, even late ones, make frames."""
    recorder, writer, _ = _ready_recorder(tmp_path)
    recorder.start()
    recorder.tick(late_s=3.0)  # this tick's values are 3 s old
    assert writer.frames == 0
    recorder.tick(late_s=0.002)
    recorder.tick(late_s=0.5)  # once the episode runs, a late frame is still a frame
    assert writer.frames == 2


def test_recorder_marks_the_episode_in_progress(tmp_path):
    recorder, writer, _ = _ready_recorder(tmp_path)
    recorder.start()
    assert recorder.mark_success(True)[0]
    recorder.tick()
    recorder.stop()
    assert writer.commands[-1][1]["success"] is True
    recorder.close()
    assert writer.commands[-1][0] == "close"


def test_skeletons_read_from_their_bytes_as_genpy_reads_them():
    # The recorder reads each frame's skeleton straight from its bytes (genpy's decode was
    # most of its decoding time); names decoded once, then recognised.
    import glob

    import motion_sensor
    from motion_apps.skeleton_raw import SkeletonReader

    root = os.path.join(os.path.dirname(__file__), "..", "..", "..")
    devel = glob.glob(os.path.join(root, "catkin_ws", "devel", "lib", "python3*", "dist-packages", "motion_sensor"))
    if not devel:
        pytest.skip("the catkin workspace is not built (scripts/setup --test)")
    if devel[0] not in motion_sensor.__path__:
        motion_sensor.__path__.append(devel[0])
    from geometry_msgs.msg import Point

    from motion_sensor.msg import HandSkeleton

    reader = SkeletonReader()
    rng = np.random.default_rng(7)
    for names in (["palm", "thumb_tip", "wrist"], ["palm", "thumb_tip", "wrist"], ["index_tip"], []):
        msg = HandSkeleton(hand_type="right", hand_id=3, confidence=0.5, joint_names=names)
        msg.header.frame_id = "leap"
        msg.joints = [Point(*rng.normal(size=3)) for _ in names]
        buffer = io.BytesIO()
        msg.serialize(buffer)
        got_names, points = reader.read(buffer.getvalue())
        assert got_names == names
        np.testing.assert_array_equal(points, [(p.x, p.y, p.z) for p in msg.joints] or np.zeros((0, 3)))
    with pytest.raises(ValueError, match="do not fit"):
        reader.read(buffer.getvalue()[:-1] + b"\x05\x00\x00\x00")


def test_frames_hold_the_commands_rate_and_before_any_the_measured_velocity():
    frames = EpisodeFrames()
    frames.on_joints(JOINTS, [1, 2, 3], [0.5, 0, 0])
    frames.on_tool([0, 0, 1], [0, 0, 0, 1])
    np.testing.assert_array_equal(frames.sample()["command_velocity"], [0.5, 0, 0])  # holding still as measured
    frames.on_command(JOINTS, [4, 5, 6], [0.1, -0.2, 0.3])
    np.testing.assert_allclose(frames.sample()["command_velocity"], [0.1, -0.2, 0.3])
    frames.on_command(JOINTS, [4, 5, 6])  # a command without its rate
    np.testing.assert_array_equal(frames.sample()["command_velocity"], [0, 0, 0])
    assert frames.features()["command_velocity"]["names"] == JOINTS
