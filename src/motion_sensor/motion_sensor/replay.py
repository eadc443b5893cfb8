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
