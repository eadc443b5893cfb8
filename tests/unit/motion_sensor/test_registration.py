"""DTW registration between hand and robot space: known transforms are recovered."""

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from motion_sensor.errors import MotionSensorError
from motion_sensor.registration.device_registration import Registration, register, umeyama


def figure(u):
    return np.column_stack(
        [0.1 * np.sin(2 * np.pi * u), 0.07 * np.sin(4 * np.pi * u + 0.5), 0.05 * np.sin(6 * np.pi * u + 1.0)]
    )


def test_umeyama_recovers_a_similarity_and_never_a_reflection(rng):
    points = rng.normal(size=(50, 3))
    rotation = Rotation.from_euler("xyz", [0.4, -0.2, 2.0]).as_matrix()
    r, t, s = umeyama(points, 2.5 * points @ rotation.T + [1, 2, 3])
    np.testing.assert_allclose(r, rotation, atol=1e-9)
    np.testing.assert_allclose(t, [1, 2, 3], atol=1e-9)
    assert s == pytest.approx(2.5)
    mirrored = points * [1, 1, -1]
    r, _, _ = umeyama(points, mirrored)
    assert np.linalg.det(r) == pytest.approx(1.0)


def test_register_paths_at_different_speeds_with_tremor(rng):
    true = Rotation.from_euler("zyx", [1.2, 0.3, -0.4])
    hand_t = np.cumsum(rng.uniform(0.7, 1.3, 800)) * 0.009
    hand_u = ((hand_t - hand_t[0]) / (hand_t[-1] - hand_t[0])) ** 1.4  # the hand lingers at the start
    hand = figure(hand_u) + 0.0005 * np.sin(2 * np.pi * 10 * hand_t)[:, None] + rng.normal(0, 1e-4, (800, 3))
    robot_t = np.linspace(0, 2.5 * (hand_t[-1] - hand_t[0]), 600)
    robot = 0.8 * true.apply(figure(np.linspace(0, 1, 600))) + [0.4, -0.1, 0.3]
    result = register(hand, robot, hand_t, robot_t)
    assert (Rotation.from_matrix(result.rotation) * true.inv()).magnitude() < np.radians(1.0)
    probe = figure(np.linspace(0, 1, 100))
    expected = 0.8 * true.apply(probe) + [0.4, -0.1, 0.3]
    assert np.abs(result.apply(probe) - expected).max() < 0.002
    assert result.speed_reduction == pytest.approx(2.5, rel=1e-6)
    times, points = result.imitate(hand_t, hand)
    assert times[-1] - times[0] == pytest.approx(2.5 * (hand_t[-1] - hand_t[0]))


def test_yaml_round_trip_and_checks(tmp_path):
    reg = Registration(Rotation.from_euler("z", 0.5).as_matrix(), np.array([0.1, 0.2, 0.3]), 1.2, 2.0, 0.001)
    path = tmp_path / "reg.yaml"
    reg.save(str(path))
    back = Registration.load(str(path))
    np.testing.assert_allclose(back.rotation, reg.rotation, atol=1e-12)
    assert back.scale == 1.2 and back.speed_reduction == 2.0
    path.write_text("rotation: [[1, 0, 0], [0, 1, 0], [0, 0, -1]]\ntranslation_m: [0, 0, 0]\n")
    with pytest.raises(MotionSensorError, match="rotation"):
        Registration.load(str(path))
    with pytest.raises(MotionSensorError, match="cannot read"):
        Registration.load(str(tmp_path / "missing.yaml"))


def test_register_refuses_unusable_paths():
    still = np.zeros((50, 3))
    with pytest.raises(MotionSensorError, match="barely moves"):
        register(still, figure(np.linspace(0, 1, 50)))
    with pytest.raises(MotionSensorError, match="at least 10"):
        register(figure(np.linspace(0, 1, 5)), figure(np.linspace(0, 1, 50)))
