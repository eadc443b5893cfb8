"""Replay schedules: when each recorded frame is due, relative to the replay start."""
from typing import Iterable, Iterator, Tuple


def replay_schedule(times: Iterable[float], rate: float = 1.0, start_offset: float = 0.0) -> Iterator[Tuple[int, float]]:
    """Yield (index, due seconds after start) for recorded ``times`` (s, any origin).

    ``rate`` > 1 plays faster; ``rate`` <= 0 means as fast as possible (every frame due at 0).
    Frames recorded before ``start_offset`` seconds into the recording are skipped.
    """
    times = list(times)
    if not times:
        return
    origin = times[0] + start_offset
    for index, t in enumerate(times):
        if t < origin:
            continue
        yield index, 0.0 if rate <= 0 else (t - origin) / rate


CSV_COLUMNS = ("stamp", "x", "y", "z", "qx", "qy", "qz", "qw", "hand_type")


def read_csv(path: str):
    """Read a CSV hand stream: header ``stamp,x,y,z,qx,qy,qz,qw,hand_type`` (s, m, unit
    quaternion, left/right; an empty hand_type row means no hand). Returns (samples,
    rejected lines) as HandSamples; bad rows are skipped and listed, never fatal."""
    import csv

    import numpy as np

    from .errors import MotionSensorError
    from .hand_sample import HandSample

    samples, rejected = [], []
    try:
        with open(path, newline="", encoding="utf-8") as fh:
            reader = csv.DictReader(fh)
            missing = [c for c in CSV_COLUMNS if c not in (reader.fieldnames or [])]
            if missing:
                raise MotionSensorError(f"CSV {path} lacks columns {missing}; expected {','.join(CSV_COLUMNS)}")
            for lineno, row in enumerate(reader, start=2):
                try:
                    values = [float(row[c]) for c in CSV_COLUMNS[:8]]
                except (TypeError, ValueError):
                    rejected.append(f"line {lineno}: non-numeric value")
                    continue
                hand_type = (row["hand_type"] or "").strip()
                if hand_type not in ("", "left", "right"):
                    rejected.append(f"line {lineno}: hand_type must be left, right or empty")
                    continue
                types = (hand_type,) if hand_type else ()
                samples.append(HandSample(stamp=values[0], position=np.array(values[1:4]),
                                          orientation=np.array(values[4:8]), hands_num=len(types),
                                          hand_types=types, device="csv"))
    except OSError as exc:
        raise MotionSensorError(f"cannot read CSV {path}: {exc}") from None
    if not samples:
        raise MotionSensorError(f"CSV {path} holds no usable row ({len(rejected)} rejected)")
    return samples, rejected
