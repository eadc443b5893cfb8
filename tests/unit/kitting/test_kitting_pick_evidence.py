"""A pick is never reported done without evidence (kitting.picker.KittingPicker, closed loop
on the simulated cell with a fake controller and an injected clock): no descent on a pose
older than max_pose_age, an unconfirmed pick is checked again above the slot (camera, else
the gripper's part sensor), and a part that is not where it should be is 'failed', not
'placed'."""

import pytest

from kitting.cell import load_cell

from .test_kitting_cell import _closed_loop, _run, _state

END = ("placed", "skipped", "failed", "missed")


@pytest.fixture(scope="module")
def cell():
    return load_cell()


def _with_sensor(picker, sim):
    """The simulated magnet's part sensor: True while it holds a part."""
    picker.part_present = lambda: sim.held is not None


def test_a_part_last_seen_longer_ago_than_max_pose_age_is_not_picked(cell):
    sim, fake, picker, events = _closed_loop(cell, {"max_pose_age": 0.5})
    try:
        sim.spawn("washer_silver")
        while not picker.candidates():
            fake.sleep(0.1)
        fake.blind = True  # the camera stops delivering (e.g. registration lost)
        fake.sleep(0.6)
        assert picker.candidates() == [] and picker.run_once() is None
        assert fake.moves == []
        fake.blind = False  # fresh sightings: the same track is picked
        _run(picker, fake, events, END)
        assert events[-1].event == "placed", [(e.event, e.reason) for e in events]
    finally:
        sim.close()


def test_a_descent_about_to_start_on_a_stale_pose_is_deferred_and_retried(cell):
    sim, fake, picker, events = _closed_loop(cell, {"max_pose_age": 0.2})
    moves = []

    def blind_during_first_hover(target):
        moves.append(target)
        fake.blind = len(moves) == 1  # the hover move takes >= 0.3 s without images

    fake.before_move = blind_during_first_hover

    def see_again_once_deferred(event):
        events.append(event)
        if event.event == "missed":
            fake.blind = False

    picker.on_event = see_again_once_deferred
    try:
        part = sim.spawn("bolt_yellow")
        _run(picker, fake, events, ("missed", "failed", "placed"))
        deferred = events[-1]
        assert deferred.event == "missed" and deferred.reason.startswith("deferred: the part was last seen"), [
            (e.event, e.reason) for e in events
        ]
        assert [on for _, on in fake.gripper_calls] == [True, False]  # nothing touched, magnet off
        assert _state(sim, part).state == "belt"
        _run(picker, fake, events, ("placed", "failed", "skipped"))
        fake.sleep(1.0)
        assert events[-1].event == "placed"
        assert (_state(sim, part).state, _state(sim, part).slot) == ("resting", "bolt_yellow")
    finally:
        sim.close()


def test_an_unconfirmed_pick_confirmed_by_the_part_sensor_is_placed(cell):
    sim, fake, picker, events = _closed_loop(cell, {"max_pose_age": 10.0})
    _with_sensor(picker, sim)
    fake.blind_after_grip = True
    try:
        part = sim.spawn("nut_silver")
        _run(picker, fake, events, END)
        picked = next(e for e in events if e.event == "picked")
        assert not picked.verified
        assert events[-1].event == "placed", [(e.event, e.reason) for e in events]
        assert "confirmed by the gripper's part sensor" in events[-1].reason
        fake.sleep(1.0)
        assert (_state(sim, part).state, _state(sim, part).slot) == ("resting", "nut_silver")
    finally:
        sim.close()


def test_an_unconfirmed_pick_without_any_evidence_is_failed_not_placed(cell):
    sim, fake, picker, events = _closed_loop(cell, {"max_pose_age": 10.0})
    fake.blind_after_grip = True  # no image after the lift, no part sensor
    try:
        sim.spawn("nut_yellow")
        _run(picker, fake, events, END)
        assert [e.event for e in events][-2:] == ["picked", "failed"], [(e.event, e.reason) for e in events]
        assert "no evidence the part is held" in events[-1].reason
        assert not events[-1].verified
    finally:
        sim.close()


def test_a_part_sensor_reading_no_part_above_the_slot_fails_the_pick(cell):
    sim, fake, picker, events = _closed_loop(cell, {"max_pose_age": 10.0})
    picker.part_present = lambda: False
    fake.blind_after_grip = True
    try:
        sim.spawn("washer_yellow")
        _run(picker, fake, events, END)
        assert events[-1].event == "failed" and "part sensor reads no part" in events[-1].reason
    finally:
        sim.close()


def test_a_grasp_that_missed_seen_on_the_belt_during_the_carry_is_never_released_as_placed(cell):
    # The camera is blind while the magnet is on and sees again during the carry: the miss
    # check, overlapped with the carry, finds the part on the belt above the slot, before
    # any release; the part is retried (never placed) while it is reachable.
    sim, fake, picker, events = _closed_loop(cell, {"max_pose_age": 10.0})
    real_set_gripper = fake.set_gripper

    def magnet_that_never_grips(on):
        fake.gripper_calls.append((fake.t, bool(on)))  # switched, but the part stays on the belt
        fake.blind = bool(on)

    fake.set_gripper = magnet_that_never_grips

    def camera_back_during_carry(target):
        if target[2] > 0.2 and fake.blind and picker.holding is not None:
            fake.blind = False  # images of the carry arrive (after the lift)

    fake.before_move = camera_back_during_carry
    try:
        part = sim.spawn("bolt_silver")
        _run(picker, fake, events, ("missed",))
        assert events[-1].reason == "missed: the part is still on the belt after the lift", [
            (e.event, e.reason) for e in events
        ]
        assert [on for _, on in fake.gripper_calls] == [True]  # never released over the slot
        assert picker.holding is None
        while fake.t < 30.0:  # retried while reachable, then left to ride off
            if picker.run_once() is None:
                fake.sleep(0.1)
        assert "placed" not in [e.event for e in events], [(e.event, e.reason) for e in events]
        assert _state(sim, part).state in ("belt", "gone")
    finally:
        fake.set_gripper = real_set_gripper
        sim.close()


def test_a_part_still_on_the_magnet_after_the_release_is_failed(cell):
    sim, fake, picker, events = _closed_loop(cell)
    picker.part_present = lambda: True  # a stuck part (residual magnetism)
    try:
        sim.spawn("washer_silver")
        _run(picker, fake, events, END)
        assert events[-1].event == "failed" and "still on the magnet" in events[-1].reason
    finally:
        sim.close()


def test_after_a_pick_that_did_not_happen_the_arm_clears_the_cameras_view(cell):
    # The camera sees the cell only while the arm waits at its wait position: anywhere over
    # the belt the arm hides the markers (as a perturbed camera can make it), so the part is
    # never seen again while the arm hovers.
    sim, fake, picker, events = _closed_loop(cell, {"max_pose_age": 0.2})
    wait = picker.params["wait_position"]

    def blind_away_from_wait(target):
        fake.blind = bool(max(abs(a - b) for a, b in zip(target, wait)) > 1e-6)

    fake.before_move = blind_away_from_wait
    try:
        sim.spawn("nut_silver")
        _run(picker, fake, events, ("missed", "failed", "placed"))
        assert events[-1].event == "missed" and events[-1].reason.startswith("deferred"), [
            (e.event, e.reason) for e in events
        ]
        # Back at the wait position: the camera sees the belt again.
        assert list(fake.moves[-1][1]) == pytest.approx(wait)
        assert not fake.blind
    finally:
        sim.close()
