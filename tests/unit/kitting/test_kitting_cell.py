"""Kitting: the loop's plain-Python modules without ROS.

- kitting.cell_sim.CellSimulation: belt kinematics in clock time, overruns, the
  electromagnet's grip zone, a gripped part following the tool, released parts coming to
  rest in the tray slot under them (or elsewhere, slot '');
- kitting.picker.KittingPicker in a closed loop: a fake motion controller (simulated
  clock, straight-line moves of 0.3 s + distance / 0.5 m/s) drives the CellSimulation's
  tool and magnet, and the picker is fed noisy sightings of the simulation's ground truth;
- kitting.campaign: trial planning and the campaign statistics;
- kitting.vision_pipeline.VisionPipeline on a few rendered images (pybullet DIRECT).
"""

import math
from dataclasses import replace

import cv2
import numpy as np
import pybullet as p
import pytest

from kitting.calibration import pose_error
from kitting.camera import PinholeCamera, render
from kitting.campaign import UNKNOWN, CampaignStats, Trial, plan_trials
from kitting.cell import load_cell
from kitting.cell_sim import MAX_CATCH_UP, SPAWN_MARGIN, CellSimulation
from kitting.parts import CLASS_NAMES, PART_CLASSES
from kitting.picker import KittingPicker, cell_obstacles, check_segment
from kitting.sim_scene import FOREIGN_CLASS, SimScene, marker_image
from kitting.vision import PartObservation
from kitting.vision_pipeline import VisionPipeline

DOWN = [1.0, 0.0, 0.0, 0.0]  # tool0 quaternion (x, y, z, w): tool z axis pointing down
STEP = 0.01  # s, the fake controller's / the tests' update period


@pytest.fixture(scope="module")
def cell():
    return load_cell()


@pytest.fixture
def sim(cell):
    simulation = CellSimulation(cell)
    yield simulation
    simulation.close()


def _state(sim, part_id):
    return next(s for s in sim.states() if s.part_id == part_id)


def _tool_for_face(cell, face):
    """tool0 position that puts the magnet face (tool pointing down) at ``face``."""
    return np.asarray(face, float) + [0.0, 0.0, cell.gripper.tcp_length]


def _face(sim):
    return sim.tool_position - [0.0, 0.0, sim.cell.gripper.tcp_length]


def _top(cell, class_name):
    return cell.belt.height + PART_CLASSES[class_name].height


def _wait(sim, duration):
    """Advance the clock by ``duration`` in STEP increments, the tool where it is."""
    for _ in range(int(round(duration / STEP))):
        sim.advance(sim.time + STEP)


def _move_face(sim, target, speed=0.25):
    """Move the magnet face in a straight line to ``target`` at ``speed`` (m/s), advancing
    the clock in STEP increments."""
    start, target = _face(sim), np.asarray(target, float)
    count = max(1, int(math.ceil(np.linalg.norm(target - start) / speed / STEP)))
    for k in range(1, count + 1):
        sim.set_tool_pose(_tool_for_face(sim.cell, start + (target - start) * k / count), DOWN)
        sim.advance(sim.time + STEP)


def _belt_x(sim, part_id):
    return float(_state(sim, part_id).position[0])


# -- CellSimulation -------------------------------------------------------------------------------
def test_belt_parts_move_at_belt_speed_times_clock_time_also_across_an_overrun(cell):
    sim = CellSimulation(cell, start_time=100.0)
    try:
        x0 = cell.belt.x_start + SPAWN_MARGIN
        part = sim.spawn("nut_yellow", y_offset=0.03)
        for k in range(1, 38):
            sim.advance(100.0 + k * STEP)
        state = _state(sim, part)
        assert state.state == "belt" and sim.overruns == 0
        assert state.position[0] == pytest.approx(x0 + cell.belt.speed * 0.37, abs=1e-9)
        assert state.position[1] == pytest.approx(cell.belt.y + 0.03, abs=1e-12)
        assert state.position[2] == pytest.approx(cell.belt.height, abs=1e-12)
        # The machine was busy for 0.63 s: the belt still moves by speed x elapsed time, the
        # physics skips ahead (counted).
        sim.advance(101.0)
        assert sim.overruns == 1
        assert _state(sim, part).position[0] == pytest.approx(x0 + cell.belt.speed * 1.0, abs=1e-9)
        # The rendered body is where the ground truth says.
        body = sim.scene.body_of(part)
        assert p.getBasePositionAndOrientation(body, physicsClientId=sim.client)[0][0] == pytest.approx(
            x0 + cell.belt.speed * 1.0, abs=1e-6
        )
        # A time that is not later changes nothing.
        sim.advance(100.5)
        assert _state(sim, part).position[0] == pytest.approx(x0 + cell.belt.speed * 1.0, abs=1e-9)
        # A changed belt speed applies from now on.
        sim.belt_speed = 0.2
        sim.advance(102.0)
        assert _state(sim, part).position[0] == pytest.approx(x0 + cell.belt.speed * 1.0 + 0.2, abs=1e-9)
        assert sim.overruns == 2
    finally:
        sim.close()


