"""Kits in the cell (plain Python, injected clock): one part per slot until the tray is
swapped, the earliest deadline first among several parts on the belt, the simulated tray
swap, and the campaign's kit and miss figures."""

import math

import numpy as np
import pytest

from kitting.campaign import CampaignStats, Trial, plan_trials
from kitting.cell import load_cell
from kitting.kits import Kit, score_kit

from .test_kitting_cell import _closed_loop, _run, _state

END = ("placed", "failed")


def _until(fake, condition, timeout=20.0):
    """Advance the fake's clock until ``condition()`` (bounded: the test fails instead of hanging)."""
    end = fake.t + timeout
    while not condition():
        assert fake.t < end, "condition not met in simulated time"
        fake.sleep(0.1)


@pytest.fixture(scope="module")
def cell():
    return load_cell()


def test_one_part_per_slot_until_the_tray_is_swapped(cell):
    sim, fake, picker, events = _closed_loop(cell)
    trays = []  # what the node publishes on kitting/tray
    picker.on_tray = trays.append
    slots = [slot.part_class for slot in cell.tray.slots]
    try:
        first = sim.spawn("nut_yellow", y_offset=0.03)
        _run(picker, fake, events, END)
        assert events[-1].event == "placed" and picker.filled == {"nut_yellow"}
        assert trays == [{"slots": slots, "filled": ["nut_yellow"], "complete": False}]
        second = sim.spawn("nut_yellow", y_offset=-0.03)
        fake.sleep(12.0)  # into the pick window and beyond: its slot is full, it is left alone
        assert picker.run_once() is None
        assert [e.event for e in events].count("placed") == 1 and picker.candidates() == []
        assert _state(sim, second).state == "belt"
        picker.tray_swapped()
        assert picker.filled == set() and trays[-1]["filled"] == [] and not trays[-1]["complete"]
        third = sim.spawn("nut_yellow")
        events.clear()
        _run(picker, fake, events, END, timeout=fake.t + 40.0)
        assert events[-1].event == "placed"
        fake.sleep(1.0)
        assert _state(sim, first).slot == "nut_yellow" and _state(sim, third).slot == "nut_yellow"
    finally:
        sim.close()


def test_the_tray_state_says_when_the_kit_is_complete(cell):
    sim, fake, picker, events = _closed_loop(cell)
    try:
        slots = [slot.part_class for slot in cell.tray.slots]
        picker.filled.update(slots[:-1])
        assert picker.tray_state() == {"slots": slots, "filled": slots[:-1], "complete": False}
        picker.filled.add(slots[-1])
        assert picker.tray_state()["complete"]
    finally:
        sim.close()


def test_the_part_leaving_the_window_first_is_picked_first_and_unreachable_ones_are_skipped(cell):
    sim, fake, picker, events = _closed_loop(cell)
    try:
        behind = sim.spawn("washer_yellow", y_offset=-0.04)
        fake.sleep(2.0)  # 10 cm apart on the belt
        ahead = sim.spawn("bolt_silver", y_offset=0.04)
        # Both seen: the later-spawned one is upstream; the other leaves the window first.
        _until(fake, lambda: len(picker.candidates()) >= 2)
        order = [t.class_name for t in picker.candidates()]
        assert order == ["washer_yellow", "bolt_silver"]
        assert picker.deadline(picker.candidates()[0]) < picker.deadline(picker.candidates()[1])
        _run(picker, fake, events, END)
        first = [e for e in events if e.event in END][0]
        assert first.class_name == "washer_yellow" and first.event == "placed"
        assert _state(sim, behind).state != "belt" and ahead
    finally:
        sim.close()


def test_a_part_that_can_no_longer_be_reached_is_skipped_and_the_next_one_planned(cell):
    sim, fake, picker, events = _closed_loop(cell)
    try:
        sim.spawn("nut_silver")
        _until(fake, lambda: picker.candidates())
        fake.sleep(5.5)  # once the second part is in view, the first is near the window's end: too late
        sim.spawn("washer_silver")
        _until(fake, lambda: len(picker.candidates()) >= 2)
        event = picker.run_once()
        skipped = [e for e in events if e.event == "skipped"]
        assert [e.class_name for e in skipped] == ["nut_silver"], [(e.event, e.reason) for e in events]
        assert event is not None and event.class_name == "washer_silver"
    finally:
        sim.close()


def test_clear_tray_removes_the_tray_parts_only(cell):
    sim, fake, picker, events = _closed_loop(cell)
    try:
        placed = sim.spawn("bolt_yellow")
        _run(picker, fake, events, END)
        fake.sleep(1.0)
        on_belt = sim.spawn("nut_yellow")
        assert _state(sim, placed).state == "resting"
        assert sim.clear_tray() == 1
        assert placed not in {s.part_id for s in sim.states()}
        assert _state(sim, on_belt).state == "belt"
        assert sim.clear_tray() == 0
    finally:
        sim.close()


def test_plan_trials_takes_the_kit_feed_and_keeps_the_seeded_draws():
    plain = plan_trials(6, 3, True, 0.05)
    kitted = plan_trials(6, 3, True, 0.05, classes=["nut_silver"] * 6, kits=[0, 0, 0, 1, 1, 1])
    assert [t.class_name for t in kitted] == ["nut_silver"] * 6 and [t.kit for t in kitted] == [0, 0, 0, 1, 1, 1]
    assert [(t.y_offset, t.yaw, t.belt_speed) for t in plain] == [(t.y_offset, t.yaw, t.belt_speed) for t in kitted]


def test_campaign_summary_has_kit_scores_misses_and_the_arrival_rate():
    stats = CampaignStats()
    classes = ["bolt_yellow", "nut_yellow", "washer_yellow"]
    for k, name in enumerate(classes):
        stats.add_part(Trial(k, name, 0.0, 0.0), k + 1, 10.0 + 15.0 * k)  # 4 parts/min
    stats.add_event(1, "picked")
    stats.resolve(1, "resting", "bolt_yellow", 30.0)
    stats.resolve(2, "gone", "", 60.0)  # rode off unpicked: a miss
    stats.add_event(3, "picked")
    stats.resolve(3, "resting", "", 70.0)  # picked, dropped outside: a failure, not a miss
    stats.kit_scores.append(score_kit(Kit(0, tuple(classes)), [("bolt_yellow", "bolt_yellow")]))
    summary = stats.summary()
    assert summary["misses"] == 1 and summary["successes"] == 1
    assert math.isclose(summary["arrival_rate_per_min"], 4.0)
    assert summary["kits"] == 1 and summary["kits_complete"] == 0
    assert summary["kit_score"] == 3 and summary["kit_score_max"] == 12
    assert np.isclose(summary["kit_score_rate"], 0.25)


def test_a_part_given_up_by_the_node_settles_its_kit_before_it_rides_off():
    stats = CampaignStats()
    for k, name in enumerate(("nut_yellow", "nut_silver", "bolt_silver")):
        stats.add_part(Trial(k, name, 0.0, 0.0), k + 1, 0.0)
    stats.add_event(1, "skipped: part leaves the reach window before the arm can get there")
    stats.add_event(2, "failed: not placed: no evidence the part is held")
    assert stats.parts[1].settled and stats.parts[2].settled
    assert not stats.parts[3].settled  # on its way
    stats.resolve(3, "resting", "bolt_silver", 20.0)
    assert stats.parts[3].settled
