"""Kitting trials and their statistics (the paper's 90-trial evaluation), without ROS.

``plan_trials`` draws each trial's part class (cycling through the six classes), its
place across the belt and orientation, and with ``perturb`` its lighting, camera offset
(±2 cm / ±2°) and belt speed (±30 %). ``CampaignStats`` collects what happened: each
vision observation against the simulator's true pose at the image's stamp (pose error,
classification), the kitting node's events and each part's final place; ``summary`` gives
the figures and ``table`` the per-class table; ``plot_confusion`` draws the confusion
matrix.
"""

import math
from collections import Counter
from collections.abc import Sequence
from dataclasses import asdict, dataclass, field

import numpy as np

from .cycle_phases import phase_summary
from .kits import kit_summary
from .parts import CLASS_NAMES

UNKNOWN = "(missed)"


@dataclass
class Trial:
    index: int
    class_name: str
    y_offset: float  # m across the belt
    yaw: float  # rad
    belt_speed: float = math.nan  # m/s; NaN keeps the cell's
    light_level: float = math.nan
    camera_offset: list[float] = field(default_factory=list)  # [dx dy dz (m), rx ry rz (rad)]
    kit: int = 0  # the kit the part belongs to


def plan_trials(
    count: int,
    seed: int,
    perturb: bool,
    belt_speed: float,
    max_y_offset: float = 0.06,
    classes: Sequence[str] | None = None,
    kits: Sequence[int] | None = None,
) -> list[Trial]:
    """``count`` trials drawn from ``seed``: of the given ``classes`` (and ``kits``) in
    order, else cycling through the six classes. The random draws do not depend on the
    classes: the same seed gives the same places and perturbations."""
    rng = np.random.default_rng(seed)
    trials = []
    for index in range(count):
        trial = Trial(
            index,
            classes[index] if classes is not None else CLASS_NAMES[index % len(CLASS_NAMES)],
            float(rng.uniform(-max_y_offset, max_y_offset)),
            float(rng.uniform(-math.pi, math.pi)),
        )
        if perturb:
            trial.belt_speed = float(belt_speed * rng.uniform(0.7, 1.3))
            trial.light_level = float(rng.uniform(0.7, 1.2))
            trial.camera_offset = list(rng.uniform(-0.02, 0.02, 3)) + list(np.radians(rng.uniform(-2.0, 2.0, 3)))
        if kits is not None:
            trial.kit = int(kits[index])
        trials.append(trial)
    return trials


@dataclass
class PartRecord:
    """What happened to one spawned part."""

    trial: Trial
    part_id: int
    spawned: float
    predictions: Counter = field(default_factory=Counter)  # predicted class -> sightings
    pose_errors_mm: list[float] = field(default_factory=list)
    events: list[str] = field(default_factory=list)  # as the operator reads them
    unverified: int = 0  # picks the camera could not confirm (no image since the lift)
    phases: dict = field(default_factory=dict)  # the placing pick's timed phases (kitting.cycle_phases), s
    final_state: str = ""
    slot: str = ""
    resolved: float | None = None
    reason: str = ""

    @property
    def detected(self) -> bool:
        return sum(self.predictions.values()) > 0

    @property
    def predicted(self) -> str:
        return self.predictions.most_common(1)[0][0] if self.predictions else UNKNOWN

    @property
    def classified(self) -> bool:
        return self.predicted == self.trial.class_name

    @property
    def picked(self) -> bool:
        return any(event.split(":")[0] == "picked" for event in self.events)

    @property
    def unverified_picks(self) -> int:
        """Picks the camera could not confirm (no image after the lift)."""
        return self.unverified

    @property
    def success(self) -> bool:
        return self.final_state == "resting" and self.slot == self.trial.class_name

    @property
    def settled(self) -> bool:
        """Come to rest, or given up by the kitting node (skipped: out of reach; failed):
        nothing more will go into the tray for it, so its kit may be scored and swapped
        without waiting for it to ride off the belt."""
        return bool(self.final_state) or any(e.split(":")[0] in ("skipped", "failed") for e in self.events)