def test_parts_past_the_belt_end_are_gone(sim, cell):
    sim.belt_speed = 0.5
    part = sim.spawn("bolt_silver")
    travel = cell.belt.x_end - (cell.belt.x_start + SPAWN_MARGIN)
    t_end = travel / 0.5
    sim.advance(t_end - 0.02)
    assert _state(sim, part).state == "belt" and part in sim.scene.parts
    sim.advance(t_end + 0.02)
    assert _state(sim, part).state == "gone"
    assert part not in sim.scene.parts
    assert [pose for pose in sim.render_poses() if pose[0] == part] == []
    sim.advance(t_end + 1.0)  # stays gone, is not moved any more
    assert _state(sim, part).state == "gone"


def test_magnet_grips_only_inside_grip_gap_and_grip_radius(sim, cell):
    gripper = cell.gripper
    assert gripper.grip_radius < 0.02 and gripper.grip_gap < 0.02
    part = sim.spawn("nut_silver", y_offset=0.0)
    others = [sim.spawn("nut_silver", y_offset=-0.08), sim.spawn("nut_silver", y_offset=0.08)]
    top = _top(cell, "nut_silver")
    sim.advance(1.0)

    def try_grip(dy, gap, magnet=True):
        t = sim.time + STEP
        x = _belt_x(sim, part) + sim.belt_speed * STEP  # where the part is at t
        sim.set_tool_pose(_tool_for_face(cell, [x, cell.belt.y + dy, top + gap]), DOWN)
        sim.set_magnet(magnet)
        sim.advance(t)
        return sim.held

    assert try_grip(0.0, 0.003, magnet=False) is None  # magnet off
    assert try_grip(0.02, 0.003) is None  # 2 cm to the side
    assert try_grip(0.0, 0.003 + 0.02) is None  # 2 cm too high
    assert try_grip(0.0, -0.004) is None  # face pushed into the part
    assert {s.state for s in sim.states()} == {"belt"}
    # Off-centre and a gap, but inside both limits: gripped, and only that part.
    held = try_grip(0.75 * gripper.grip_radius, 0.75 * gripper.grip_gap)
    assert held == part
    assert _state(sim, part).state == "held"
    assert all(_state(sim, other).state == "belt" for other in others)


def test_gripped_part_follows_the_tool(sim, cell):
    part = sim.spawn("bolt_yellow")
    sim.advance(0.5)
    x = _belt_x(sim, part) + sim.belt_speed * STEP
    sim.set_tool_pose(_tool_for_face(cell, [x, cell.belt.y, _top(cell, "bolt_yellow") + 0.003]), DOWN)
    sim.set_magnet(True)
    sim.advance(sim.time + STEP)
    assert sim.held == part
    offset = _state(sim, part).position - _face(sim)
    start = _face(sim)
    _move_face(sim, start + [0.0, 0.0, 0.10], speed=0.1)
    _move_face(sim, start + [0.10, -0.08, 0.10], speed=0.1)
    _wait(sim, 0.3)
    state = _state(sim, part)
    assert state.state == "held"
    moved = state.position - _face(sim)
    assert np.linalg.norm(moved - offset) < 0.003, (moved, offset)
    # The part really went up with the tool (not left on the belt).
    assert state.position[2] > cell.belt.height + 0.09


def _grip_from_belt(sim, cell, class_name, wait=0.3):
    part = sim.spawn(class_name, y_offset=0.02)
    _wait(sim, wait)
    x = _belt_x(sim, part) + sim.belt_speed * STEP
    sim.set_tool_pose(_tool_for_face(cell, [x, cell.belt.y + 0.02, _top(cell, class_name) + 0.003]), DOWN)
    sim.set_magnet(True)
    sim.advance(sim.time + STEP)
    assert sim.held == part, class_name
    return part


def test_released_over_a_slot_each_class_rests_in_that_slot(sim, cell):
    floor = cell.tray.position[2]
    for class_name in CLASS_NAMES:
        part = _grip_from_belt(sim, cell, class_name)
        slot = cell.tray.slot_for(class_name)
        above = np.r_[slot.center[:2], 0.20]
        _move_face(sim, np.r_[_face(sim)[:2], 0.20])
        _move_face(sim, above, speed=0.5)
        _move_face(sim, np.r_[slot.center[:2], floor + 0.015 + PART_CLASSES[class_name].height])
        sim.set_magnet(False)
        assert sim.held is None and _state(sim, part).state == "falling"
        _wait(sim, 1.0)
        state = _state(sim, part)
        assert (state.state, state.slot) == ("resting", class_name)
        assert slot.contains(state.position[:2])
        assert state.position[2] == pytest.approx(floor, abs=0.003)
    # Every part stayed in its own slot while the others were carried.
    assert sorted((s.slot, s.class_name) for s in sim.states()) == sorted((c, c) for c in CLASS_NAMES)


