"""motion_controller_client follow_path FILE: the path file's form is checked, each refusal
naming the file and the row, before anything is sent (hw_interface.path_file, and the
command-line tool refusing a malformed file without ROS)."""

import importlib.util
import os
from importlib.machinery import SourceFileLoader

import numpy as np
import pytest

from hw_interface.path_file import check_path_dof, read_path_file

from ..conftest import HOME, ROOT

_LOADER = SourceFileLoader(
    "motion_controller_client", os.path.join(ROOT, "src", "hw_interface", "nodes", "motion_controller_client")
)


def _write(tmp_path, name, text):
    path = tmp_path / name
    path.write_text(text, encoding="utf-8")
    return str(path)


def _rows(times, offset=0.0):
    return np.column_stack([times, HOME + offset * np.asarray(times)[:, None]])


def test_a_csv_with_a_header_and_comments_and_absolute_times(tmp_path):
    table = _rows(np.array([12.0, 12.1, 12.25]), offset=0.1)
    text = "# exported path\ntime,j1,j2,j3,j4,j5,j6\n" + "\n".join(",".join(f"{v:.6f}" for v in r) for r in table)
    times, joints = read_path_file(_write(tmp_path, "path.csv", text + "\n"))
    np.testing.assert_allclose(times, [0.0, 0.1, 0.25], atol=1e-9)  # counted from the first row
    np.testing.assert_allclose(joints, table[:, 1:], atol=1e-6)
    check_path_dof("path.csv", joints, 6)


def test_an_npy_array(tmp_path):
    table = _rows(np.linspace(0.0, 1.0, 11), offset=0.2)
    np.save(tmp_path / "path.npy", table)
    times, joints = read_path_file(str(tmp_path / "path.npy"))
    np.testing.assert_array_equal(times, table[:, 0])
    np.testing.assert_array_equal(joints, table[:, 1:])


@pytest.mark.parametrize(
    "text,reason",
    [
        ("0,1,2\n0.1,1,2,3\n", r"bad\.csv:2: 4 columns where the first row has 3"),
        ("0,1,2\n0.1,1,x\n", r"bad\.csv:2: not comma-separated numbers"),
        ("0,1,2\n0.1,1,nan\n", r"line 2 has a value that is no number"),
        ("# a comment\ntime,a,b\n0,1,2\n0.1,1,nan\n", r"line 4 has a value that is no number"),
        ("0,1,2\n0.2,1,2\n0.2,1,2\n", r"line 3's time 0.2 s does not come after line 2's 0.2 s"),
        ("0,1,2\n0.2,1,2\n0.1,1,2\n", r"line 3's time 0.1 s does not come after line 2's"),
        ("0,1,2x\n0.1,1,2\n0.2,1.1,2\n", r"bad\.csv:1: not comma-separated numbers"),  # not a header
        ("0 0.0 0.0\n0.1,1,2\n0.2,1.1,2\n", r"bad\.csv:1: not comma-separated numbers"),
        ("t,a\n0.1,1,2\n0.2,1.1,2\n", r"bad\.csv:1: .*nor a header of the data's 3 columns"),
        ("0,1,2\n4000,1,2\n", r"lasts 4000 s, over the 3600 s"),
        ("0,1,2\n", r"at least 2 rows of time \+ joints, got shape \(1, 3\)"),
        ("0\n1\n", r"got shape \(2, 1\)"),
        ("", r"got shape"),
    ],
)
def test_a_malformed_csv_is_refused_naming_the_row(tmp_path, text, reason):
    with pytest.raises(ValueError, match=reason):
        read_path_file(_write(tmp_path, "bad.csv", text))


def test_a_malformed_npy_and_a_missing_file_are_refused(tmp_path):
    np.save(tmp_path / "flat.npy", np.arange(7.0))
    with pytest.raises(ValueError, match=r"flat\.npy: a path is rows of time \+ joints .*shape \(7,\)"):
        read_path_file(str(tmp_path / "flat.npy"))
    np.save(tmp_path / "text.npy", np.array([["0", "1"], ["1", "2"]]))
    with pytest.raises(ValueError, match=r"text\.npy: holds <U1, not numbers"):
        read_path_file(str(tmp_path / "text.npy"))
    (tmp_path / "empty.npy").write_bytes(b"")
    with pytest.raises(ValueError, match=r"empty\.npy: not a NumPy \.npy array"):
        read_path_file(str(tmp_path / "empty.npy"))
    (tmp_path / "junk.npy").write_bytes(b"not an array")
    with pytest.raises(ValueError, match=r"junk\.npy: not a NumPy \.npy array"):
        read_path_file(str(tmp_path / "junk.npy"))
    np.savez(tmp_path / "archive.npz", path=np.zeros((3, 7)))
    os.rename(tmp_path / "archive.npz", tmp_path / "archive.npy")
    with pytest.raises(ValueError, match=r"archive\.npy: not a NumPy \.npy array"):
        read_path_file(str(tmp_path / "archive.npy"))
    np.save(tmp_path / "long.npy", np.zeros(5_000_000))  # refused on its shape, not copied
    with pytest.raises(ValueError, match=r"long\.npy: a path is rows of time \+ joints .*shape \(5000000,\)"):
        read_path_file(str(tmp_path / "long.npy"))
    (tmp_path / "excel.csv").write_bytes("\ufefftime,a\n0,1\n0.5,2\n".encode())  # a UTF-8 BOM
    times, joints = read_path_file(str(tmp_path / "excel.csv"))
    assert times.tolist() == [0.0, 0.5] and joints.ravel().tolist() == [1.0, 2.0]
    (tmp_path / "binary.csv").write_bytes(b"\xff\xfe\x00\x81")
    with pytest.raises(ValueError, match=r"binary\.csv: cannot be read as a text CSV"):
        read_path_file(str(tmp_path / "binary.csv"))
    with pytest.raises(ValueError, match=r"absent\.csv: no such file"):
        read_path_file(str(tmp_path / "absent.csv"))


def test_the_joint_count_must_be_the_robots():
    with pytest.raises(ValueError, match=r"p\.csv: 5 joint columns after the time, the robot has 6 joints"):
        check_path_dof("p.csv", np.zeros((3, 5)), 6)


def test_the_tool_refuses_a_malformed_file_before_ros(tmp_path, capsys):
    """Exit 2 with the file's reason, before any node starts (no master is needed)."""
    tool = importlib.util.module_from_spec(importlib.util.spec_from_loader("motion_controller_client", _LOADER))
    _LOADER.exec_module(tool)
    bad = _write(tmp_path, "bad.csv", "0,1,2\n0.1,1\n")
    assert tool.main(["motion_controller_client", "follow_path", bad]) == 2
    assert "bad.csv:2: 2 columns where the first row has 3" in capsys.readouterr().err
