"""The ROS log folder's ``latest`` link is replaced atomically (no 'File exists' race
between nodes starting together), and left alone when a non-link is in the way."""

import os

from motion_common.ros_log_link import install, renew_latest_link


def test_latest_is_replaced_atomically(tmp_path):
    first, second = tmp_path / "run1", tmp_path / "run2"
    first.mkdir()
    second.mkdir()
    assert renew_latest_link(str(first))
    assert os.readlink(tmp_path / "latest") == str(first)
    # A stale temporary name from a killed process does not stop the next one.
    os.symlink(str(first), tmp_path / f"latest.{os.getpid()}.tmp")
    assert renew_latest_link(str(second))
    assert os.readlink(tmp_path / "latest") == str(second)
    assert sorted(os.listdir(tmp_path)) == ["latest", "run1", "run2"]


def test_a_directory_in_the_way_is_kept(tmp_path):
    (tmp_path / "latest").mkdir()
    (tmp_path / "run").mkdir()
    assert not renew_latest_link(str(tmp_path / "run"))
    assert (tmp_path / "latest").is_dir()


def test_install_replaces_rosgraphs_function():
    import rosgraph.roslogging

    install()
    assert rosgraph.roslogging.renew_latest_logdir is renew_latest_link
