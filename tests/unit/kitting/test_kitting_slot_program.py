"""kitting.slot_program: tray slot poses from a program taught by gesture.

The shipped tests/data/kitting_taught_slots.yaml was written by
tests/tools/make_kitting_slot_program.py through motion_apps.teach.TeachSession (the teach
mode's state machine) with known offsets from the YAML slots; further programs are taught
here the same way. The closed loop places parts with the taught slots in the simulated
cell, whose tray is still the YAML one.
"""

import math
import os

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from kitting.cell import load_cell
from kitting.parts import CLASS_NAMES
from kitting.slot_program import SlotProgramError, magnet_point, slots_from_program, tool_tilt_deg
from motion_apps.teach import TeachSession
from motion_commander.program import Program, Waypoint, load_program

from ..conftest import DATA
from .test_kitting_cell import _closed_loop, _run, _state

TAUGHT = os.path.join(DATA, "kitting_taught_slots.yaml")
DOWN = [1.0, 0.0, 0.0, 0.0]
# The offsets make_kitting_slot_program.py taught (m, from the YAML slot centre).
TAUGHT_OFFSETS = {
    "bolt_yellow": (0.006, -0.004),
    "nut_yellow": (-0.005, 0.007),
    "washer_yellow": (0.008, 0.003),
    "bolt_silver": (-0.007, -0.006),
    "nut_silver": (0.004, 0.008),
    "washer_silver": (-0.003, -0.008),
}


@pytest.fixture(scope="module")
def cell():
    return load_cell()


def _teach(cell, releases, tmp_path, grip_first=True):
    """A program saved by TeachSession: for each (x, y, orientation) a grip over the belt,
    then a release with tool0 at the magnet point above (x, y). Returns the saved file."""
    pose = {"position": [0.0, 0.7, 0.3], "orientation": DOWN}

    def state():
        return pose["position"], pose["orientation"], [0.0] * 6

    session = TeachSession(cell.robot, state, programs_dir=str(tmp_path), program_name="slots", clock=lambda: 0.0)
    for x, y, orientation in releases:
        if grip_first:
            pose.update(position=[-0.25, cell.belt.y, 0.2], orientation=DOWN)
            assert session.handle_command("grip").understood
        # tool0 such that the magnet face (tcp_length along tool z) is 0.1 m above the tray at (x, y)
        face = np.array([x, y, cell.tray.position[2] + 0.1])
        tool = face - Rotation.from_quat(orientation).apply([0.0, 0.0, cell.gripper.tcp_length])
        pose.update(position=list(tool), orientation=list(orientation))
        feedback = session.handle_command("release")
        assert feedback.understood, feedback.text
    assert session.handle_command("save").understood
    return session.saved_path


def test_the_shipped_taught_program_gives_every_slot_its_taught_centre(cell):
    taught = slots_from_program(cell, load_program(TAUGHT), TAUGHT)
    for class_name in CLASS_NAMES:
        yaml_center = cell.tray.slot_for(class_name).center
        center = taught.cell.tray.slot_for(class_name).center
        np.testing.assert_allclose(center[:2] - yaml_center[:2], TAUGHT_OFFSETS[class_name], atol=1e-4)
        assert center[2] == pytest.approx(yaml_center[2])  # the floor stays the tray's
        assert taught.sources[class_name].startswith("taught release")
        assert taught.offsets[class_name] == pytest.approx(math.hypot(*TAUGHT_OFFSETS[class_name]), abs=1e-4)
    # The input cell is not modified, and the tray's geometry (path checks) is unchanged.
    fresh = load_cell()
    assert all(np.array_equal(a.center, b.center) for a, b in zip(cell.tray.slots, fresh.tray.slots))
    assert taught.cell.tray.size == cell.tray.size
    assert len(taught.summary()) == 6 and "mm from the YAML slot" in taught.summary()[0]


def test_slots_not_taught_keep_their_yaml_pose(cell, tmp_path):
    nut = cell.tray.slot_for("nut_yellow").center
    path = _teach(cell, [(nut[0] + 0.01, nut[1], DOWN)], tmp_path)
    taught = slots_from_program(cell, load_program(path), path)
    assert taught.sources["nut_yellow"].startswith("taught")
    np.testing.assert_allclose(taught.cell.tray.slot_for("nut_yellow").center[:2], [nut[0] + 0.01, nut[1]], atol=1e-9)
    for class_name in set(CLASS_NAMES) - {"nut_yellow"}:
        assert taught.sources[class_name] == "cell YAML"
        assert np.array_equal(taught.cell.tray.slot_for(class_name).center, cell.tray.slot_for(class_name).center)


def test_a_slightly_tilted_tool_gives_the_point_under_the_magnet(cell, tmp_path):
    washer = cell.tray.slot_for("washer_silver").center
    tilted = (Rotation.from_quat(DOWN) * Rotation.from_euler("x", 10, degrees=True)).as_quat()
    path = _teach(cell, [(washer[0], washer[1], tilted)], tmp_path)
    waypoint = [w for w in load_program(path).waypoints if w.action == "release"][0]
    # tool0 itself is ~9 mm off the slot centre (0.05 m * sin 10 deg), the magnet point is on it.
    assert np.linalg.norm(np.array(waypoint.position[:2]) - washer[:2]) > 0.008
    taught = slots_from_program(cell, load_program(path), path)
    np.testing.assert_allclose(taught.cell.tray.slot_for("washer_silver").center[:2], washer[:2], atol=1e-6)
    assert tool_tilt_deg(waypoint.orientation) == pytest.approx(10.0, abs=1e-6)


