"""Kitting cell foundations: cell YAML, camera model vs rendering, calibration (ChArUco
intrinsics, marker extrinsics), detector and pixel-to-belt geometry on rendered images."""

import math

import cv2
import numpy as np
import pybullet as p
import pytest

from kitting.calibration import BoardSpec, calibrate_intrinsics, extrinsics_from_marker, pose_error
from kitting.camera import PinholeCamera, render
from kitting.cell import cell_from_dict, load_cell
from kitting.detector import ClassicalDetector
from kitting.geometry import pixel_to_belt, pixels_to_plane
from kitting.parts import CLASS_NAMES, PART_CLASSES
from kitting.sim_scene import SimScene, render_board_views
from kitting.vision import BeltVision
from motion_common.errors import ParameterError


@pytest.fixture(scope="module")
def cell():
    return load_cell()


@pytest.fixture(scope="module")
def client():
    cid = p.connect(p.DIRECT)
    yield cid
    p.disconnect(cid)


@pytest.fixture
def scene(client, cell):
    p.resetSimulation(physicsClientId=client)
    return SimScene(client, cell)


def test_six_classes_with_plausible_sizes():
    assert len(CLASS_NAMES) == 6
    for part in PART_CLASSES.values():
        assert part.thread in ("M8", "M10", "M12")
        assert 0.008 <= part.width <= 0.05 and part.height > 0


def test_cell_yaml_loads_with_units_and_rejects_unknown_keys(cell):
    assert cell.belt.speed == pytest.approx(0.05)
    assert len(cell.tray.slots) == 6 and {s.part_class for s in cell.tray.slots} == set(CLASS_NAMES)
    assert cell.camera.width == 640 and cell.camera.height == 480
    with pytest.raises(ParameterError, match="unknown parameter 'sped'"):
        cell_from_dict({"belt": {"sped": 0.1}}, "x.yaml")
    with pytest.raises(ParameterError):
        cell_from_dict({"belt": {"speed": -1.0}}, "x.yaml")


def test_rendered_pixels_match_K(client, cell, scene):
    """A dark belt edge and the marker corners land where cv2.projectPoints puts them."""
    camera = PinholeCamera.from_spec(cell.camera)
    image = render(client, camera, supersample=2)
    result = extrinsics_from_marker(image, cell.markers, camera.K, camera.distortion)
    assert result.ok and result.reprojection_px < 0.5


def test_scene_moves_parts_along_the_belt(scene, cell):
    part = scene.add_part("nut_silver", -0.3, cell.belt.y)
    scene.step(2.0)
    assert scene.parts[part].x == pytest.approx(-0.3 + 2.0 * cell.belt.speed)
    body_x = p.getBasePositionAndOrientation(scene.body_of(part), physicsClientId=scene.client)[0][0]
    assert body_x == pytest.approx(scene.parts[part].x)


def test_charuco_intrinsics_within_one_percent(client):
    spec = BoardSpec()
    camera = PinholeCamera(640, 480, np.array([[600.0, 0, 319.5], [0, 600.0, 239.5], [0, 0, 1]]))
    images = render_board_views(client, spec, camera, 10)
    result = calibrate_intrinsics(images, spec)
    print(
        f"ChArUco: fx {result.fx:.2f} fy {result.fy:.2f} (true 600) rms {result.rms:.3f} px, {result.views_used} views"
    )
    assert abs(result.fx / 600.0 - 1) < 0.01 and abs(result.fy / 600.0 - 1) < 0.01
    assert result.rms < 1.0


def test_marker_extrinsics_recover_the_camera_pose(client, cell, scene):
    camera = PinholeCamera.from_spec(cell.camera)
    image = render(client, camera, supersample=2)
    result = extrinsics_from_marker(image, cell.markers, camera.K, camera.distortion)
    position_error, angle_error = pose_error(result.T_base_cam, camera.pose)
    print(
        f"marker extrinsics: {1000 * position_error:.2f} mm, {angle_error:.3f} deg, "
        f"reprojection {result.reprojection_px:.3f} px"
    )
    assert result.ok and result.used == [7, 8]
    assert position_error < 0.003 and angle_error < 0.3
    estimated = camera.with_pose(result.T_base_cam)
    points = np.c_[
        np.random.default_rng(1).uniform(-0.55, -0.05, 30),
        np.random.default_rng(2).uniform(0.6, 0.8, 30),
        np.full(30, cell.belt.height),
    ]
    errors = np.linalg.norm(pixels_to_plane(estimated, camera.project(points), cell.belt.height) - points, axis=1)
    assert np.percentile(errors, 95) < 0.002


