"""Mean filter, quaternion averaging and the sequencer's drop rules."""
import numpy as np
import pytest
from hypothesis import given, settings, strategies as st
from scipy.spatial.transform import Rotation

from motion_sensor.errors import MotionSensorError
from motion_sensor.filters import MeanFilter, average_quaternions, make_filter
from motion_sensor.hand_sample import HandSample
from motion_sensor.sequencer import Sequencer, SequencerConfig

IDENTITY = np.array([0.0, 0.0, 0.0, 1.0])


def sample(stamp, position=(0.0, 0.0, 0.2), orientation=IDENTITY, **kw):
    return HandSample(stamp=stamp, position=np.array(position, dtype=float),
                      orientation=np.array(orientation, dtype=float), **kw)


def test_mean_filter_averages_the_last_ten():
    f = MeanFilter()
    for i in range(15):
        position, orientation = f.update(i, np.array([i, 0.0, 0.0]), IDENTITY)
    assert position[0] == pytest.approx(np.mean(range(5, 15)))
    np.testing.assert_allclose(orientation, IDENTITY)


def test_quaternion_average_ignores_sign_and_stays_unit(rng):
    base = Rotation.from_euler("xyz", [0.3, -0.2, 1.0])
    rotations = base * Rotation.from_rotvec(rng.normal(0, 0.02, (10, 3)))
    quats = rotations.as_quat()
    quats[::2] *= -1  # the same rotations with flipped signs
    mean = average_quaternions(quats)
    assert np.linalg.norm(mean) == pytest.approx(1.0)
    # scipy's chordal mean of the unflipped rotations is the reference answer.
    assert (Rotation.from_quat(mean) * rotations.mean().inv()).magnitude() < 1e-9
    assert (Rotation.from_quat(mean) * base.inv()).magnitude() < 0.05


@settings(max_examples=50, deadline=None)
@given(st.lists(st.lists(st.floats(-1, 1), min_size=4, max_size=4), min_size=1, max_size=10))
def test_quaternion_average_is_always_unit(raw):
    quats = np.array(raw, dtype=float)
    norms = np.linalg.norm(quats, axis=1)
    quats = quats[norms > 1e-3] / norms[norms > 1e-3, None]
    if len(quats):
        assert np.linalg.norm(average_quaternions(quats)) == pytest.approx(1.0)


def test_unknown_filter_and_bad_queue_are_explained():
    with pytest.raises(MotionSensorError, match="unknown filter"):
        make_filter("median")
    with pytest.raises(MotionSensorError, match="queue_size"):
        make_filter("mean", queue_size=0)


def test_sequencer_passes_good_frames_and_counts():
    seq = Sequencer()
    out = seq.process(sample(10.0), now=10.01)
    assert out is not None and out.stamp == 10.0
    assert seq.counters["frames_out"] == 1 and seq.dropped == 0


@pytest.mark.parametrize("bad, reason", [
    (dict(position=(np.nan, 0, 0)), "non_finite"),
    (dict(orientation=(0, 0, 0, 2.0)), "non_unit_quaternion"),
    (dict(orientation=(0, 0, 0, 0)), "non_unit_quaternion"),
    (dict(hands_num=2), "hands_num_mismatch"),
])
def test_sequencer_drops_bad_frames(bad, reason):
    seq = Sequencer()
    assert seq.process(sample(10.0, **bad), now=10.0) is None
    assert seq.counters["dropped_" + reason] == 1


def test_sequencer_drops_stale_duplicate_out_of_order_and_future():
    seq = Sequencer(SequencerConfig(max_age_s=0.1))
    assert seq.process(sample(10.0), now=10.2) is None            # older than max age
    assert seq.process(sample(10.0), now=10.01) is not None
    assert seq.process(sample(10.0), now=10.02) is None           # duplicate
    assert seq.process(sample(9.99), now=10.02) is None           # out of order
    assert seq.process(sample(11.0), now=10.02) is None           # from the future
    assert seq.process(sample(-1.0), now=10.02) is None           # negative stamp
    assert seq.process(sample(10.05), now=10.06) is not None
    counts = seq.counters
    assert (counts["dropped_stale"], counts["dropped_duplicate"], counts["dropped_out_of_order"],
            counts["dropped_future_stamp"], counts["dropped_bad_stamp"]) == (1, 1, 1, 1, 1)
    assert seq.dropped == 5


def test_new_hand_reseeds_the_filter_instead_of_blending():
    seq = Sequencer()
    for i in range(5):
        seq.process(sample(10.0 + 0.01 * i, position=(0.0, 0.0, 0.2), hand_id=1), now=10.1)
    out = seq.process(sample(10.1, position=(0.1, 0.0, 0.2), hand_id=2), now=10.1)
    np.testing.assert_allclose(out.position, [0.1, 0.0, 0.2])
    assert seq.counters["filter_reseeds"] == 1


def test_frame_without_hand_is_counted_not_an_error():
    seq = Sequencer()
    empty = HandSample(stamp=10.0, position=np.zeros(3), orientation=np.zeros(4), hands_num=0, hand_types=())
    assert seq.process(empty, now=10.0) is None
    assert seq.counters["dropped_no_hand"] == 1


def test_bad_config_is_refused():
    with pytest.raises(MotionSensorError, match="max_age_s"):
        SequencerConfig(max_age_s=0)