def test_magnet_point_is_tcp_length_along_the_tool_z_axis():
    assert np.allclose(magnet_point([0.1, 0.2, 0.3], DOWN, 0.05), [0.1, 0.2, 0.25])
    assert np.allclose(magnet_point([0.0, 0.0, 0.0], [0.0, 0.0, 0.0, 1.0], 0.05), [0.0, 0.0, 0.05])


def test_a_release_named_after_a_class_is_that_class_slot(cell):
    # 30 mm off the bolt_yellow slot toward its neighbour, but named for bolt_yellow.
    bolt = cell.tray.slot_for("bolt_yellow").center
    nearest_other = min(
        (s for s in cell.tray.slots if s.part_class != "bolt_yellow"),
        key=lambda s: np.linalg.norm(s.center[:2] - bolt[:2]),
    )
    direction = (nearest_other.center[:2] - bolt[:2]) / np.linalg.norm(nearest_other.center[:2] - bolt[:2])
    point = bolt[:2] + 0.03 * direction
    tool = [point[0], point[1], 0.3]
    program = Program(cell.robot, waypoints=[Waypoint("release_bolt_yellow", tool, DOWN, [0.0] * 6, "release")])
    taught = slots_from_program(cell, program, "named.yaml")
    np.testing.assert_allclose(taught.cell.tray.slot_for("bolt_yellow").center[:2], point, atol=1e-9)
    assert taught.sources[nearest_other.part_class] == "cell YAML"


@pytest.mark.parametrize(
    "change, message",
    [
        (dict(robot="ur5e"), "taught on robot 'ur5e'"),
        (dict(tool_frame="flange"), "poses are of 'flange'"),
    ],
)
def test_a_program_of_another_robot_or_tool_frame_is_refused(cell, change, message):
    program = load_program(TAUGHT)
    for key, value in change.items():
        setattr(program, key, value)
    with pytest.raises(SlotProgramError, match=message):
        slots_from_program(cell, program, TAUGHT)


def test_refusals_name_the_file_the_waypoint_and_what_to_do(cell, tmp_path):
    nut = cell.tray.slot_for("nut_silver").center
    # Beyond the tray's edge, 5 cm past its outer slots.
    outside = cell.tray.position[1] - cell.tray.size[1] / 2 - 0.05
    far = _teach(cell, [(cell.tray.position[0], outside, DOWN)], tmp_path / "far")
    with pytest.raises(
        SlotProgramError,
        match=r"far.*slots.yaml: waypoint 'release2': released at .* mm from the "
        r".* slot .*release over the slot",
    ):
        slots_from_program(cell, load_program(far), far)
    twice = _teach(cell, [(nut[0], nut[1], DOWN), (nut[0] + 0.005, nut[1], DOWN)], tmp_path / "twice")
    with pytest.raises(SlotProgramError, match="a second release for the nut_silver slot .*'release2'.*delete one"):
        slots_from_program(cell, load_program(twice), twice)
    tilted = (Rotation.from_quat(DOWN) * Rotation.from_euler("y", 30, degrees=True)).as_quat()
    tilt = _teach(cell, [(nut[0], nut[1], tilted)], tmp_path / "tilt")
    with pytest.raises(SlotProgramError, match="tilted 30 deg from straight down .*re-teach"):
        slots_from_program(cell, load_program(tilt), tilt)
    no_release = Program(cell.robot, waypoints=[Waypoint("wp1", [0.3, 0.2, 0.3], DOWN, [0.0] * 6)])
    with pytest.raises(SlotProgramError, match="no release waypoint"):
        slots_from_program(cell, no_release, "none.yaml")


def test_closed_loop_releases_at_the_taught_slot_and_the_part_rests_in_it(cell):
    taught = slots_from_program(cell, load_program(TAUGHT), TAUGHT)
    # The simulation keeps the YAML tray (the real one); only the picker knows the taught slots.
    sim, fake, picker, events = _closed_loop(cell, seed=4)
    picker.cell = taught.cell
    try:
        part = sim.spawn("washer_yellow", y_offset=0.0, yaw=0.2)
        _run(picker, fake, events, ("placed", "skipped", "failed", "missed"))
        fake.sleep(1.0)
        placed = events[-1]
        assert placed.event == "placed", [(e.event, e.reason) for e in events]
        expected = taught.cell.tray.slot_for("washer_yellow").center[:2]
        assert np.linalg.norm(placed.position[:2] - expected) < 1e-6
        assert np.linalg.norm(placed.position[:2] - cell.tray.slot_for("washer_yellow").center[:2]) > 0.008
        state = _state(sim, part)
        assert (state.state, state.slot) == ("resting", "washer_yellow")
        # The part came to rest under the taught point (it falls ~2 cm, so a few mm of play).
        assert np.linalg.norm(np.asarray(state.position[:2]) - expected) < 0.006
    finally:
        sim.close()