def test_released_over_the_floor_or_the_belt_rests_without_a_slot(sim, cell):
    floor_top = cell.belt.height - 0.35 + 0.005
    part = _grip_from_belt(sim, cell, "washer_silver")
    _move_face(sim, np.r_[_face(sim)[:2], 0.20])
    _move_face(sim, [-0.30, 0.30, 0.20], speed=0.5)  # beside the belt, away from the tray
    _wait(sim, 0.3)  # the part stops swinging
    sim.set_magnet(False)
    _wait(sim, 1.5)
    state = _state(sim, part)
    assert (state.state, state.slot) == ("resting", "")
    assert state.position[2] == pytest.approx(floor_top, abs=0.003)
    assert np.allclose(state.position[:2], [-0.30, 0.30], atol=0.02)

    part = _grip_from_belt(sim, cell, "nut_yellow")
    over_belt = _face(sim) + [0.0, 0.0, 0.03]
    _move_face(sim, over_belt)
    sim.set_magnet(False)
    _wait(sim, 1.0)
    state = _state(sim, part)
    assert (state.state, state.slot) == ("resting", "")
    assert state.position[2] == pytest.approx(cell.belt.height, abs=0.003)


def test_spawn_refuses_unknown_classes_and_off_belt_offsets(sim, cell):
    half = cell.belt.width / 2
    with pytest.raises(ValueError, match="unknown part class"):
        sim.spawn("screw_silver")
    for bad in (half, -half, half - 0.005, 1.0, math.nan, math.inf):
        with pytest.raises(ValueError, match="off the belt"):
            sim.spawn("nut_yellow", y_offset=bad)
    with pytest.raises(ValueError):
        sim.spawn("nut_yellow", yaw=math.nan)
    assert sim.parts == {} and sim.scene.parts == {}
    # The limits themselves are accepted, and so is the foreign object.
    sim.spawn("nut_yellow", y_offset=half - 0.011)
    sim.spawn(FOREIGN_CLASS)
    assert len(sim.parts) == 2


def test_non_finite_or_malformed_tool_poses_are_ignored(sim, cell):
    good = _tool_for_face(cell, [-0.3, 0.6, 0.2])
    sim.set_tool_pose(good, DOWN)
    for position, orientation in (
        ([math.nan, 0.6, 0.2], DOWN),
        ([math.inf, 0.6, 0.2], DOWN),
        (good, [math.nan, 0.0, 0.0, 1.0]),
        (good, [0.0, 0.0, 0.0, 0.0]),
        ([0.1, 0.2], DOWN),
        (good, [0.0, 0.0, 1.0]),
    ):
        sim.set_tool_pose(position, orientation)
        assert np.array_equal(sim.tool_position, good)
        assert np.allclose(sim.tool_orientation, DOWN)
    sim.advance(0.1)
    assert np.all(np.isfinite(_face(sim)))
    # A non-normalised quaternion is normalised.
    sim.set_tool_pose(good, [2.0, 0.0, 0.0, 0.0])
    assert np.allclose(sim.tool_orientation, DOWN)


def test_real_time_factor_is_one_when_keeping_up_and_shows_overruns(sim):
    for k in range(1, 201):
        sim.advance(k * STEP)
    assert sim.real_time_factor == pytest.approx(1.0, abs=0.03)
    assert sim.overruns == 0
    assert sim.steps == pytest.approx(2.0 / sim.time_step, abs=2)
    for k in range(1, 5):  # 0.5 s late every time: 0.25 s stepped of each
        sim.advance(2.0 + 0.5 * k)
    assert sim.overruns == 4
    assert sim.real_time_factor == pytest.approx(MAX_CATCH_UP / 0.5, abs=0.03)


# -- KittingPicker in a closed loop ------------------------------------------------------------
class StopError(Exception):
    """What the motion controller client raises on STOP (result code attached)."""

    def __init__(self, message, result):
        super().__init__(message)
        self.result = result


class FakeController:
    """A motion controller on a simulated clock: move_l is a straight line of the tool
    taking 0.3 s + distance / 0.5 m/s, stepped in STEP increments into ``sim`` (tool pose,
    clock); the camera sees the belt parts every ``frame_period`` s (x inside ``view``)
    with seeded noise and feeds them to ``observe``."""

    SPEED, OVERHEAD = 0.5, 0.3

    def __init__(self, sim, tool_position, seed=7, noise=0.0005, frame_period=0.1, view=(-0.60, 0.0)):
        self.sim = sim
        self.t = sim.time
        self.position = np.asarray(tool_position, float)
        self.orientation = np.asarray(DOWN, float)
        self.rng = np.random.default_rng(seed)
        self.noise, self.frame_period, self.view = noise, frame_period, view
        self.next_frame = self.t
        self.observe = None
        self.moves, self.gripper_calls, self.frames = [], [], 0
        self.fail_next_move = 0  # result code raised halfway through the next move_l
        self.before_move = None  # called with each move_l target before it starts
        self.blind_after_grip = False  # the camera stops delivering once the magnet is on
        self.blind = False
        sim.set_tool_pose(self.position, self.orientation)

    # -- the controller interface the picker uses
    def clock(self):
        return self.t

    def get_pose(self):
        return self.position.copy(), self.orientation.copy()

    def move_l(self, position, orientation):
        target = np.asarray(position, float)
        self.moves.append((self.t, target.copy()))
        if self.before_move is not None:
            self.before_move(target)
        self.orientation = np.asarray(orientation, float)
        start = self.position.copy()
        duration = self.OVERHEAD + float(np.linalg.norm(target - start)) / self.SPEED
        count = max(1, int(math.ceil(duration / STEP)))
        fail, self.fail_next_move = self.fail_next_move, 0
        for k in range(1, count + 1):
            if fail and k > count // 2:
                raise StopError("STOP pressed: motion stopped", fail)
            self.position = start + (target - start) * k / count
            self._tick(duration / count)

    def set_gripper(self, on):
        self.gripper_calls.append((self.t, bool(on)))
        self.blind = self.blind or (self.blind_after_grip and bool(on))
        self.sim.set_magnet(bool(on))

    def sleep(self, duration):
        end = self.t + max(0.0, float(duration))
        while self.t < end - 1e-9:
            self._tick(min(STEP, end - self.t))

    # -- the simulated world
    def _tick(self, dt):
        self.t += dt
        self.sim.set_tool_pose(self.position, self.orientation)
        self.sim.advance(self.t)
        if self.observe is not None and not self.blind and self.t >= self.next_frame - 1e-9:
            self.next_frame = self.t + self.frame_period
            self.frames += 1
            seen = [
                PartObservation(
                    s.class_name,
                    float(s.position[0] + self.rng.normal(0, self.noise)),
                    float(s.position[1] + self.rng.normal(0, self.noise)),
                    0.0,
                    0.9,
                    (0, 0),
                )
                for s in self.sim.states()
                if s.state == "belt" and self.view[0] <= s.position[0] <= self.view[1]
            ]
            self.observe(self.t, seen)


