"""Kitting: constant-velocity belt tracking (filterpy) and intercept planning, on seeded
synthetic data."""

import numpy as np
import pytest

from kitting.intercept import plan_intercept
from kitting.tracking import BeltTracker, Observation


def _run(tracker, rng, parts, steps=40, dt=0.2, noise=0.001, drop=0.0):
    for k in range(steps):
        t = k * dt
        observations = []
        for name, x0, y0, vx in parts:
            if rng.random() >= drop:
                observations.append(Observation(name, x0 + vx * t + rng.normal(0, noise), y0 + rng.normal(0, noise)))
        rng.shuffle(observations)
        tracker.update(t, observations)
    return (steps - 1) * dt


def test_tracker_follows_parts_at_belt_speed(rng):
    tracker = BeltTracker({"initial_speed": 0.0})
    parts = [("nut_silver", -0.5, 0.65, 0.05), ("bolt_yellow", -0.45, 0.75, 0.05), ("washer_yellow", -0.6, 0.70, 0.05)]
    t = _run(tracker, rng, parts, drop=0.1)
    tracks = tracker.confirmed()
    assert len(tracks) == 3 and not tracker.stopped
    for name, x0, y0, vx in parts:
        track = next(tr for tr in tracks if tr.class_name == name)
        assert track.velocity[0] == pytest.approx(vx, abs=0.005)
        assert np.allclose(track.position, (x0 + vx * t, y0), atol=0.002)


def test_tracks_start_and_stop(rng):
    tracker = BeltTracker({"max_misses": 2, "min_hits": 2})
    tracker.update(0.0, [Observation("nut_yellow", 0.0, 0.7)])
    assert len(tracker.tracks) == 1 and not tracker.confirmed()
    tracker.update(0.2, [Observation("nut_yellow", 0.01, 0.7)])
    assert len(tracker.confirmed()) == 1
    tracker.update(0.4, [])
    tracker.update(0.6, [])
    assert tracker.tracks == {} and len(tracker.stopped) == 1
    tracker.update(0.8, [Observation("nut_yellow", 0.79, 0.7)])
    tracker.update(1.0, [Observation("nut_yellow", 0.81, 0.7)])  # past the belt end
    assert tracker.tracks == {}


def test_intercept_earliest_feasible_point():
    # Part at x=-0.5 moving 0.05 m/s; window [-0.2, 0.3]; arm needs 2 s.
    plan = plan_intercept((-0.5, 0.7), (0.05, 0.0), t0=0.0, now=0.0, reach_time=2.0, x_min=-0.2, x_max=0.3)
    assert plan.ok and plan.time == pytest.approx(6.0) and plan.point[0] == pytest.approx(-0.2)
    # Already in the window: the arm's time decides.
    plan = plan_intercept((0.0, 0.7), (0.05, 0.0), 0.0, 0.0, 2.0, -0.2, 0.3)
    assert plan.ok and plan.time == pytest.approx(2.0, abs=1e-6) and plan.point[0] == pytest.approx(0.1)
    # Reach time depending on the point: distance from a base at the origin at 0.5 m/s.
    plan = plan_intercept((0.0, 0.7), (0.05, 0.0), 0.0, 0.0, lambda q: float(np.hypot(*q)) / 0.5, -0.2, 0.3)
    assert plan.ok and plan.time - 0.0 == pytest.approx(np.hypot(*plan.point) / 0.5, abs=1e-6)


def test_intercept_reasons():
    gone = plan_intercept((0.5, 0.7), (0.05, 0.0), 0.0, 0.0, 1.0, -0.2, 0.3)
    assert not gone.ok and "already left" in gone.reason
    late = plan_intercept((0.25, 0.7), (0.05, 0.0), 0.0, 0.0, 3.0, -0.2, 0.3)
    assert not late.ok and "before the arm" in late.reason
    still = plan_intercept((0.5, 0.7), (0.0, 0.0), 0.0, 0.0, 1.0, -0.2, 0.3)
    assert not still.ok and "still" in still.reason


def test_intercept_on_random_tracks_is_consistent(rng):
    for _ in range(200):
        x0, speed, reach = rng.uniform(-0.8, 0.4), rng.uniform(0.01, 0.1), rng.uniform(0.5, 5.0)
        plan = plan_intercept((x0, 0.7), (speed, 0.0), 0.0, 0.0, reach, -0.2, 0.3)
        if plan.ok:
            assert plan.time >= reach - 1e-6 and -0.2 - 1e-9 <= plan.point[0] <= 0.3 + 1e-9
        else:
            # infeasible only when the window is left before the arm arrives
            assert x0 + speed * reach > 0.3 - 1e-9
