"""Kits as a real cell fills them, and their score (ARIAC's kitting task score).

A kit is a tray with at most one part per slot: by default one part of each class (each
in its class's slot), or the kits of a kit order file::

    # one list of part classes per kit; each class fills its slot of cell.yaml's tray
    kits:
      - [bolt_yellow, nut_yellow, washer_yellow]
      - [bolt_silver, nut_silver, washer_silver, bolt_yellow]
    repeat: 2          # optional: the list of kits this many times (default 1)

``load_kit_order`` refuses, naming the file and the kit, an unknown class, a class the
tray has no slot for, a class twice in one kit (one part per slot) and an empty kit.

``score_kit`` scores a finished tray the way ARIAC (2023) scores a kitting shipment, with
the parts of this cell: per slot of the kit, 3 points for the right part (type and
colour), 2 for the right type in the wrong colour (a silver nut in the yellow nut's slot),
0 otherwise; a bonus of n (the kit's part count) when every slot has 3; a penalty of
m - n when the tray holds m > n parts. ARIAC's tray-id point and destination multiplier
have no counterpart here (one tray, one destination). The score is never negative; its
maximum is 4 n.
"""

import math
from collections import Counter
from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np

from .cell import Cell
from .parts import CLASS_NAMES, PART_CLASSES

__all__ = [
    "Kit",
    "KitScore",
    "KitOrderError",
    "default_kits",
    "load_kit_order",
    "kit_feed",
    "score_kit",
    "kit_summary",
]


class KitOrderError(ValueError):
    """A kit order file that cannot be used; the message names the file and the kit."""


@dataclass(frozen=True)
class Kit:
    index: int
    classes: tuple[str, ...]  # one per slot


@dataclass
class KitScore:
    """One finished tray: points per slot of the kit, bonus, extra-parts penalty, score."""

    kit: int
    slot_points: dict[str, int] = field(default_factory=dict)  # slot class -> 0, 2 or 3
    bonus: int = 0
    penalty: int = 0
    parts_in_tray: int = 0
    score: int = 0
    max_score: int = 0

    @property
    def complete(self) -> bool:
        """Every slot holds its part and nothing else is in the tray."""
        return self.bonus > 0 and self.penalty == 0

    def as_dict(self) -> dict:
        return {
            "kit": self.kit,
            "slot_points": dict(self.slot_points),
            "bonus": self.bonus,
            "penalty": self.penalty,
            "parts_in_tray": self.parts_in_tray,
            "score": self.score,
            "max_score": self.max_score,
            "complete": self.complete,
        }


def default_kits(parts: int) -> list[Kit]:
    """Kits of one part of each class, enough for ``parts`` parts (the last one partial)."""
    kits = []
    for index, start in enumerate(range(0, parts, len(CLASS_NAMES))):
        kits.append(Kit(index, tuple(CLASS_NAMES[: min(len(CLASS_NAMES), parts - start)])))
    return kits


def load_kit_order(path: str, cell: Cell) -> list[Kit]:
    """The kits of a kit order YAML file, checked against the cell's tray."""
    from motion_common.errors import ParameterError
    from motion_common.params import read_yaml_file

    try:
        data = read_yaml_file(path)
    except ParameterError as exc:
        raise KitOrderError(f"kit order {exc}") from None
    if not isinstance(data, dict) or "kits" not in data:
        raise KitOrderError(f"kit order {path}: needs a 'kits' list (one list of part classes per kit)")
    unknown = sorted(set(data) - {"kits", "repeat"})
    if unknown:
        raise KitOrderError(f"kit order {path}: unknown key(s) {unknown}; allowed: kits, repeat")
    repeat = data.get("repeat", 1)
    if not isinstance(repeat, int) or isinstance(repeat, bool) or not 1 <= repeat <= 10000:
        raise KitOrderError(f"kit order {path}: repeat must be a whole number in [1, 10000], not {repeat!r}")
    kits = data["kits"]
    if not isinstance(kits, list) or not kits:
        raise KitOrderError(f"kit order {path}: 'kits' must be a non-empty list of kits")
    slots = {slot.part_class for slot in cell.tray.slots}
    out = []
    for number, classes in enumerate(kits, 1):
        where = f"kit order {path}: kit {number}"
        if not isinstance(classes, list) or not classes:
            raise KitOrderError(f"{where}: must be a non-empty list of part classes")
        for name in classes:
            if name not in PART_CLASSES:
                raise KitOrderError(f"{where}: unknown part class {name!r}; valid: {list(CLASS_NAMES)}")
            if name not in slots:
                raise KitOrderError(f"{where}: the tray of {cell.source} has no slot for {name}")
        twice = sorted(name for name, count in Counter(classes).items() if count > 1)
        if twice:
            raise KitOrderError(f"{where}: {twice} more than once (one part per slot)")
        out.append(tuple(classes))
    return [Kit(index, classes) for index, classes in enumerate(out * repeat)]


def kit_feed(kits: Sequence[Kit], seed: int, parts: int | None = None) -> list[tuple[int, str]]:
    """(kit index, class) of every part to feed: kit after kit, each kit's parts in a random
    order drawn from ``seed``; at most ``parts`` of them."""
    rng = np.random.default_rng(seed)
    feed = []
    for kit in kits:
        order = list(kit.classes)
        rng.shuffle(order)
        feed += [(kit.index, name) for name in order]
    return feed if parts is None else feed[:parts]


def score_kit(kit: Kit, tray: Sequence[tuple[str, str]]) -> KitScore:
    """Score the tray holding ``tray`` [(part class, slot class it rests in)] for ``kit``."""
    by_slot: dict[str, list[str]] = {}
    for class_name, slot in tray:
        by_slot.setdefault(slot, []).append(class_name)
    points = {}
    for wanted in kit.classes:
        there = by_slot.get(wanted, [])
        best = 0
        for class_name in there:
            if class_name == wanted:
                best = max(best, 3)
            elif class_name in PART_CLASSES and PART_CLASSES[class_name].kind == PART_CLASSES[wanted].kind:
                best = max(best, 2)
        points[wanted] = best
    n, m = len(kit.classes), len(tray)
    bonus = n if all(p == 3 for p in points.values()) else 0
    penalty = m - n if m > n else 0
    score = max(0, sum(points.values()) + bonus - penalty)
    return KitScore(kit.index, points, bonus, penalty, m, score, 4 * n)


def kit_summary(scores: Sequence[KitScore]) -> dict:
    """The kits' figures for a campaign summary."""
    total, best = sum(s.score for s in scores), sum(s.max_score for s in scores)
    return {
        "kits": len(scores),
        "kits_complete": sum(s.complete for s in scores),
        "kit_score": total,
        "kit_score_max": best,
        "kit_score_rate": total / best if best else math.nan,
        "kit_scores": [s.as_dict() for s in scores],
    }