PICKER_PARAMS = {"descent_time": 0.46}  # the fake's descent (8 cm: 0.3 s + 0.08 / 0.5 s)


def _closed_loop(cell, params=None, **fake_args):
    sim = CellSimulation(cell)
    picker_params = dict(PICKER_PARAMS, **(params or {}))
    wait = KittingPicker(cell, None, picker_params).params["wait_position"]
    fake = FakeController(sim, wait, **fake_args)
    events = []
    picker = KittingPicker(cell, fake, picker_params, clock=fake.clock, sleep=fake.sleep, on_event=events.append)
    fake.observe = picker.observe
    return sim, fake, picker, events


def _run(picker, fake, events, until, timeout=40.0):
    """run_once until an event in ``until`` (or the timeout of simulated time)."""
    while fake.t < timeout:
        if any(e.event in until for e in events):
            return
        if picker.run_once() is None:
            fake.sleep(0.1)
    raise AssertionError(f"no {until} event within {timeout} s: {[(e.event, e.reason) for e in events]}")


@pytest.mark.parametrize("class_name", CLASS_NAMES)
def test_closed_loop_each_class_ends_in_its_slot(cell, class_name):
    sim, fake, picker, events = _closed_loop(cell, seed=CLASS_NAMES.index(class_name))
    try:
        part = sim.spawn(
            class_name, y_offset=0.04 * (CLASS_NAMES.index(class_name) % 3 - 1), yaw=0.3 * CLASS_NAMES.index(class_name)
        )
        _run(picker, fake, events, ("placed", "skipped", "failed", "missed"))
        fake.sleep(1.0)  # the released part settles
        assert [e.event for e in events] == ["tracked", "planned", "picked", "placed"], [
            (e.event, e.reason) for e in events
        ]
        assert len({e.track_id for e in events}) == 1 and events[0].class_name == class_name
        assert events[-1].reason == f"slot {class_name}"
        state = _state(sim, part)
        assert (state.state, state.slot) == ("resting", class_name)
        # The magnet went on once (at the hover point) and off once (over the slot).
        assert [on for _, on in fake.gripper_calls] == [True, False]
        # The pick happened inside the pick window (planned inside it on the track of the
        # plan's time; the grasp is re-predicted from the newest sightings, which moves it
        # by up to ~2 cm for a part planned as soon as it is confirmed).
        picked = next(e for e in events if e.event == "picked")
        x_min, x_max = picker.params["pick_window"]
        assert x_min - 0.02 <= picked.position[0] <= x_max + 0.02
        assert len(picker.cycle_times) == 1 and picker.cycle_times[0] > 0
    finally:
        sim.close()


def test_closed_loop_pick_without_an_image_after_the_lift_is_marked_unverified_and_not_placed(cell):
    sim, fake, picker, events = _closed_loop(cell)
    fake.blind_after_grip = True  # e.g. the camera lost its registration mid-pick
    try:
        part = sim.spawn("nut_silver")
        _run(picker, fake, events, ("placed", "skipped", "failed", "missed"))
        fake.sleep(1.0)
        picked = [e for e in events if e.event == "picked"]
        assert len(picked) == 1 and picked[0].reason.startswith("unverified: no camera image since the lift"), [
            (e.event, e.reason) for e in events
        ]
        assert not picked[0].verified  # the typed flag the campaign counts, not the text
        # Released over the slot (where it does land), but without evidence never "placed".
        assert events[-1].event == "failed" and "no evidence" in events[-1].reason
        assert (_state(sim, part).state, _state(sim, part).slot) == ("resting", "nut_silver")
    finally:
        sim.close()


def test_closed_loop_with_images_after_the_lift_the_pick_is_verified(cell):
    sim, fake, picker, events = _closed_loop(cell)
    try:
        sim.spawn("nut_silver")
        _run(picker, fake, events, ("placed", "skipped", "failed", "missed"))
        assert [e.reason for e in events if e.event == "picked"] == [""]
    finally:
        sim.close()


