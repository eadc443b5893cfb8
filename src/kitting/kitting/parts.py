"""The six part classes of "Towards Robot Software Abstraction": bolt, nut and washer, each
in yellow (zinc-yellow passivated) and silver (stainless / bright zinc).

Sizes are ISO metric, M8-M12: a hex bolt M8x40 (ISO 4017: head 13 mm across flats, 5.3 mm
high), a hex nut M12 (ISO 4032: 18 mm across flats, 10.8 mm thick) and a flat washer M10
(ISO 7089: 10.5 mm bore, 20 mm outside, 2 mm thick). All lengths in metres.

A part lies flat on the belt: the bolt on its side (its head is taller than its shaft), the
nut and the washer on a face. A part's pose (x, y, yaw) is the area centroid of its
footprint on the belt; ``centroid_height`` is the height above the belt at which the
silhouette's centroid is best intersected (about half the visible height).
"""

from dataclasses import dataclass

KINDS = ("bolt", "nut", "washer")
COLOURS = ("yellow", "silver")

# Rendered colours (linear RGBA, 0-1): zinc-yellow and stainless grey.
RGBA = {
    "yellow": (0.88, 0.72, 0.12, 1.0),
    "silver": (0.78, 0.78, 0.80, 1.0),
}


@dataclass(frozen=True)
class PartClass:
    """One of the six classes: kind (bolt|nut|washer), colour (yellow|silver), geometry."""

    kind: str
    colour: str
    thread: str  # "M8" ... "M12"
    length: float  # m, footprint extent along the part's axis (bolt: head + shaft)
    width: float  # m, footprint extent across (nut: across flats, washer: outside diameter)
    height: float  # m, top above the belt
    bore: float = 0.0  # m, washer hole diameter (0: none visible from above)
    centroid_height: float = 0.0  # m, see module docstring

    @property
    def name(self) -> str:
        return f"{self.kind}_{self.colour}"

    @property
    def rgba(self) -> tuple[float, float, float, float]:
        return RGBA[self.colour]

    @property
    def footprint_area(self) -> float:
        """m², area seen from above (the detector's size check)."""
        import math

        if self.kind == "bolt":
            return BOLT_HEAD[0] * BOLT_HEAD[1] + (self.length - BOLT_HEAD[0]) * BOLT_SHAFT[0]
        if self.kind == "nut":
            return math.sqrt(3) / 2 * self.width**2
        return math.pi / 4 * (self.width**2 - self.bore**2)


# Bolt M8x40: head (along axis, across) and shaft (diameter, shaft bottom above the belt).
BOLT_HEAD = (0.0053, 0.013)
BOLT_SHAFT = (0.008, 0.0025)


def _make(kind: str, colour: str) -> PartClass:
    if kind == "bolt":
        return PartClass(kind, colour, "M8", length=0.0453, width=0.013, height=0.013, centroid_height=0.0055)
    if kind == "nut":
        return PartClass(kind, colour, "M12", length=0.018, width=0.018, height=0.0108, centroid_height=0.0054)
    return PartClass(kind, colour, "M10", length=0.020, width=0.020, height=0.002, bore=0.0105, centroid_height=0.001)


PART_CLASSES: dict[str, PartClass] = {f"{kind}_{colour}": _make(kind, colour) for kind in KINDS for colour in COLOURS}
CLASS_NAMES = tuple(PART_CLASSES)


def part_class(name: str) -> PartClass:
    """The class called ``name`` (e.g. "nut_yellow"); ValueError listing the valid names."""
    try:
        return PART_CLASSES[name]
    except KeyError:
        raise ValueError(f"unknown part class {name!r}; valid: {list(CLASS_NAMES)}") from None
