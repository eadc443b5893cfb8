"""Gesture template files: the folder a user records into, and the labelled datasets of
the evaluation CLI. One text format for both.

Path file (``.csv``): one point per row, ``x y z t`` separated by whitespace or commas;
x, y, z in millimetres, t in milliseconds (any origin, increasing). Lines starting with
``#`` are comments (the writer puts the label, the source and the axes there). Rows that
are not four finite numbers are skipped and reported, never fatal.

Template folder (``load_templates`` / ``save_template``)::

    <dir>/<label>/<n>.csv        e.g. gestures/swipe_right/003.csv

The label is the sub-folder name (letters, digits, ``_`` and ``-``); every file is one
performance. Points of recorded templates are in the device frame of the hand message
(REP 103: x forward, y left, z up), of the palm or the index tip. Files are written
atomically (temporary file in the same folder, fsync, rename, fsync of the folder), so a
crash never leaves half a template behind.

Evaluation dataset (``load_dataset``)::

    <dir>/<subject>/<label>.csv  or deeper: <dir>/<subject>/**/<label>.csv

The subject is the first folder under ``<dir>``, the label the file stem (a trailing
``_<n>`` or ``-<n>`` repetition suffix is *not* stripped: name files by label).
"""

import os
import re
from dataclasses import dataclass, field

import numpy as np

from motion_common.atomic_file import write_atomic
from motion_sensor.errors import MotionSensorError

LABEL_RE = re.compile(r"^[A-Za-z0-9_\-]+$")


@dataclass
class PathFile:
    """One performance read from a file: points (n x 3, mm), times (n, ms), label, subject,
    and the rows skipped with their reason."""

    path: str
    label: str
    points: np.ndarray
    times: np.ndarray
    subject: str = ""
    skipped: list[str] = field(default_factory=list)


def read_path(path: str, label: str = "", subject: str = "") -> PathFile:
    """Read one ``x y z t`` file (see the module docstring)."""
    rows, skipped = [], []
    try:
        with open(path, encoding="utf-8", errors="replace") as fh:
            for lineno, line in enumerate(fh, start=1):
                text = line.strip()
                if not text or text.startswith("#"):
                    continue
                parts = text.replace(",", " ").split()
                try:
                    values = [float(v) for v in parts]
                except ValueError:
                    skipped.append(f"{path}:{lineno}: not numbers: {text[:40]!r}")
                    continue
                if len(values) != 4:
                    skipped.append(f"{path}:{lineno}: {len(values)} values, expected 4 (x y z t)")
                    continue
                if not all(np.isfinite(values)):
                    skipped.append(f"{path}:{lineno}: non-finite value")
                    continue
                rows.append(values)
    except OSError as exc:
        raise MotionSensorError(f"cannot read gesture file {path}: {exc}") from None
    data = np.array(rows, dtype=float).reshape(-1, 4)
    return PathFile(
        path, label or os.path.splitext(os.path.basename(path))[0], data[:, :3], data[:, 3], subject, skipped
    )


def format_path(points, times, comment: str = "") -> str:
    """File text of a path (points mm, times ms)."""
    points = np.asarray(points, dtype=float).reshape(-1, 3)
    times = np.asarray(times, dtype=float).reshape(-1)
    if len(points) != len(times):
        raise MotionSensorError(f"{len(points)} points but {len(times)} times")
    lines = [f"# {line}" for line in comment.splitlines()] if comment else []
    lines.append("# x y z [mm] t [ms]")
    lines.extend(f"{x:.3f} {y:.3f} {z:.3f} {t:.3f}" for (x, y, z), t in zip(points, times))
    return "\n".join(lines) + "\n"


def check_label(label: str) -> str:
    """The label if it is a valid folder name, else MotionSensorError."""
    if not LABEL_RE.match(label or ""):
        raise MotionSensorError(f"gesture label {label!r}: use letters, digits, '_' and '-' only")
    return label


def save_template(folder: str, label: str, points_mm, times_ms, comment: str = "") -> str:
    """Write one performance as the next free ``<folder>/<label>/<n>.csv``; return its path."""
    check_label(label)
    target = os.path.join(folder, label)
    os.makedirs(target, exist_ok=True)
    taken = [int(m.group(1)) for name in os.listdir(target) for m in [re.match(r"^(\d+)\.csv$", name)] if m]
    path = os.path.join(target, f"{(max(taken) + 1) if taken else 1:03d}.csv")
    write_atomic(path, format_path(points_mm, times_ms, comment or f"gesture {label}"))
    return path


def load_templates(folder: str, min_points: int = 5) -> tuple[list[PathFile], list[str]]:
    """Every template of ``<folder>/<label>/*.csv``: (files, problems). Files with fewer
    than ``min_points`` valid rows are left out and listed in the problems."""
    if not os.path.isdir(folder):
        raise MotionSensorError(f"gesture template folder {folder} does not exist")
    files, problems = [], []
    for label in sorted(os.listdir(folder)):
        sub = os.path.join(folder, label)
        if not os.path.isdir(sub) or label.startswith("."):
            continue
        for name in sorted(os.listdir(sub)):
            if not name.endswith(".csv"):
                continue
            item = read_path(os.path.join(sub, name), label)
            problems.extend(item.skipped)
            if len(item.points) < min_points:
                problems.append(f"{item.path}: {len(item.points)} valid rows, need {min_points}: file left out")
                continue
            files.append(item)
    return files, problems


def load_dataset(folder: str, min_points: int = 5) -> tuple[list[PathFile], list[str]]:
    """Every ``<folder>/<subject>/**/<label>.csv``: (files, problems) as load_templates."""
    if not os.path.isdir(folder):
        raise MotionSensorError(f"dataset folder {folder} does not exist")
    files, problems = [], []
    for subject in sorted(os.listdir(folder)):
        base = os.path.join(folder, subject)
        if not os.path.isdir(base) or subject.startswith("."):
            if subject.endswith(".csv"):
                problems.append(f"{base}: a file directly in the dataset folder has no subject: left out")
            continue
        for root, dirs, names in os.walk(base):
            dirs.sort()
            for name in sorted(names):
                if not name.endswith(".csv"):
                    continue
                item = read_path(os.path.join(root, name), subject=subject)
                problems.extend(item.skipped)
                if len(item.points) < min_points:
                    problems.append(f"{item.path}: {len(item.points)} valid rows, need {min_points}: file left out")
                    continue
                files.append(item)
    return files, problems


def subjects_of(files: list[PathFile]) -> list[str]:
    """Sorted distinct subjects."""
    return sorted({f.subject for f in files})


def templates_to_samples(files: list[PathFile]) -> list[tuple[str, np.ndarray, np.ndarray | None]]:
    """(label, points, times) triples for DTWClassifier.fit."""
    return [(f.label, f.points, f.times) for f in files]