def test_closed_loop_part_too_fast_for_the_pick_window_is_skipped(cell):
    fast = replace(cell, belt=replace(cell.belt, speed=0.4))
    sim, fake, picker, events = _closed_loop(fast)
    try:
        part = sim.spawn("nut_yellow")
        _run(picker, fake, events, ("skipped", "placed", "failed", "missed"), timeout=10.0)
        assert [e.event for e in events] == ["tracked", "skipped"], [(e.event, e.reason) for e in events]
        assert "reach window" in events[-1].reason
        assert fake.moves == [] and fake.gripper_calls == []
        # Not tried again: the part rides off the belt's end.
        fake.sleep(0.5)
        assert picker.run_once() is None
        fake.sleep(4.0)
        assert _state(sim, part).state == "gone"
    finally:
        sim.close()


def test_closed_loop_stop_during_the_carry_fails_and_keeps_the_part(cell):
    sim, fake, picker, events = _closed_loop(cell)

    def stop_after_pick(event):
        events.append(event)
        if event.event == "picked":
            fake.fail_next_move = 15  # STOP: the next move is interrupted

    picker.on_event = stop_after_pick
    try:
        part = sim.spawn("bolt_silver")
        _run(picker, fake, events, ("placed", "skipped", "failed", "missed"))
        assert [e.event for e in events] == ["tracked", "planned", "picked", "failed"], [
            (e.event, e.reason) for e in events
        ]
        assert "move refused or interrupted" in events[-1].reason
        fake.sleep(1.0)
        # The magnet was never switched off: the part hangs on it.
        assert [on for _, on in fake.gripper_calls] == [True]
        assert sim.held == part and _state(sim, part).state == "held"
        assert picker.holding is not None
        assert picker.run_once() is None  # the part is done: no new cycle for it
        # After the latch is released, recovery carries the held part to its slot.
        event = picker.place_held()
        fake.sleep(1.0)
        assert event.event == "placed" and picker.holding is None
        state = _state(sim, part)
        assert (state.state, state.slot) == ("resting", "bolt_silver")
    finally:
        sim.close()


def test_closed_loop_stop_during_the_lift_keeps_the_gripped_part_on_the_magnet(cell):
    sim, fake, picker, events = _closed_loop(cell)
    stopped = []

    def stop_once_gripped(target):
        if sim.held is not None and not stopped:  # the descent gripped the part
            stopped.append(sim.held)
            fake.fail_next_move = 15  # STOP during the lift

    fake.before_move = stop_once_gripped
    try:
        part = sim.spawn("nut_silver")
        _run(picker, fake, events, ("placed", "skipped", "failed", "missed"))
        assert stopped == [part]
        assert [e.event for e in events] == ["tracked", "planned", "failed"]
        assert "move refused or interrupted" in events[-1].reason
        assert "magnet stays on" in events[-1].reason
        fake.sleep(1.0)
        assert [on for _, on in fake.gripper_calls] == [True]
        assert sim.held == part and _state(sim, part).state == "held"
        # Once the stop is released the held part goes to its slot.
        picker.place_held()
        fake.sleep(2.0)
        assert _state(sim, part).state == "resting" and _state(sim, part).slot == "nut_silver"
    finally:
        sim.close()


def test_check_segment_refuses_paths_through_the_belt_and_accepts_paths_above(cell):
    obstacles = cell_obstacles(cell)
    belt = cell.belt
    clearance = 0.004
    through = check_segment([-0.3, belt.y, 0.20], [-0.3, belt.y, belt.height - 0.02], obstacles, clearance)
    assert "belt" in through
    grazing = check_segment(
        [-0.5, belt.y, belt.height + 0.002], [0.0, belt.y, belt.height + 0.002], obstacles, clearance
    )
    assert "belt" in grazing and "2.0 mm" in grazing
    assert check_segment([-0.5, belt.y, 0.20], [0.0, belt.y + 0.05, 0.15], obstacles, clearance) == ""
    assert (
        check_segment([-0.5, belt.y, belt.height + 0.01], [0.0, belt.y, belt.height + 0.01], obstacles, clearance) == ""
    )
    # The descent onto a part: its end is allowed to come closer, its start is not.
    descent = ([-0.3, belt.y, belt.height + 0.09], [-0.29, belt.y, belt.height + 0.003])
    assert "belt" in check_segment(*descent, obstacles, clearance)
    assert check_segment(*descent, obstacles, clearance, allowed_end=0.10) == ""
    # The tray plate is an obstacle too.
    tray = cell.tray.position
    assert "tray" in check_segment([tray[0], tray[1], 0.2], [tray[0], tray[1], tray[2] - 0.02], obstacles, clearance)


# -- campaign ----------------------------------------------------------------------------------
def _as_tuple(trial):
    return (
        trial.index,
        trial.class_name,
        trial.y_offset,
        trial.yaw,
        repr(trial.belt_speed),
        repr(trial.light_level),
        tuple(trial.camera_offset),
    )