class CampaignStats:
    """Collects observations, events and outcomes of the parts of a campaign."""

    def __init__(self, match_radius: float = 0.03):
        self.parts: dict[int, PartRecord] = {}
        self.match_radius = match_radius
        self.unmatched_detections = 0
        self.started: float | None = None
        self.finished: float | None = None
        self.kit_scores: list = []  # kitting.kits.KitScore of each finished tray
        self.spawn_times: list[float] = []

    def add_part(self, trial: Trial, part_id: int, now: float):
        self.parts[part_id] = PartRecord(trial, part_id, now)
        self.spawn_times.append(now)
        if self.started is None:
            self.started = now

    def add_observation(self, truth: Sequence[tuple], seen: Sequence[tuple]):
        """One image: ``truth`` [(part_id, x, y, state)] at its stamp, ``seen`` [(class, x, y)]
        from the vision node. Each sighting is matched to the nearest true part on the belt."""
        on_belt = [(pid, x, y) for pid, x, y, state in truth if state == "belt" and pid in self.parts]
        for class_name, x, y in seen:
            best = min(on_belt, key=lambda t: math.hypot(t[1] - x, t[2] - y), default=None)
            if best is None or math.hypot(best[1] - x, best[2] - y) > self.match_radius:
                self.unmatched_detections += 1
                continue
            record = self.parts[best[0]]
            record.predictions[class_name] += 1
            record.pose_errors_mm.append(1000.0 * math.hypot(best[1] - x, best[2] - y))

    def add_event(self, part_id: int, event: str, verified: bool = True):
        """One event of a part (its text as the operator reads it); ``verified`` False for a
        pick the camera could not confirm."""
        if part_id in self.parts:
            self.parts[part_id].events.append(event)
            self.parts[part_id].unverified += not verified

    def add_phases(self, part_id: int, phases: dict):
        """The timed phases (phase -> s) of the pick that ended a part's cycle."""
        if part_id in self.parts:
            self.parts[part_id].phases = {str(k): float(v) for k, v in phases.items()}

    def resolve(self, part_id: int, state: str, slot: str, now: float, reason: str = ""):
        record = self.parts[part_id]
        record.final_state, record.slot, record.resolved, record.reason = state, slot, now, reason
        self.finished = now if self.finished is None else max(self.finished, now)

    # -- figures -----------------------------------------------------------------------------
    def summary(self) -> dict:
        records = list(self.parts.values())
        errors = [e for r in records for e in r.pose_errors_mm]
        successes = sum(r.success for r in records)
        span_min = ((self.finished - self.started) / 60.0) if self.started is not None and self.finished else math.nan
        cycle = [r.resolved - r.spawned for r in records if r.success and r.resolved is not None]
        spawns = sorted(self.spawn_times)
        arrival = (
            60.0 * (len(spawns) - 1) / (spawns[-1] - spawns[0])
            if len(spawns) > 1 and spawns[-1] > spawns[0]
            else math.nan
        )
        return {
            "trials": len(records),
            "successes": successes,
            "success_rate": successes / len(records) if records else math.nan,
            "pose_error_mm_p50": float(np.percentile(errors, 50)) if errors else math.nan,
            "pose_error_mm_p95": float(np.percentile(errors, 95)) if errors else math.nan,
            "pose_samples": len(errors),
            "picks_per_minute": successes / span_min if span_min and span_min > 0 else math.nan,
            "spawn_to_place_s_p50": float(np.percentile(cycle, 50)) if cycle else math.nan,
            "spawn_to_place_s_p99": float(np.percentile(cycle, 99)) if cycle else math.nan,
            "unmatched_detections": self.unmatched_detections,
            "unverified_picks": sum(r.unverified_picks for r in records),
            # Parts that rode off the belt's end never picked (left the pick window unpicked).
            "misses": sum(r.final_state == "gone" and not r.picked for r in records),
            "arrival_rate_per_min": arrival,
            # Where the cycle goes: each phase over the picks that placed their part.
            "cycle_phases_s": phase_summary(r.phases for r in records if r.success),
            **kit_summary(self.kit_scores),
            "per_class": self.per_class(),
            "failures": [
                {
                    "trial": r.trial.index,
                    "class": r.trial.class_name,
                    "state": r.final_state,
                    "slot": r.slot,
                    "predicted": r.predicted,
                    "events": r.events,
                    "reason": r.reason,
                }
                for r in records
                if not r.success
            ],
            "trials_detail": [
                dict(
                    asdict(r.trial),
                    spawned=r.spawned,
                    sightings=len(r.pose_errors_mm),
                    pose_error_mm_p95=float(np.percentile(r.pose_errors_mm, 95)) if r.pose_errors_mm else math.nan,
                    pose_error_mm_max=max(r.pose_errors_mm, default=math.nan),
                    part_id=r.part_id,
                    success=r.success,
                    predicted=r.predicted,
                    events=r.events,
                    final_state=r.final_state,
                    slot=r.slot,
                    phases=r.phases,
                )
                for r in records
            ],
        }

    def per_class(self) -> dict[str, dict]:
        table = {}
        for name in CLASS_NAMES:
            records = [r for r in self.parts.values() if r.trial.class_name == name]
            errors = [e for r in records for e in r.pose_errors_mm]
            n = len(records)
            table[name] = {
                "trials": n,
                "detected": sum(r.detected for r in records),
                "classified": sum(r.classified for r in records),
                "picked": sum(r.picked for r in records),
                "placed": sum(r.success for r in records),
                "pose_error_mm_p95": float(np.percentile(errors, 95)) if errors else math.nan,
            }
        return table

    def confusion(self) -> np.ndarray:
        """Rows: true class; columns: predicted class (by majority of sightings), then 'missed'."""
        labels = list(CLASS_NAMES) + [UNKNOWN]
        matrix = np.zeros((len(CLASS_NAMES), len(labels)), int)
        for r in self.parts.values():
            matrix[CLASS_NAMES.index(r.trial.class_name), labels.index(r.predicted)] += 1
        return matrix

    def table(self) -> str:
        """The per-class table as text."""
        lines = [f"{'class':<15}{'trials':>7}{'detect':>8}{'class.':>8}{'pick':>6}{'place':>7}{'pose p95 mm':>13}"]
        for name, row in self.per_class().items():
            lines.append(
                f"{name:<15}{row['trials']:>7}{row['detected']:>8}{row['classified']:>8}{row['picked']:>6}"
                f"{row['placed']:>7}{row['pose_error_mm_p95']:>13.2f}"
            )
        return "\n".join(lines)

    def plot_confusion(self, path: str, title: str = "kitting campaign: classification"):
        """Write the confusion matrix as a PNG (atomically)."""
        import matplotlib

        matplotlib.use("Agg")
        import io

        import matplotlib.pyplot as plt

        from motion_common.atomic_file import write_atomic

        matrix = self.confusion()
        labels = list(CLASS_NAMES) + ["missed"]
        fig, ax = plt.subplots(figsize=(7.5, 5.5))
        ax.imshow(matrix, cmap="Blues")
        ax.set_xticks(range(len(labels)), labels, rotation=35, ha="right")
        ax.set_yticks(range(len(CLASS_NAMES)), CLASS_NAMES)
        ax.set_xlabel("predicted (majority of sightings)")
        ax.set_ylabel("true class")
        for (i, j), value in np.ndenumerate(matrix):
            if value:
                ax.text(
                    j, i, str(value), ha="center", va="center", color="white" if value > matrix.max() / 2 else "black"
                )
        ax.set_title(title)
        fig.tight_layout()
        buffer = io.BytesIO()
        fig.savefig(buffer, format="png", dpi=110)
        plt.close(fig)
        write_atomic(path, buffer.getvalue())
