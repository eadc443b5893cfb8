"""The speed-adaptive filters: One Euro with a speed threshold, and the IMM Kalman.

A synthetic hand: a still phase with physiological tremor (9 Hz, 0.4 mm) and sensor
noise (0.3 mm), then a deliberate move at 0.3 m/s, sampled at 110 Hz with jittered gaps.
"""

import numpy as np
import pytest

from motion_sensor.errors import MotionSensorError
from motion_sensor.sequencing.filters import KalmanFilter, OneEuroFilter, make_filter

from ..conftest import ROOT

IDENTITY = np.array([0.0, 0.0, 0.0, 1.0])
RATE = 110.0


def synthetic_hand(rng, still_s=2.0, move_s=1.0, speed=0.3):
    """(stamps, positions, true positions, moving mask) of a still-then-moving hand."""
    gaps = np.clip(rng.normal(1.0 / RATE, 0.0005, int((still_s + move_s) * RATE)), 0.004, None)
    stamps = 100.0 + np.cumsum(gaps)
    t = stamps - stamps[0]
    truth = np.zeros((len(t), 3))
    moving = t > still_s
    truth[moving, 0] = speed * (t[moving] - still_s)
    tremor = 0.0004 * np.sin(2 * np.pi * 9.0 * t)[:, None] * np.array([1.0, 0.6, 0.3])
    noise = rng.normal(0, 0.0003, truth.shape)
    return stamps, truth + tremor + noise, truth, moving


def run(f, stamps, positions):
    return np.array([f.update(t, p, IDENTITY)[0] for t, p in zip(stamps, positions)])


def still_jitter(output, stamps, still_s=2.0):
    """RMS (m) of the output's frame-to-frame steps while the hand is still (after warm-up)."""
    t = stamps - stamps[0]
    still = output[(t > 0.5) & (t < still_s)]
    return float(np.sqrt(np.mean(np.sum(np.diff(still, axis=0) ** 2, axis=1))))


def moving_lag(output, truth, moving, stamps):
    """Mean distance (m) behind the true path in the last half second of the move."""
    late = moving & (stamps > stamps[-1] - 0.5)
    return float(np.mean(np.linalg.norm(output[late] - truth[late], axis=1)))


def test_speed_threshold_keeps_a_trembling_hand_steady_and_still_follows_a_move(rng):
    stamps, positions, truth, moving = synthetic_hand(rng)
    classic = run(OneEuroFilter(speed_threshold=0.0), stamps, positions)
    thresholded = run(OneEuroFilter(), stamps, positions)
    raw_jitter = still_jitter(positions, stamps)
    # Same beta: without the threshold the tremor opens the cutoff and passes through.
    assert still_jitter(thresholded, stamps) < 0.6 * still_jitter(classic, stamps)
    assert still_jitter(thresholded, stamps) < 0.2 * raw_jitter
    # Once moving at 0.3 m/s the cutoff is open: within 1.5 mm of the true path.
    assert moving_lag(thresholded, truth, moving, stamps) < 0.0015


def test_one_euro_speed_comes_from_the_inputs_not_the_lagging_output(rng):
    """A hand drifting at 3 cm/s with a low mincutoff: the output trails the drift by
    ~16 mm, which must not read as speed and open the cutoff onto the tremor."""
    stamps, positions, _, _ = synthetic_hand(rng, still_s=3.0, move_s=0.0)
    drift = np.outer(0.03 * (stamps - stamps[0]), [0.0, 1.0, 0.0])
    f = OneEuroFilter(mincutoff=0.3)
    out = run(f, stamps, positions + drift)
    assert float(np.linalg.norm(f._velocity)) == pytest.approx(0.03, abs=0.015)
    # Once the output trails the drift at a steady distance, what is left is the tremor.
    assert still_jitter(out - drift, stamps, still_s=3.0) < 0.2 * still_jitter(positions, stamps, still_s=3.0)


def test_imm_kalman_takes_the_manoeuvre_model_at_the_start_of_a_move_only(rng):
    """The manoeuvre is the acceleration: at the start of a move the manoeuvring model
    explains the frames, then the steady CV model follows the constant speed again."""
    stamps, positions, truth, moving = synthetic_hand(rng, still_s=2.0, move_s=1.0)
    f = KalmanFilter()
    probabilities, outputs = [], []
    for t, p in zip(stamps, positions):
        outputs.append(f.update(t, p, IDENTITY)[0])
        probabilities.append(f.maneuver_probability)
    probabilities, outputs = np.array(probabilities), np.array(outputs)
    onset = int(np.argmax(moving))
    assert np.mean(probabilities[100:onset]) < 0.1
    assert np.max(probabilities[onset : onset + int(0.15 * RATE)]) > 0.8
    assert np.mean(probabilities[-int(0.5 * RATE) :]) < 0.1
    assert moving_lag(outputs, truth, moving, stamps) < 0.002
    assert still_jitter(outputs, stamps) < 0.3 * still_jitter(positions, stamps)