def test_plan_trials_cycles_the_classes_and_is_reproducible():
    trials = plan_trials(13, seed=4, perturb=False, belt_speed=0.05)
    assert [t.class_name for t in trials] == [CLASS_NAMES[i % 6] for i in range(13)]
    assert [t.index for t in trials] == list(range(13))
    assert [_as_tuple(t) for t in trials] == [_as_tuple(t) for t in plan_trials(13, 4, False, 0.05)]
    assert [t.y_offset for t in trials] != [t.y_offset for t in plan_trials(13, 5, False, 0.05)]
    for trial in trials:
        assert abs(trial.y_offset) <= 0.06 and -math.pi <= trial.yaw <= math.pi
        assert math.isnan(trial.belt_speed) and trial.camera_offset == []
    assert len({round(t.y_offset, 6) for t in trials}) == 13  # really drawn, not constant
    assert all(abs(t.y_offset) <= 0.02 for t in plan_trials(20, 1, False, 0.05, max_y_offset=0.02))


def test_plan_trials_perturbations_lie_in_the_documented_ranges():
    trials = plan_trials(300, seed=11, perturb=True, belt_speed=0.05)
    assert [_as_tuple(t) for t in trials] == [_as_tuple(t) for t in plan_trials(300, 11, True, 0.05)]
    speeds = np.array([t.belt_speed for t in trials])
    offsets = np.array([t.camera_offset for t in trials])
    lights = np.array([t.light_level for t in trials])
    assert offsets.shape == (300, 6)
    assert np.all((speeds >= 0.05 * 0.7) & (speeds <= 0.05 * 1.3))
    assert np.all(np.abs(offsets[:, :3]) <= 0.02)
    assert np.all(np.abs(offsets[:, 3:]) <= math.radians(2.0) + 1e-12)
    assert np.all((lights >= 0.7) & (lights <= 1.2))
    # The ranges are used, not a sliver of them.
    assert speeds.min() < 0.05 * 0.75 and speeds.max() > 0.05 * 1.25
    assert np.abs(offsets[:, :3]).max() > 0.018 and np.abs(offsets[:, 3:]).max() > math.radians(1.8)


def _stats_scenario():
    """Four parts: two placed right, one misclassified (put in the wrong slot), one never seen."""
    stats = CampaignStats(match_radius=0.03)
    classes = {1: "nut_yellow", 2: "bolt_silver", 3: "washer_silver", 4: "washer_yellow"}
    for part_id, name in classes.items():
        stats.add_part(Trial(part_id - 1, name, 0.0, 0.0), part_id, now=10.0 * (part_id - 1))
    truth = [
        (1, -0.30, 0.70, "belt"),
        (2, -0.40, 0.65, "belt"),
        (3, -0.50, 0.75, "belt"),
        (4, -0.20, 0.70, "belt"),
        (99, -0.1, 0.7, "belt"),
    ]  # 99: not a campaign part
    # Sightings offset by known distances: 1, 2 (part 1); 3, 4 (part 2, misclassified twice,
    # right once at 5 mm); part 4 at 1 mm; a far sighting; a sighting of a held part.
    stats.add_observation(
        truth,
        [
            ("nut_yellow", -0.299, 0.70),
            ("bolt_yellow", -0.40, 0.653),
            ("washer_yellow", -0.20, 0.701),
            ("nut_silver", 0.30, 0.0),
        ],
    )
    stats.add_observation(truth, [("nut_yellow", -0.30, 0.702), ("bolt_yellow", -0.404, 0.65)])
    stats.add_observation(
        [(1, -0.25, 0.70, "held"), (2, -0.40, 0.65, "belt")],
        [("nut_yellow", -0.25, 0.70), ("bolt_silver", -0.403, 0.654)],
    )
    for part_id, events in {
        1: ["tracked", "planned", "picked", "placed"],
        2: ["tracked", "planned", "picked", "placed"],
        4: ["tracked", "planned", "picked: unverified: no camera image since the lift", "placed"],
    }.items():
        for event in events:
            # The kitting node says whether the camera confirmed a pick (KittingEvent.verified).
            stats.add_event(part_id, event, verified="unverified" not in event)
    stats.add_event(42, "picked")  # unknown part: ignored
    stats.resolve(1, "resting", "nut_yellow", 30.0)
    stats.resolve(2, "resting", "bolt_yellow", 40.0)
    stats.resolve(3, "gone", "", 50.0, reason="never seen")
    stats.resolve(4, "resting", "washer_yellow", 70.0)
    return stats


