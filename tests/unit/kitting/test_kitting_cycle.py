"""Where a pick's cycle goes and what shortens it (kitting.picker.KittingPicker in the
closed loop of test_kitting_cell, kitting.cycle_phases, kitting.campaign): each pick's
phases are timed and sent with its final event; the camera's miss check runs during the
carry (the release still waits for it); the carry is one straight move from the lift
point; the reach-time estimate follows the measured approaches."""

import math

import numpy as np
import pytest

from kitting.campaign import CampaignStats, Trial
from kitting.cell import load_cell
from kitting.cycle_phases import PHASES, phase_summary

from .test_kitting_cell import _closed_loop, _run

END = ("placed", "skipped", "failed", "missed")


@pytest.fixture(scope="module")
def cell():
    return load_cell()


def _tool0(cell, face):
    return np.asarray(face, float) + [0.0, 0.0, cell.gripper.tcp_length]


def test_a_placed_pick_carries_its_timed_phases_which_add_up_to_its_cycle(cell):
    sim, fake, picker, events = _closed_loop(cell)
    try:
        sim.spawn("washer_yellow")
        _run(picker, fake, events, END)
        placed = events[-1]
        assert placed.event == "placed", [(e.event, e.reason) for e in events]
        assert list(placed.phases) == list(PHASES)
        assert all(value >= 0.0 for value in placed.phases.values())
        # The fake's moves take 0.3 s + distance / 0.5 m/s: each moving phase at least 0.3 s.
        for name in ("approach", "descent", "lift", "carry", "release"):
            assert placed.phases[name] >= 0.3, placed.phases
        assert sum(placed.phases.values()) == pytest.approx(picker.cycle_times[-1], abs=1e-6)
        assert all(e.phases is None for e in events[:-1])
    finally:
        sim.close()


def test_the_miss_check_runs_during_the_carry_and_the_release_waits_for_it(cell):
    # A fast carry (shorter than verify_time) leaves the rest of the check to wait above
    # the slot; a slow one covers it (check 0). Either way no move waits at the lift point.
    for verify_time in (0.2, 3.0):
        sim, fake, picker, events = _closed_loop(cell, {"verify_time": verify_time})
        try:
            sim.spawn("nut_silver")
            _run(picker, fake, events, END)
            phases = events[-1].phases
            assert events[-1].event == "placed" and phases is not None, [(e.event, e.reason) for e in events]
            lift_end = [t for t, _ in fake.moves]  # move start times
            slot = cell.tray.slot_for("nut_silver")
            above = _tool0(cell, np.r_[slot.center[:2], cell.belt.height + picker.params["transit_height"]])
            carry = next(i for i, (_, target) in enumerate(fake.moves) if np.allclose(target, above, atol=1e-6))
            # the carry starts as soon as the lift ends: no sleep in between
            lift_start = lift_end[carry - 1]
            assert fake.moves[carry][0] - lift_start == pytest.approx(
                0.3 + picker.params["hover_height"] / 0.5, abs=0.02
            )
            expected_check = max(0.0, verify_time - phases["carry"])
            assert phases["check"] == pytest.approx(expected_check, abs=0.02)
            # the release (the next move, down into the slot) started only after the check
            release_start = fake.moves[carry + 1][0]
            assert release_start - lift_start >= phases["lift"] + verify_time - 1e-6
        finally:
            sim.close()


def test_the_carry_is_one_straight_move_from_the_lift_point(cell):
    sim, fake, picker, events = _closed_loop(cell)
    try:
        sim.spawn("bolt_yellow")
        _run(picker, fake, events, END)
        assert events[-1].event == "placed"
        picked = next(e for e in events if e.event == "picked")
        lift = _tool0(cell, picked.position + [0.0, 0.0, picker.params["hover_height"]])
        targets = [target for _, target in fake.moves]
        index = next(i for i, target in enumerate(targets) if np.allclose(target, lift, atol=1e-6))
        slot = cell.tray.slot_for("bolt_yellow")
        above = _tool0(cell, np.r_[slot.center[:2], cell.belt.height + picker.params["transit_height"]])
        assert np.allclose(targets[index + 1], above, atol=1e-6)  # no rise to transit height first
    finally:
        sim.close()


def test_below_the_clear_height_the_arm_still_rises_before_moving_sideways(cell):
    sim, fake, picker, events = _closed_loop(cell)
    try:
        low = np.array([0.35, 0.25, cell.tray.position[2] + 0.03])  # just above the tray floor
        fake.position = _tool0(cell, low)
        target = np.array([-0.3, 0.7, cell.belt.height + 0.2])
        picker._move_to(target)
        first, second = (t for _, t in fake.moves[-2:])
        assert np.allclose(first, _tool0(cell, np.r_[low[:2], target[2]]))  # straight up
        assert np.allclose(second, _tool0(cell, target))
    finally:
        sim.close()


def test_the_reach_estimate_follows_a_slower_controller(cell):
    sim, fake, picker, events = _closed_loop(cell)
    fake.SPEED = 0.2  # m/s: much slower than the parameters' estimate
    try:
        assert picker.approach_scale == 1.0
        sim.spawn("washer_silver")
        _run(picker, fake, events, END)
        assert events[-1].event in ("placed", "missed"), [(e.event, e.reason) for e in events]
        assert picker.approach_scale > 1.5
        start, point = np.array([0.3, 0.3, 0.2]), np.array([-0.3, 0.7])
        hover = np.r_[point, cell.belt.height + picker.params["hover_height"]]
        measured = 2 * 0.3 / 2 + float(np.linalg.norm(hover - start)) / 0.2  # one move of the fake
        assert picker.reach_time(start, point) - picker.descent_time >= 0.8 * measured
    finally:
        sim.close()


def test_phase_summary_and_the_campaign_summary():
    picks = [dict(zip(PHASES, np.arange(1.0, 8.0) * k)) for k in (1.0, 2.0, 3.0)]
    summary = phase_summary(picks + [{}])
    assert summary["picks"] == 3
    assert summary["approach"] == {"p50": 2.0, "mean": 2.0, "p95": pytest.approx(2.9)}
    assert summary["cycle"]["p50"] == pytest.approx(2 * 28.0)
    empty = phase_summary([])
    assert empty["picks"] == 0 and math.isnan(empty["cycle"]["p50"])

    stats = CampaignStats()
    for part_id, name in ((1, "nut_yellow"), (2, "bolt_silver")):
        stats.add_part(Trial(part_id - 1, name, 0.0, 0.0), part_id, now=0.0)
    stats.add_phases(1, picks[0])
    stats.add_phases(2, picks[2])
    stats.add_phases(9, picks[1])  # not a campaign part: ignored
    stats.resolve(1, "resting", "nut_yellow", 10.0)
    stats.resolve(2, "gone", "", 20.0)  # not placed: its phases are not counted
    summary = stats.summary()
    assert summary["cycle_phases_s"]["picks"] == 1
    assert summary["cycle_phases_s"]["release"]["p50"] == pytest.approx(7.0)
    assert summary["trials_detail"][0]["phases"] == picks[0]
