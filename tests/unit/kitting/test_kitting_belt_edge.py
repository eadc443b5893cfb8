"""The camera registration pinned by the belt's far edge (kitting.belt_edge), and the
simulated camera drawing where its intrinsics say (kitting.camera.projection_matrix)."""

import math

import cv2
import numpy as np
import pybullet as p
import pytest
from scipy.spatial.transform import Rotation

from kitting.belt_edge import far_edge, measure_line, refine_with_lines
from kitting.calibration import extrinsics_from_marker, observe_marker
from kitting.camera import PinholeCamera, render
from kitting.cell import load_cell
from kitting.sim_scene import SimScene
from kitting.vision_pipeline import VisionPipeline

# Camera offsets [dx dy dz (m), rx ry rz (rad)] inside the campaign's perturbation ranges
# (kitting.campaign: +-2 cm, +-2 degrees) where the markers alone leave the camera tilted.
OFFSETS = (
    (0.014, 0.008, -0.011, 0.021, -0.009, 0.012),
    (-0.010, -0.001, 0.010, -0.030, 0.015, -0.020),
    (0.004, -0.007, 0.017, 0.010, 0.030, 0.005),
)


@pytest.fixture(scope="module")
def cell():
    return load_cell()


@pytest.fixture(scope="module")
def views(cell):
    """(true camera, grey image, RGB image) of the empty cell from the nominal camera and
    from each of OFFSETS."""
    client = p.connect(p.DIRECT)
    try:
        SimScene(client, cell)
        nominal = PinholeCamera.from_spec(cell.camera)
        cameras = [nominal]
        for offset in OFFSETS:
            pose = nominal.pose.copy()
            pose[:3, :3] = pose[:3, :3] @ Rotation.from_rotvec(offset[3:]).as_matrix()
            pose[:3, 3] += offset[:3]
            cameras.append(nominal.with_pose(pose))
        out = []
        for camera in cameras:
            rgb = render(client, camera)
            out.append((camera, cv2.cvtColor(rgb, cv2.COLOR_RGB2GRAY), rgb))
        return out
    finally:
        p.disconnect(client)


def _belt_error_mm(cell, estimate, truth) -> float:
    """Largest belt-plane distance (mm) between where ``truth`` sees a point of the belt and
    where the ``estimate`` pose puts that pixel, over the belt in view."""
    worst = 0.0
    for x in np.linspace(truth.pose[0, 3] - 0.2, truth.pose[0, 3] + 0.2, 5):
        for y in np.linspace(cell.belt.y - 0.1, cell.belt.y + 0.1, 3):
            pixel = truth.project([[x, y, cell.belt.height]])[0]
            ray = estimate.pose[:3, :3] @ np.linalg.inv(estimate.K) @ np.r_[pixel, 1.0]
            origin = estimate.pose[:3, 3]
            hit = origin + ray * (cell.belt.height - origin[2]) / ray[2]
            worst = max(worst, 1000.0 * math.hypot(hit[0] - x, hit[1] - y))
    return worst


def test_the_rendered_image_lands_where_the_intrinsics_project(cell, views):
    # Marker corners found in the image against K's projection of the true corners: no
    # systematic offset (a half-pixel convention error shows as a mean of ~0.5 px).
    residuals = []
    for camera, grey, _ in views:
        for marker in cell.markers:
            seen = observe_marker(grey, marker, camera.K, camera.distortion)
            if seen.ok:
                residuals.append(seen.corners - camera.project(marker.corners()))
    residuals = np.vstack(residuals)
    assert len(residuals) >= 24
    assert np.all(np.abs(residuals.mean(axis=0)) < 0.15), residuals.mean(axis=0)