def test_campaign_stats_on_a_hand_made_scenario():
    stats = _stats_scenario()
    summary = stats.summary()
    assert summary["trials"] == 4 and summary["successes"] == 2
    assert summary["success_rate"] == pytest.approx(0.5)
    assert summary["unmatched_detections"] == 2  # the far one and the held one
    assert summary["unverified_picks"] == 1  # part 4's pick
    errors = [1.0, 3.0, 1.0, 2.0, 4.0, 5.0]  # mm, as the sightings were placed
    assert summary["pose_samples"] == len(errors)
    assert summary["pose_error_mm_p50"] == pytest.approx(2.5, abs=1e-6)
    assert summary["pose_error_mm_p95"] == pytest.approx(4.75, abs=1e-6)  # 4 + 0.75 x (5 - 4)
    # 2 successes between the first spawn (0 s) and the last resolution (70 s).
    assert summary["picks_per_minute"] == pytest.approx(2 / (70.0 / 60.0))
    # spawn -> place of the successes: 30 s (part 1) and 40 s (part 4)
    assert summary["spawn_to_place_s_p50"] == pytest.approx(35.0)
    failures = {f["class"]: f for f in summary["failures"]}
    assert set(failures) == {"bolt_silver", "washer_silver"}
    assert failures["bolt_silver"]["predicted"] == "bolt_yellow" and failures["bolt_silver"]["slot"] == "bolt_yellow"
    assert failures["washer_silver"]["predicted"] == UNKNOWN and failures["washer_silver"]["reason"] == "never seen"

    table = summary["per_class"]
    assert table["nut_yellow"] == {
        "trials": 1,
        "detected": 1,
        "classified": 1,
        "picked": 1,
        "placed": 1,
        "pose_error_mm_p95": pytest.approx(np.percentile([1.0, 2.0], 95)),
    }
    row = table["bolt_silver"]
    assert (row["trials"], row["detected"], row["classified"], row["picked"], row["placed"]) == (1, 1, 0, 1, 0)
    row = table["washer_silver"]
    assert (row["trials"], row["detected"], row["classified"], row["picked"], row["placed"]) == (1, 0, 0, 0, 0)
    assert math.isnan(row["pose_error_mm_p95"])
    assert table["nut_silver"]["trials"] == 0 and table["bolt_yellow"]["trials"] == 0
    assert table["washer_yellow"]["picked"] == 1  # an unverified pick is still a pick

    matrix = stats.confusion()
    labels = list(CLASS_NAMES) + [UNKNOWN]
    assert matrix.shape == (6, 7) and matrix.sum() == 4
    expected = np.zeros((6, 7), int)
    for true, predicted in (
        ("nut_yellow", "nut_yellow"),
        ("bolt_silver", "bolt_yellow"),
        ("washer_silver", UNKNOWN),
        ("washer_yellow", "washer_yellow"),
    ):
        expected[CLASS_NAMES.index(true), labels.index(predicted)] += 1
    assert np.array_equal(matrix, expected)
    text = stats.table()
    assert len(text.splitlines()) == 7 and "bolt_silver" in text


def test_plot_confusion_writes_a_png(tmp_path):
    path = tmp_path / "confusion.png"
    _stats_scenario().plot_confusion(str(path))
    data = path.read_bytes()
    assert data[:8] == b"\x89PNG\r\n\x1a\n" and len(data) > 5000
    image = cv2.imread(str(path))
    assert image is not None and image.shape[0] > 300 and image.shape[1] > 400
    assert [f.name for f in tmp_path.iterdir()] == ["confusion.png"]  # no temporary left over


# -- VisionPipeline on rendered images ---------------------------------------------------------
VISION_PARTS = (
    ("nut_yellow", -0.42, 0.66, 0.4),
    ("bolt_silver", -0.30, 0.74, 1.1),
    ("washer_yellow", -0.18, 0.70, 0.0),
)


@pytest.fixture(scope="module")
def rendered(cell):
    """Images of three parts on the belt: from the cell's camera, and from the camera moved
    by 2 cm and 1 degree."""
    client = p.connect(p.DIRECT)
    try:
        scene = SimScene(client, cell)
        for name, x, y, yaw in VISION_PARTS:
            scene.add_part(name, x, y, yaw)
        camera = PinholeCamera.from_spec(cell.camera)
        moved_pose = camera.pose.copy()
        tilt = cv2.Rodrigues(np.radians([0.6, 0.0, 0.8]))[0]  # about 1 degree
        moved_pose[:3, :3] = tilt @ moved_pose[:3, :3]
        moved_pose[:3, 3] += [0.02, 0.0, 0.0]
        moved = camera.with_pose(moved_pose)
        return {"camera": camera, "image": render(client, camera), "moved": moved, "moved_image": render(client, moved)}
    finally:
        p.disconnect(client)


def _pipeline(cell, camera):
    return VisionPipeline(cell, camera.K, camera.distortion, camera.width, camera.height)


def _assert_parts_located(result, tolerance=0.003):
    assert result.ok, result.reason
    assert sorted(o.class_name for o in result.parts) == sorted(name for name, *_ in VISION_PARTS)
    for name, x, y, _ in VISION_PARTS:
        seen = next(o for o in result.parts if o.class_name == name)
        assert math.hypot(seen.x - x, seen.y - y) < tolerance, (name, seen.x - x, seen.y - y)


def test_pipeline_registers_from_the_markers_and_locates_parts(cell, rendered):
    camera = rendered["camera"]
    pipeline = _pipeline(cell, camera)
    result = pipeline.process(rendered["image"], 1.0)
    _assert_parts_located(result)
    assert result.reason == "" and result.rejections == []
    position_error, angle_error = pose_error(pipeline.camera_pose, camera.pose)
    # Sanity of the pose itself (TinyRenderer images are not anti-aliased: the marker
    # corners are quantised to pixels, the pose is off by a few mm / tenths of a degree
    # mostly along the optical axis; what matters is the part positions above).
    assert position_error < 0.008 and angle_error < 0.8
    assert pipeline.registration_time == 1.0 and pipeline.counts["parts"] == 3
    assert pipeline.counts["camera moved: re-registered"] == 0