def test_imm_is_steadier_than_a_single_cv_model_that_follows_as_well(rng):
    stamps, positions, truth, moving = synthetic_hand(rng)
    imm = run(KalmanFilter(), stamps, positions)
    single = run(KalmanFilter(maneuver_process_noise=0.0, process_noise=10.0), stamps, positions)
    assert moving_lag(imm, truth, moving, stamps) < 2 * moving_lag(single, truth, moving, stamps) + 0.0005
    assert still_jitter(imm, stamps) < 0.3 * still_jitter(single, stamps)
    assert KalmanFilter(maneuver_process_noise=0.0).maneuver_probability == 0.0


@pytest.mark.parametrize(
    "name,params",
    [
        ("one_euro", {"speed_threshold": -0.1}),
        ("one_euro", {"beta": float("nan")}),
        ("kalman", {"switch_probability": 0.0}),
        ("kalman", {"switch_probability": 0.7}),
        ("kalman", {"maneuver_process_noise": -1.0}),
    ],
)
def test_bad_adaptive_parameters_are_rejected_by_name(name, params):
    with pytest.raises(MotionSensorError, match=list(params)[0]):
        make_filter(name, **params)


def test_imm_recovers_from_a_huge_accepted_move_without_non_finite_output():
    f = KalmanFilter()
    t = 10.0
    for _step in range(50):
        t += 0.009
        out, _ = f.update(t, np.array([0.0, 0.0, 0.2]), IDENTITY)
    for _step in range(20):  # the sequencer accepted a 5 km "move" (a broken device)
        t += 0.009
        out, _ = f.update(t, np.array([5000.0, 0.0, 0.2]), IDENTITY)
        assert np.all(np.isfinite(out))
    assert out[0] == pytest.approx(5000.0, abs=1.0)


def test_shipped_sequencer_yaml_states_the_filters_defaults():
    """config/sequencer.yaml documents each filter's parameters with units: it must build
    and say what the code does when the parameters are left out."""
    import inspect
    import os

    import yaml

    from motion_sensor.sequencing.filters import FILTERS

    path = os.path.join(ROOT, "src", "motion_sensor", "config", "sequencer.yaml")
    with open(path, encoding="utf-8") as fh:
        params = yaml.safe_load(fh)["filter_params"]
    assert set(params) == set(FILTERS)
    for name, values in params.items():
        make_filter(name, **values)
        defaults = {k: p.default for k, p in inspect.signature(FILTERS[name]).parameters.items()}
        for key, value in values.items():
            assert defaults[key] == pytest.approx(value), f"{name}.{key}: yaml {value}, code {defaults[key]}"


def test_fast_likelihood_matches_scipy(rng):
    """The IMM's likelihood shortcut gives scipy's multivariate normal log-density."""
    from scipy.stats import multivariate_normal

    from motion_sensor.sequencing.filters import _gaussian_log_density

    for _ in range(20):
        a = rng.normal(size=(3, 3))
        covariance = a @ a.T + 0.01 * np.eye(3)
        residual = rng.normal(size=3)
        assert _gaussian_log_density(residual, covariance) == pytest.approx(
            multivariate_normal.logpdf(residual, cov=covariance), rel=1e-9, abs=1e-9
        )


def test_kalman_loads_filterpy_when_built_not_on_the_first_frame():
    """filterpy takes seconds to import; done on the first frame it stalled the stream until
    the queued frames went stale (a whole session lost 76 of 348 commands that way)."""
    import os
    import subprocess
    import sys

    package_root = os.path.join(ROOT, "src", "motion_sensor")
    code = (
        "import sys; from motion_sensor.sequencing.filters import make_filter; "
        "assert 'filterpy.kalman' not in sys.modules; make_filter('kalman'); "
        "assert 'filterpy.kalman' in sys.modules"
    )
    common_root = os.path.join(ROOT, "src", "motion_common")
    env = dict(os.environ, PYTHONPATH=os.pathsep.join([package_root, common_root, os.environ.get("PYTHONPATH", "")]))
    subprocess.run([sys.executable, "-c", code], check=True, env=env)


