"""Registration never stops silently (kitting.vision_pipeline): whatever markers are seen
register the camera, with the held registration (or the calibrated pose) as the prior;
a frame that shows no marker keeps the last registration only for registration_max_age."""

import math

import numpy as np
import pytest

from kitting.calibration import extrinsics_from_marker, pose_error
from kitting.cell import load_cell
from kitting.vision_pipeline import VisionPipeline

from .test_kitting_cell import _assert_parts_located, _cover_markers, rendered  # noqa: F401  (the rendered images fixture)


@pytest.fixture(scope="module")
def cell():
    return load_cell()


def _cover(cell, camera, image, marker_ids):
    return _cover_markers(cell, camera, image, marker_ids)


def _pipeline(cell, camera, prior=None, **params):
    return VisionPipeline(cell, camera.K, camera.distortion, camera.width, camera.height, params, prior_pose=prior)


def test_one_hidden_marker_confirms_the_held_registration(cell, rendered):  # noqa: F811
    camera = rendered["camera"]
    pipeline = _pipeline(cell, camera)
    assert pipeline.process(rendered["image"], 1.0).registration == "full"
    held = pipeline.camera_pose.copy()
    one_hidden = _cover(cell, camera, rendered["image"], {cell.markers[0].id})
    result = pipeline.process(one_hidden, 1.0 + 3 * pipeline.params["registration_max_age"])
    # The other marker is where the held pose puts it: confirmed, its age restarts.
    assert result.ok and result.registration == "confirmed" and result.reason == ""
    assert pipeline.registration_time == 1.0 + 3 * pipeline.params["registration_max_age"]
    assert np.allclose(pipeline.camera_pose, held)
    _assert_parts_located(result)


def test_a_moved_camera_seeing_one_marker_is_re_registered_from_it(cell, rendered):  # noqa: F811
    pipeline = _pipeline(cell, rendered["camera"])
    pipeline.process(rendered["image"], 1.0)
    moved = rendered["moved"]
    one_hidden = _cover(cell, moved, rendered["moved_image"], {cell.markers[1].id})
    result = pipeline.process(one_hidden, 2.0)
    assert result.ok and result.registration == "partial", result.reason
    assert pipeline.counts["camera moved: re-registered"] == 1
    # One 6 cm marker fixes the camera's position along its axis poorly (~1 cm here); the
    # parts on the belt plane, what the cell picks by, stay within a few millimetres.
    position_error, angle_error = pose_error(pipeline.camera_pose, moved.pose)
    assert position_error < 0.02 and angle_error < 1.5, (position_error, angle_error)
    _assert_parts_located(result, tolerance=0.004)


def test_first_image_with_one_marker_registers_from_the_calibrated_prior(cell, rendered):  # noqa: F811
    camera = rendered["camera"]
    one_hidden = _cover(cell, camera, rendered["image"], {cell.markers[0].id})
    # Without a prior a lone marker still registers (single-marker PnP) instead of stopping.
    alone = _pipeline(cell, camera).process(one_hidden, 1.0)
    assert alone.ok and alone.registration == "partial"
    with_prior = _pipeline(cell, camera, prior=cell.camera.pose)
    result = with_prior.process(one_hidden, 1.0)
    assert result.ok and result.registration == "partial"
    _assert_parts_located(result, tolerance=0.004)


def test_no_marker_holds_the_registration_for_its_age_limit_then_stops_publishing(cell, rendered):  # noqa: F811
    camera = rendered["camera"]
    pipeline = _pipeline(cell, camera, registration_max_age=2.0)
    pipeline.process(rendered["image"], 10.0)
    none = _cover(cell, camera, rendered["image"], {m.id for m in cell.markers})
    held = pipeline.process(none, 11.9)
    assert held.ok and held.registration == "held" and held.reason == "no marker"
    stale = pipeline.process(none, 12.1)
    assert not stale.ok and stale.parts == [] and stale.registration == "none"
    assert "younger than 2 s" in stale.reason


def test_a_marker_at_the_image_border_gives_its_inner_corners(cell, rendered):  # noqa: F811
    camera = rendered["camera"]
    image = rendered["image"]
    found = extrinsics_from_marker(image, cell.markers, camera.K, camera.distortion)
    assert found.ok and not found.missing
    corners = found.image_points[:4]  # the first marker's corners, ArUco order
    left = int(math.floor(corners[:, 0].min()))
    # Crop the image so that the marker's left corners sit ~2.6 px from the border (found by
    # ArUco, inside observe_marker's 3 px margin), padded back to size on the right: the
    # principal point moves with the crop.
    crop = left - 2
    shifted = np.full_like(image, 128)
    shifted[:, : image.shape[1] - crop] = image[:, crop:]
    K = camera.K.copy()
    K[0, 2] -= crop
    strict = extrinsics_from_marker(shifted, cell.markers, K, camera.distortion)
    edge = extrinsics_from_marker(shifted, cell.markers, K, camera.distortion, edge_corners=True)
    assert strict.ok and strict.partly_hidden == [cell.markers[0].id]
    assert edge.ok and 1 <= edge.edge_corners <= 3
    assert len(edge.image_points) == 4 + edge.edge_corners
    position_error, angle_error = pose_error(edge.T_base_cam, camera.pose)
    assert position_error < 0.015 and angle_error < 1.2