def test_pipeline_re_registers_a_moved_camera(cell, rendered):
    pipeline = _pipeline(cell, rendered["camera"])
    for stamp in (1.0, 1.1):
        _assert_parts_located(pipeline.process(rendered["image"], stamp))
    assert pipeline.counts["camera moved: re-registered"] == 0
    moved = rendered["moved"]
    assert pose_error(moved.pose, rendered["camera"].pose)[0] == pytest.approx(0.02, abs=1e-9)
    result = pipeline.process(rendered["moved_image"], 1.2)
    assert pipeline.counts["camera moved: re-registered"] == 1
    _assert_parts_located(result)
    position_error, angle_error = pose_error(pipeline.camera_pose, moved.pose)
    # Sanity of the pose itself (TinyRenderer images are not anti-aliased: the marker
    # corners are quantised to pixels, the pose is off by a few mm / tenths of a degree
    # mostly along the optical axis; what matters is the part positions above).
    assert position_error < 0.008 and angle_error < 0.8
    # The average restarted from the moved pose: the old registrations are not mixed in.
    assert len(pipeline._registrations) == 1
    _assert_parts_located(pipeline.process(rendered["moved_image"], 1.3))
    assert pipeline.counts["camera moved: re-registered"] == 1


def _cover_markers(cell, camera, image, marker_ids=None):
    """The image with the cell's markers (or only those in ``marker_ids``) painted over (grey)."""
    covered = image.copy()
    for marker in cell.markers:
        if marker_ids is not None and marker.id not in marker_ids:
            continue
        _, ratio = marker_image(marker.dictionary, marker.id)
        half = marker.size * ratio / 2 + 0.005
        corners = (
            marker.pose
            @ np.array([[-half, half, 0, 1], [half, half, 0, 1], [half, -half, 0, 1], [-half, -half, 0, 1]]).T
        ).T[:, :3]
        cv2.fillConvexPoly(covered, np.round(camera.project(corners)).astype(np.int32), (128, 128, 128))
    return covered


def test_pipeline_without_markers_publishes_no_parts_before_registration(cell, rendered):
    camera = rendered["camera"]
    covered = _cover_markers(cell, camera, rendered["image"])
    assert np.any(covered != rendered["image"])
    pipeline = _pipeline(cell, camera)
    result = pipeline.process(covered, 1.0)
    assert not result.ok and result.parts == []
    assert "no marker" in result.reason and "registration" in result.reason
    assert pipeline.counts["no registration: parts not published"] == 1
    assert pipeline.camera_pose is None
    # Registered once, a covered frame keeps the registration for registration_max_age s.
    pipeline.process(rendered["image"], 2.0)
    kept = pipeline.process(covered, 2.0 + 0.5 * pipeline.params["registration_max_age"])
    _assert_parts_located(kept)
    assert kept.reason == "no marker"
    stale = pipeline.process(covered, 2.0 + 2.0 * pipeline.params["registration_max_age"])
    assert not stale.ok and stale.parts == []
    assert pipeline.counts["no registration: parts not published"] == 2


def test_pipeline_rejects_corrupt_images(cell, rendered):
    camera = rendered["camera"]
    pipeline = _pipeline(cell, camera)
    rng = np.random.default_rng(3)
    bad_images = (
        None,
        np.zeros((camera.height, camera.width, 3), np.uint8),  # blank
        rng.integers(0, 255, (camera.height // 2, camera.width // 2, 3), dtype=np.uint8),  # wrong size
        rng.integers(0, 255, (camera.height, camera.width), dtype=np.uint8),  # grey
        rendered["image"].astype(np.float32),
    )  # wrong dtype
    for k, bad in enumerate(bad_images):
        result = pipeline.process(bad, float(k))
        assert not result.ok and result.parts == [] and result.reason.startswith("corrupt image"), result.reason
    assert pipeline.counts["corrupt image"] == len(bad_images)
    assert "blank" in pipeline.process(bad_images[1], 9.0).reason
    assert "640x480" in pipeline.process(bad_images[2], 9.0).reason
    assert pipeline.camera_pose is None and pipeline.counts["parts"] == 0
    # A good image afterwards is processed normally.
    _assert_parts_located(pipeline.process(rendered["image"], 10.0))


def test_the_descent_is_timed_on_the_controller_before_the_first_pick(cell):
    _, fake, picker, _ = _closed_loop(cell, {"descent_time": 0.2})
    picker.go_to_wait()
    moves = len(fake.moves)
    took = picker.measure_descent()
    length = picker.params["hover_height"] - picker.params["grasp_gap"]
    # The fake controller takes 0.3 s + distance / 0.5 m/s per move (STEP-quantised).
    assert took == pytest.approx(FakeController.OVERHEAD + length / FakeController.SPEED, abs=2 * STEP)
    assert picker.descent_time == took
    # Down and back: the tool ends where it started, clear of the belt.
    assert len(fake.moves) == moves + 2
    assert np.allclose(fake.moves[-1][1], fake.moves[-2][1] + [0.0, 0.0, length], atol=1e-9)
