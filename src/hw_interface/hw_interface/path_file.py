"""A timed joint path read from a file for FOLLOW_PATH (``motion_controller_client
follow_path FILE``): one row per sample, its time (s) then the robot's joints (rad).

Plain Python, no ROS. A CSV (comma-separated, ``#`` comments, an optional header line:
a first line with no number in it and as many fields as the data) or a NumPy ``.npy`` array
of shape (samples, 1 + joints). Times count from the first row's:
a file exported with absolute stamps is sent as it is. The file's form is checked here,
each refusal naming the file and the row, before anything is sent; the server still checks
the path against the robot (limits, speed, where the arm is).
"""

import os

import numpy as np

from .timed_path import MAX_PATH_DURATION, MAX_PATH_SAMPLES

__all__ = ["read_path_file", "check_path_dof", "MAX_COLUMNS"]

#: Most columns a path row may have: its time and up to 63 joints.
MAX_COLUMNS = 64
#: Largest CSV read (bytes): MAX_PATH_SAMPLES rows of MAX_COLUMNS values of ~25 characters.
MAX_CSV_BYTES = MAX_PATH_SAMPLES * MAX_COLUMNS * 26


def _number(text: str) -> bool:
    try:
        float(text)
    except ValueError:
        return False
    return True


def _load(filename: str) -> tuple[np.ndarray, list[str]]:
    """(the table, where each row is in the file: "line N" or "row N")."""
    if filename.lower().endswith(".npy"):
        try:
            table = np.load(filename, mmap_mode="r", allow_pickle=False)
        except (OSError, ValueError, EOFError) as exc:
            raise ValueError(f"{filename}: not a NumPy .npy array of numbers ({exc})") from None
        if not isinstance(table, np.ndarray):
            raise ValueError(f"{filename}: not a NumPy .npy array (an .npz archive?)")
        # The shape is checked on the memory map, before anything is copied.
        if table.ndim != 2 or not 2 <= table.shape[1] <= MAX_COLUMNS:
            raise ValueError(
                f"{filename}: a path is rows of time + joints (2 to {MAX_COLUMNS} columns), got shape {table.shape}"
            )
        if table.shape[0] > MAX_PATH_SAMPLES:
            raise ValueError(f"{filename}: {table.shape[0]} rows: a path holds at most {MAX_PATH_SAMPLES}; split it")
        if table.dtype.kind not in "fiu":
            raise ValueError(f"{filename}: holds {table.dtype}, not numbers")
        return np.array(table), [f"row {i + 1}" for i in range(len(table))]
    rows, places = [], []
    if os.path.getsize(filename) > MAX_CSV_BYTES:
        raise ValueError(
            f"{filename}: {os.path.getsize(filename)} bytes, more than a path's CSV may be ({MAX_CSV_BYTES})"
        )
    try:
        header = None  # (line, fields) of a first line without a number: a header if the data agree
        with open(filename, encoding="utf-8-sig") as stream:
            for number, line in enumerate(stream, 1):
                text = line.split("#", 1)[0].strip()
                if not text:
                    continue
                fields = text.split(",")
                if len(fields) > MAX_COLUMNS:
                    raise ValueError(f"{filename}:{number}: {len(fields)} columns, a row has at most {MAX_COLUMNS}")
                if not rows and header is None and len(fields) > 1 and not any(_number(v) for v in fields):
                    header = (number, fields)  # time, joint names
                    continue
                try:
                    rows.append([float(v) for v in fields])
                except ValueError:
                    raise ValueError(f"{filename}:{number}: not comma-separated numbers: {text[:80]!r}") from None
                if header is not None and len(rows) == 1 and len(header[1]) != len(fields):
                    raise ValueError(
                        f"{filename}:{header[0]}: not comma-separated numbers, nor a header of the data's "
                        f"{len(fields)} columns: {','.join(header[1])[:80]!r}"
                    )
                places.append(f"line {number}")
                if len(rows[-1]) != len(rows[0]):
                    raise ValueError(
                        f"{filename}:{number}: {len(rows[-1])} columns where the first row has {len(rows[0])}"
                    )
                if len(rows) > MAX_PATH_SAMPLES:
                    raise ValueError(f"{filename}: more than {MAX_PATH_SAMPLES} rows: a path holds no more; split it")
    except (OSError, UnicodeError) as exc:
        raise ValueError(f"{filename}: cannot be read as a text CSV ({exc})") from None
    return np.array(rows, dtype=np.float64), places


def read_path_file(filename: str) -> tuple[np.ndarray, np.ndarray]:
    """(times from 0 (n), joints (n x dof)) of a path file, or ValueError naming the file
    and the row (a CSV's line): at least 2 rows of at least 2 columns, at most
    MAX_PATH_SAMPLES rows and MAX_PATH_DURATION s, every value finite, times strictly
    increasing."""
    if not os.path.isfile(filename):
        raise ValueError(f"{filename}: no such file")
    # _load has refused non-numbers, too many rows and too many columns.
    table, places = _load(filename)
    table = np.asarray(table, dtype=np.float64)
    if table.ndim != 2 or table.shape[0] < 2 or table.shape[1] < 2:
        raise ValueError(
            f"{filename}: a path is at least 2 rows of time + joints, got shape {table.shape} "
            "(one row per sample: time in s, then each joint in rad)"
        )
    bad = np.flatnonzero(~np.all(np.isfinite(table), axis=1))
    if bad.size:
        raise ValueError(f"{filename}: {places[bad[0]]} has a value that is no number: {table[bad[0]].tolist()}")
    times = table[:, 0] - table[0, 0]
    bad = np.flatnonzero(np.diff(times) <= 0.0)
    if bad.size:
        i = bad[0] + 1
        raise ValueError(
            f"{filename}: {places[i]}'s time {table[i, 0]:g} s does not come after {places[i - 1]}'s "
            f"{table[i - 1, 0]:g} s (times must increase strictly)"
        )
    if times[-1] > MAX_PATH_DURATION:
        raise ValueError(
            f"{filename}: the path lasts {times[-1]:g} s, over the {MAX_PATH_DURATION:g} s a path may (times in s)"
        )
    return times, table[:, 1:].copy()


def check_path_dof(filename: str, joints: np.ndarray, dof: int) -> None:
    """ValueError unless the path's rows hold ``dof`` joints (the robot's)."""
    if joints.shape[1] != dof:
        raise ValueError(
            f"{filename}: {joints.shape[1]} joint columns after the time, the robot has {dof} joints "
            f"(each row: time, then {dof} joints in the robot's order)"
        )