def test_missing_marker_is_refused(cell):
    camera = PinholeCamera.from_spec(cell.camera)
    blank = np.full((480, 640, 3), 90, np.uint8)
    result = extrinsics_from_marker(blank, cell.markers, camera.K, camera.distortion)
    assert not result.ok and "no marker" in result.reason


def test_a_marker_reaching_the_image_border_is_reported_partly_hidden(cell):
    camera = PinholeCamera.from_spec(cell.camera)
    marker = cell.markers[0]
    dictionary = cv2.aruco.getPredefinedDictionary(getattr(cv2.aruco, marker.dictionary))
    image = np.full((480, 640), 255, np.uint8)
    image[3:123, 300:420] = cv2.aruco.generateImageMarker(dictionary, marker.id, 120)  # 3 px from the top
    found = extrinsics_from_marker(image, cell.markers, camera.K, camera.distortion, require_all=True)
    assert not found.ok and found.partly_hidden == [marker.id]
    assert [i for i, _ in found.missing] == [m.id for m in cell.markers]  # the other one is not in view
    blank = extrinsics_from_marker(np.full((480, 640), 255, np.uint8), cell.markers, camera.K, camera.distortion)
    assert not blank.ok and blank.partly_hidden == []


def test_ray_plane_is_exact_for_a_tilted_camera(cell):
    camera = PinholeCamera.from_spec(cell.camera)
    tilt = math.degrees(math.acos(-camera.pose[2, 2]))
    assert tilt > 5  # the cell's camera is tilted: a straight-down model would be wrong
    points = np.array([[-0.5, 0.62, cell.belt.height], [-0.1, 0.8, cell.belt.height], [-0.3, 0.7, cell.belt.height]])
    for point, pixel in zip(points, camera.project(points)):
        assert np.allclose(pixel_to_belt(camera, pixel, cell.belt.height), point, atol=1e-9)


def _vision(cell, width=320, height=240):
    camera = PinholeCamera.from_spec(cell.camera).scaled(width, height)
    return camera, BeltVision(camera, cell.belt)


def test_detector_classifies_each_class_and_locates_it(client, cell, scene):
    camera, vision = _vision(cell, 640, 480)
    rng = np.random.default_rng(3)
    truth = {}
    for i, name in enumerate(CLASS_NAMES):
        x, y = -0.52 + 0.085 * i, cell.belt.y + rng.uniform(-0.06, 0.06)
        truth[scene.add_part(name, x, y, rng.uniform(-math.pi, math.pi))] = (name, x, y)
    observations, result = vision.observe(render(client, camera))
    assert result.rejections == []
    assert sorted(o.class_name for o in observations) == sorted(CLASS_NAMES)
    for obs in observations:
        name, x, y = min(truth.values(), key=lambda t: math.hypot(t[1] - obs.x, t[2] - obs.y))
        assert obs.class_name == name
        assert math.hypot(x - obs.x, y - obs.y) < 0.003
        assert 0.3 < obs.confidence <= 1.0


def test_detector_rejects_corrupt_images():
    detector = ClassicalDetector()
    for bad in (
        None,
        np.zeros((0, 0, 3), np.uint8),
        np.zeros((240, 320), np.float32),
        np.zeros((240, 320, 3), np.uint8),
    ):
        result = detector.detect(bad)
        assert result.corrupt and not result.detections


def test_detector_rejects_edge_parts_and_unknown_objects(client, cell, scene):
    camera, vision = _vision(cell)
    scene.add_part("nut_yellow", -0.35, cell.belt.y + cell.belt.width / 2)  # on the belt edge
    scene.add_foreign_object(x=-0.2, y=cell.belt.y)  # red box
    scene.add_foreign_object(
        half_extents=(0.025, 0.025, 0.005), x=-0.45, y=cell.belt.y, rgba=(0.78, 0.78, 0.8, 1)
    )  # silver plate
    observations, result = vision.observe(render(client, camera))
    assert observations == []
    reasons = sorted(r.reason for r in result.rejections)
    assert reasons == ["edge", "unknown object", "unknown object"]


