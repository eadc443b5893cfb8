"""Tray slot poses from a program taught by gesture (the file teach mode saves, motion_commander.program).

The operator teaches the slots the way the teach mode records any place: steer the arm
over a slot and open the hand. Each ``release`` waypoint of the saved program is one taught
slot. Which class it belongs to:

1. a release whose name contains a class name (e.g. ``release_nut_yellow``, after renaming
   the waypoint in the file) is that class's slot;
2. any other release belongs to the tray slot (from the cell YAML) nearest to it, which
   must be within ``tolerance`` of it: the operator releases over the slot meant.

The taught point is where the magnet's axis meets the tray, i.e. tool0's taught pose moved
``gripper.tcp_length`` along its own z axis, so a slightly tilted tool still gives the point
under the magnet. The tool must point down (within ``max_tilt``): a part released from a
tilted magnet lands off its axis. The taught height is not used: the picker lowers each
part to ``place_height`` above the tray floor (or the parts already in the slot).

A slot the program does not teach keeps its YAML pose; the summary says which came from
where. Nothing is guessed: two releases for one slot, a release far from every slot, a
program of another robot or tool frame, or a tilted release is an error naming the file,
the waypoint and what to do.
"""

import dataclasses
import math

import numpy as np
from scipy.spatial.transform import Rotation

from motion_commander.program import Program

from .cell import Cell, Slot
from .parts import CLASS_NAMES

# The tray slots sit 8 cm apart: half of that separates "over this slot" from the next.
DEFAULT_TOLERANCE = 0.04  # m
DEFAULT_MAX_TILT = 15.0  # deg between the tool's z axis and straight down


class SlotProgramError(ValueError):
    """A taught program that cannot give slot poses; the message says what to do."""


@dataclasses.dataclass
class TaughtSlots:
    """The cell with the taught slot centres, and where each slot's pose came from."""

    cell: Cell
    sources: dict[str, str]  # class -> "taught <waypoint>" or "cell YAML"
    offsets: dict[str, float]  # class -> m, taught centre minus YAML centre (taught slots only)

    def summary(self) -> list[str]:
        """One line per slot, for the node's log."""
        lines = []
        for slot in self.cell.tray.slots:
            where = self.sources[slot.part_class]
            extra = (
                f", {self.offsets[slot.part_class] * 1000:.1f} mm from the YAML slot"
                if slot.part_class in self.offsets
                else ""
            )
            lines.append(f"{slot.part_class:14s} ({slot.center[0]:+.3f}, {slot.center[1]:+.3f}) m  {where}{extra}")
        return lines


def magnet_point(position, orientation, tcp_length: float) -> np.ndarray:
    """The magnet face centre of a tool0 pose (position m, quaternion x, y, z, w)."""
    rotation = Rotation.from_quat(np.asarray(orientation, float))
    return np.asarray(position, float) + rotation.apply([0.0, 0.0, tcp_length])


def tool_tilt_deg(orientation) -> float:
    """Angle between the tool's z axis and straight down, in degrees."""
    z_axis = Rotation.from_quat(np.asarray(orientation, float)).apply([0.0, 0.0, 1.0])
    return math.degrees(math.acos(max(-1.0, min(1.0, -z_axis[2]))))


def _class_in_name(name: str) -> str:
    named = [c for c in CLASS_NAMES if c in name]
    # "nut_yellow" is not a substring of another class name, so at most one matches;
    # still, refuse rather than pick if a future class list makes names overlap.
    return named[0] if len(named) == 1 else ""


def slots_from_program(
    cell: Cell, program: Program, source: str, tolerance: float = DEFAULT_TOLERANCE, max_tilt: float = DEFAULT_MAX_TILT
) -> TaughtSlots:
    """The cell with its slot centres replaced by the program's release points.

    ``source`` (the program file) is named in every error. Raises SlotProgramError.
    """
    if program.robot != cell.robot:
        raise SlotProgramError(
            f"{source}: taught on robot {program.robot!r}, but the cell's robot is "
            f"{cell.robot!r}; teach the slots with the cell's robot"
        )
    if program.tool_frame != "tool0":
        raise SlotProgramError(
            f"{source}: poses are of {program.tool_frame!r}; the kitting cell's magnet is "
            "defined from tool0 (cell YAML gripper.tcp_length): teach with tool_frame tool0"
        )
    releases = [w for w in program.waypoints if w.action == "release"]
    if not releases:
        raise SlotProgramError(
            f"{source}: no release waypoint; teach each slot by opening the hand over it (the 'release' command)"
        )
    tcp_length = cell.gripper.tcp_length
    yaml_slots = {slot.part_class: slot for slot in cell.tray.slots}
    taught: dict[str, tuple[str, np.ndarray]] = {}
    for waypoint in releases:
        where = f"{source}: waypoint {waypoint.name!r}"
        tilt = tool_tilt_deg(waypoint.orientation)
        if tilt > max_tilt:
            raise SlotProgramError(
                f"{where}: the tool was tilted {tilt:.0f} deg from straight down "
                f"(at most {max_tilt:g}); re-teach the release with the tool pointing down"
            )
        point = magnet_point(waypoint.position, waypoint.orientation, tcp_length)
        class_name = _class_in_name(waypoint.name)
        if class_name:
            distance = float(np.linalg.norm(point[:2] - yaml_slots[class_name].center[:2]))
        else:
            class_name, distance = min(
                ((c, float(np.linalg.norm(point[:2] - s.center[:2]))) for c, s in yaml_slots.items()),
                key=lambda item: item[1],
            )
        if distance > tolerance:
            raise SlotProgramError(
                f"{where}: released at ({point[0]:.3f}, {point[1]:.3f}) m, {distance * 1000:.0f} mm from the "
                f"{class_name} slot of the cell YAML (at most {tolerance * 1000:.0f} mm); release over the slot, "
                "or correct the tray's position in the cell YAML"
            )
        if class_name in taught:
            raise SlotProgramError(
                f"{where}: a second release for the {class_name} slot (the first is "
                f"{taught[class_name][0]!r}); delete one of them from the program"
            )
        taught[class_name] = (waypoint.name, point)
    slots, sources, offsets = [], {}, {}
    for slot in cell.tray.slots:
        if slot.part_class in taught:
            name, point = taught[slot.part_class]
            center = np.array([point[0], point[1], slot.center[2]])
            offsets[slot.part_class] = float(np.linalg.norm(center[:2] - slot.center[:2]))
            sources[slot.part_class] = f"taught {name}"
            slots.append(Slot(slot.part_class, center, slot.size, slot.yaw))
        else:
            sources[slot.part_class] = "cell YAML"
            slots.append(slot)
    tray = dataclasses.replace(cell.tray, slots=slots)
    return TaughtSlots(dataclasses.replace(cell, tray=tray), sources, offsets)