def test_the_far_edge_pins_the_tilt_the_markers_leave_loose(cell, views):
    markers_only, with_edge = [], []
    for camera, grey, _ in views:
        found = extrinsics_from_marker(grey, cell.markers, camera.K, camera.distortion, edge_corners=True)
        assert found.ok
        edge = far_edge(cell.belt, found.T_base_cam[1, 3])
        points = measure_line(grey, camera.with_pose(found.T_base_cam), edge)
        assert len(points) > 60  # the edge is seen across the image
        refined, corner_rms, edge_median = refine_with_lines(
            found.T_base_cam, found.object_points, found.image_points, [(edge, points)], camera.K, camera.distortion
        )
        assert corner_rms < 0.8 and edge_median < 0.5, (corner_rms, edge_median)
        markers_only.append(_belt_error_mm(cell, camera.with_pose(found.T_base_cam), camera))
        with_edge.append(_belt_error_mm(cell, camera.with_pose(refined), camera))
    # The markers alone are off by 1-3 mm somewhere on the belt; with the edge, well under 1.
    assert max(markers_only) > 1.0, markers_only
    assert max(with_edge) < 0.6, with_edge
    assert max(with_edge) < 0.5 * max(markers_only)


def test_the_edge_is_not_measured_under_the_arm_or_where_the_step_is_not_clean(cell, views):
    camera, grey, _ = views[0]
    edge = far_edge(cell.belt, camera.pose[1, 3])
    everywhere = measure_line(grey, camera, edge)
    occluded = np.zeros_like(grey)
    occluded[:, : grey.shape[1] // 2] = 255  # the arm over the left half
    right = measure_line(grey, camera, edge, occluded=occluded)
    assert 0 < len(right) < 0.6 * len(everywhere)
    assert np.all(right[:, 0] >= grey.shape[1] // 2 - 1)
    # A smear across the edge (a part, a shadow): no clean step there, no point.
    smeared = grey.copy()
    rows = int(everywhere[:, 1].min()) - 6, int(everywhere[:, 1].max()) + 7
    smeared[rows[0] : rows[1], 100:300] = np.linspace(110, 40, rows[1] - rows[0])[:, None]
    points = measure_line(smeared, camera, edge)
    assert not np.any((points[:, 0] > 104) & (points[:, 0] < 296))


def test_the_pipeline_keeps_the_markers_pose_when_the_edge_is_not_there(cell, views):
    camera, _, rgb = views[1]
    no_edge = rgb.copy()
    edge_rows = measure_line(cv2.cvtColor(rgb, cv2.COLOR_RGB2GRAY), camera, far_edge(cell.belt, camera.pose[1, 3]))[
        :, 1
    ]
    top = int(edge_rows.max()) + 20
    no_edge[:top] = no_edge[top]  # the belt's top reaches past the image: no far edge
    pipeline = VisionPipeline(cell, camera.K, camera.distortion, camera.width, camera.height)
    assert pipeline.process(no_edge, 1.0).registration == "full"
    assert pipeline.counts["belt edge not seen: markers only"] == 1
    assert pipeline.counts["registered with the belt edge"] == 0
    with_edge = VisionPipeline(cell, camera.K, camera.distortion, camera.width, camera.height)
    with_edge.process(rgb, 1.0)
    with_edge.process(rgb, 1.2)  # the same corners: the refined pose is reused, not solved again
    assert with_edge.counts["registered with the belt edge"] == 1
    assert _belt_error_mm(cell, camera.with_pose(with_edge.camera_pose), camera) < 0.6


def test_an_edge_no_pose_can_match_with_the_markers_is_not_used(cell, views):
    # The belt's far edge drawn 8 px (about 7 mm) from where the cell says it is, as if the
    # belt were declared in the wrong place: the markers and the edge cannot both be right.
    camera, grey, rgb = views[3]
    rows = measure_line(grey, camera, far_edge(cell.belt, camera.pose[1, 3]))[:, 1]
    bottom = int(rows.max()) + 20
    moved = rgb.copy()
    moved[8:bottom] = rgb[: bottom - 8]
    pipeline = VisionPipeline(cell, camera.K, camera.distortion, camera.width, camera.height)
    assert pipeline.process(moved, 1.0).registration == "full"
    assert pipeline.counts["belt edge disagrees with the markers: markers only"] == 1
    assert pipeline.counts["registered with the belt edge"] == 0
