"""Live settings from the dashboard: a speed-ratio change and a filter switch must not move the tool."""

import numpy as np
import pytest

from motion_commander.errors import MotionCommanderError
from motion_commander.teleop import TeleopMapper
from motion_sensor.errors import MotionSensorError
from motion_sensor.hand_sample import HandSample
from motion_sensor.sequencing.sequencer import SEQUENCER_PARAMS, Sequencer, SequencerConfig, filter_params_for

IDENTITY = np.array([0.0, 0.0, 0.0, 1.0])


def engaged_mapper(ratio=1.0):
    mapper = TeleopMapper(ratio)
    mapper.engage([0.0, 0.0, 0.0], IDENTITY, [0.5, 0.1, 0.4], IDENTITY)
    return mapper


def test_ratio_change_keeps_the_target_and_scales_motion_from_then_on():
    mapper = engaged_mapper(1.0)
    before, _ = mapper.target([0.10, 0.0, 0.0], IDENTITY)
    np.testing.assert_allclose(before, [0.6, 0.1, 0.4])
    mapper.set_speed_ratio(0.25)
    same, _ = mapper.target([0.10, 0.0, 0.0], IDENTITY)
    np.testing.assert_allclose(same, before, atol=1e-12)  # the change itself moves nothing
    after, _ = mapper.target([0.18, 0.0, 0.0], IDENTITY)
    np.testing.assert_allclose(after - same, [0.02, 0.0, 0.0], atol=1e-12)  # 8 cm of hand -> 2 cm of tool


def test_ratio_change_keeps_orientation_references():
    mapper = engaged_mapper(1.0)
    turned = np.array([0.0, 0.0, np.sin(0.2), np.cos(0.2)])
    _, q_before = mapper.target([0.05, 0.0, 0.0], turned)
    mapper.set_speed_ratio(2.0)
    _, q_after = mapper.target([0.05, 0.0, 0.0], turned)
    np.testing.assert_allclose(abs(np.dot(q_before, q_after)), 1.0, atol=1e-12)


def test_ratio_change_while_disengaged_applies_at_the_next_engage():
    mapper = TeleopMapper(1.0)
    mapper.set_speed_ratio(0.5)
    mapper.engage([0.0, 0.0, 0.0], IDENTITY, [0.5, 0.0, 0.4], IDENTITY)
    target, _ = mapper.target([0.1, 0.0, 0.0], IDENTITY)
    np.testing.assert_allclose(target, [0.55, 0.0, 0.4])


@pytest.mark.parametrize("bad", [0.0, -1.0, float("nan"), float("inf")])
def test_bad_ratio_is_refused_and_the_old_one_stays(bad):
    mapper = engaged_mapper(1.0)
    with pytest.raises(MotionCommanderError):
        mapper.set_speed_ratio(bad)
    assert mapper.speed_ratio == 1.0


def sample(stamp, x, hand_id=1):
    return HandSample(stamp=stamp, position=np.array([x, 0.0, 0.2]), orientation=IDENTITY, hand_id=hand_id)


def run(sequencer, start, count, x0, step, dt=0.01):
    outputs = []
    for i in range(count):
        stamp = start + i * dt
        out = sequencer.process(sample(stamp, x0 + i * step), stamp)
        if out is not None:
            outputs.append(out)
    return outputs


@pytest.mark.parametrize("new_filter", ["one_euro", "kalman", "mean"])
def test_filter_switch_keeps_the_output_continuous(new_filter):
    sequencer = Sequencer(SequencerConfig(filter_name="mean", filter_params={"queue_size": 10}, entry_trim_frames=0))
    moving = run(sequencer, 100.0, 40, 0.0, 0.002)  # 0.2 m/s: the mean filter lags ~9 mm
    last = moving[-1].position
    params = filter_params_for(SEQUENCER_PARAMS.defaults(), new_filter)
    sequencer.set_filter(new_filter, params)
    after = run(sequencer, 100.4, 20, 0.080, 0.002)
    assert sequencer.config.filter_name == new_filter
    assert sequencer.counters["filter_switches"] == 1
    # The first output after the switch is where the old filter left the output: no jump
    # (a fresh filter alone would jump by the old filter's lag).
    assert np.linalg.norm(after[0].position - last) < 1e-9
    steps = [np.linalg.norm(b.position - a.position) for a, b in zip(after, after[1:])]
    assert max(steps) < 0.01


def test_unknown_filter_is_refused_and_the_old_one_keeps_running():
    sequencer = Sequencer(SequencerConfig(filter_name="mean", entry_trim_frames=0))
    old = sequencer.filter
    with pytest.raises(MotionSensorError):
        sequencer.set_filter("median")
    assert sequencer.filter is old and sequencer.config.filter_name == "mean"


def test_filter_params_for_uses_queue_size_for_the_mean_only():
    params = SEQUENCER_PARAMS.validate({"queue_size": 4, "filter_params": {"one_euro": {"beta": 10.0}}}, "test")
    assert filter_params_for(params, "mean") == {"queue_size": 4}
    assert filter_params_for(params, "one_euro")["beta"] == 10.0