# Nuts far from the camera's nadir (the belt's far side, y = 0.78 m: 0.24 m off the camera,
# ~0.33 m at the ends of the row) at the yaws where the old detector's aspect < 1.35 test
# rejected them as "unknown object": parallax sweeps a 10.8 mm high nut's top face up to
# 6-7 mm across the belt plane (aspect up to 1.43).
NUT_ROW_X = (-0.52, -0.45, -0.38, -0.30, -0.22, -0.15, -0.08)
NUT_YAWS_DEG = (0, 5, 15, 20, 35, 45, 55)


def test_detector_classifies_nuts_of_both_colours_at_any_yaw_far_from_the_camera(client, cell, scene):
    camera, vision = _vision(cell, 640, 480)
    y = 0.78
    failures = []
    for yaw in NUT_YAWS_DEG:
        for first, second in (("yellow", "silver"), ("silver", "yellow")):
            for part_id in list(scene.parts):
                scene.remove_part(part_id)
            truth = [(f"nut_{first if i % 2 == 0 else second}", x) for i, x in enumerate(NUT_ROW_X)]
            for name, x in truth:
                scene.add_part(name, x, y, math.radians(yaw))
            observations, result = vision.observe(render(client, camera))
            for name, x in truth:
                seen = [o for o in observations if math.hypot(o.x - x, o.y - y) < 0.003]
                if [o.class_name for o in seen] != [name]:
                    failures.append((name, x, yaw, [o.class_name for o in seen], [r.detail for r in result.rejections]))
    assert failures == []


def test_detector_rejects_look_alikes_of_nuts_and_bolts(client, cell, scene):
    """Boxes in the parts' colours and sizes: 15 and 18 mm cubes (90° corners, not a hexagon's
    120°), a 45 x 13 x 13 mm bar (a bolt's size without the head standing out of the shaft),
    a 20 x 20 x 2 mm tile; far from the nadir (largest parallax) and near it."""
    camera, vision = _vision(cell, 640, 480)
    silver, yellow = PART_CLASSES["nut_silver"].rgba, PART_CLASSES["nut_yellow"].rgba
    objects = [
        ((0.0075,) * 3, silver),
        ((0.009,) * 3, yellow),
        ((0.0225, 0.0065, 0.0065), silver),
        ((0.01, 0.01, 0.001), yellow),
    ]
    for y in (0.78, 0.62):
        for x, (half_extents, rgba) in zip((-0.50, -0.38, -0.22, -0.10), objects):
            scene.add_foreign_object(half_extents=half_extents, x=x, y=y, yaw=0.4, rgba=rgba)
    observations, result = vision.observe(render(client, camera))
    assert observations == []
    assert [r.reason for r in result.rejections] == ["unknown object"] * 8
    assert all(r.detail for r in result.rejections)


def test_shape_envelope_comes_from_the_parts_dimensions():
    from kitting.detector import hull_widths, shape_envelope

    nut = PART_CLASSES["nut_silver"]
    envelope = shape_envelope(nut, 0.8)
    assert envelope["width_min_mm"] == pytest.approx((18.0, 18.0 * 2 / math.sqrt(3)))
    assert envelope["width_max_mm"][1] == pytest.approx(18.0 * 2 / math.sqrt(3) + 10.8 * 0.8)
    assert envelope["area_mm2"][0] == pytest.approx(1e6 * nut.footprint_area)
    # A regular hexagon 18 mm across flats, and the same swept by 6 mm (its top face seen
    # obliquely): the narrowest width stays within [across flats, across corners].
    r = 18.0 / math.sqrt(3)
    hexagon = np.array([(r * math.cos(a), r * math.sin(a)) for a in np.arange(6) * math.pi / 3])
    assert hull_widths(hexagon) == pytest.approx((18.0, 2 * r))
    for angle in np.radians([0, 20, 45, 90]):
        shifted = hexagon + 6.0 * np.array([math.cos(angle), math.sin(angle)])
        points = np.vstack([hexagon, shifted]).astype(np.float32)
        narrowest, widest = hull_widths(cv2.convexHull(points).reshape(-1, 2))
        assert 18.0 - 1e-6 <= narrowest <= 2 * r + 1e-6 and widest <= 2 * r + 6.0 + 1e-6