def test_a_windowed_speed_tells_a_slow_move_from_tremor_sooner(rng):
    # 0.1 m/s is a slow deliberate move; the classic speed (consecutive inputs smoothed at
    # dcutoff = 1 Hz) still reads it below the 0.08 m/s threshold a while after it starts.
    stamps, positions, truth, moving = synthetic_hand(rng, speed=0.1)
    classic = run(OneEuroFilter(speed_window=0.0, drift_window=0.0), stamps, positions)
    windowed = run(OneEuroFilter(speed_window=0.2, drift_window=0.0), stamps, positions)
    t = stamps - stamps[0]
    onset = moving & (t < 2.5)  # the first half second of the move

    def onset_lag(output):
        return float(np.mean(np.linalg.norm(output[onset] - truth[onset], axis=1)))

    assert onset_lag(windowed) < 0.7 * onset_lag(classic), (onset_lag(windowed), onset_lag(classic))
    # The tremor nets nothing over the window: the still hand stays as steady.
    assert still_jitter(windowed, stamps) <= 1.1 * still_jitter(classic, stamps)


def test_lag_compensation_adds_back_the_low_pass_lag_and_never_more_than_max_lead():
    stamps = 100.0 + np.arange(0.0, 2.0, 1.0 / RATE)
    ramp = np.column_stack([0.05 * (stamps - stamps[0]), np.zeros(len(stamps)), np.zeros(len(stamps))])
    # 0.05 m/s: below the speed threshold, the 3 Hz low-pass trails by v / (2 pi 3 Hz) = 2.65 mm.
    plain = run(OneEuroFilter(lag_compensation=0.0), stamps, ramp)
    compensated = run(OneEuroFilter(lag_compensation=1.0), stamps, ramp)
    assert ramp[-1, 0] - plain[-1, 0] == pytest.approx(0.05 / (2 * np.pi * 3.0), rel=0.1)
    assert abs(ramp[-1, 0] - compensated[-1, 0]) < 0.0003
    # A jump (a hand re-found elsewhere) reads as a high speed: the lead stays bounded.
    bounded = OneEuroFilter(lag_compensation=1.0, max_lead=0.002, beta=0.0)
    run(bounded, stamps[:50], ramp[:50])
    out, _ = bounded.update(stamps[50], ramp[50] + [0.5, 0.0, 0.0], IDENTITY)
    assert np.linalg.norm(bounded._lead) <= 0.002 + 1e-12
    assert out[0] <= ramp[50, 0] + 0.5 + 0.002 + 1e-9


def test_the_drift_gate_follows_a_slow_steady_move_the_speed_gate_misses(rng):
    # 0.072 m/s: below the 0.08 m/s speed gate, above the drift gate's 0.065 m/s over 0.3 s.
    stamps, positions, truth, moving = synthetic_hand(rng, speed=0.072)
    gated = run(OneEuroFilter(), stamps, positions)
    ungated = run(OneEuroFilter(drift_window=0.0), stamps, positions)
    assert moving_lag(gated, truth, moving, stamps) < 0.6 * moving_lag(ungated, truth, moving, stamps), (
        moving_lag(gated, truth, moving, stamps),
        moving_lag(ungated, truth, moving, stamps),
    )


def test_the_drift_gate_leaves_a_still_hand_and_a_hand_wandering_back_and_forth_as_they_were(rng):
    # A still trembling hand from its first frame (a window only partly filled would read its
    # noise as speed), then a palm wandering 8 mm back and forth at 1.6 Hz (a hand opening and
    # closing): up to 0.067 m/s net over 0.2 s, 0.053 over 0.3 s.
    stamps, positions, _, moving = synthetic_hand(rng)
    t = stamps - stamps[0]
    wander = positions[~moving] + np.outer(0.008 * np.sin(2 * np.pi * 1.6 * t[~moving]), [1.0, 0.0, 0.0])
    for hand in (positions[~moving], wander):
        gated = run(OneEuroFilter(), stamps[~moving], hand)
        ungated = run(OneEuroFilter(drift_window=0.0), stamps[~moving], hand)
        np.testing.assert_array_equal(gated, ungated)


def test_the_drift_gate_opens_only_on_a_whole_window():
    f = OneEuroFilter(drift_window=0.3, drift_threshold=0.0)
    stamps = 100.0 + np.arange(0.0, 0.5, 1.0 / RATE)
    speeds = [f._drift_speed(t, np.array([0.05 * (t - 100.0), 0.0, 0.0])) for t in stamps]
    whole = stamps - stamps[0] >= 0.3
    assert not any(speeds[i] for i in np.flatnonzero(~whole))
    assert np.allclose(np.array(speeds)[whole], 0.05)


def test_the_new_one_euro_parameters_are_checked():
    for params in (
        {"speed_window": -0.1},
        {"lag_compensation": 1.5},
        {"max_lead": -1.0},
        {"drift_window": -0.3},
        {"drift_threshold": -0.01},
    ):
        with pytest.raises(MotionSensorError):
            OneEuroFilter(**params)
