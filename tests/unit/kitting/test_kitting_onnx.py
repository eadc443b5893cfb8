"""The ONNX detector path (kitting.onnx_detector) on rendered images, with a tiny model the
test builds itself with onnx.helper (no torch, no download) in the YOLOv8 export layout.

The model is a fixed graph that does what a trained YOLOv8 head outputs, from colour
thresholds: per class (0 yellow, 1 silver, 2 red) a foreground mask; on a stride-4 grid of
32 x 32 windows (input pixels) the mask's local moments give a box (centroid, and width /
height from the second moments: a uniform bar of length L has variance L² / 12) and a
score (the share of a 64 x 64 neighbourhood's foreground inside the window, to the 16th
power: 1 only where the window holds a whole blob; times a per-class gain). Each
(class, cell) pair is one anchor column, with its class's score and zeros elsewhere:
output 1 x (4 + 3) x 19200, boxes cx, cy, w, h in letterboxed-input pixels. The image is
640 x 480 and the input 320 x 320, so the letterbox (scale 0.5, 40 px bands) must be undone
for the positions to come out right.
"""

import math

import numpy as np
import onnx
import pybullet as p
import pytest
from onnx import TensorProto, helper

from kitting.camera import PinholeCamera, render
from kitting.cell import load_cell
from kitting.detector import belt_mask_for
from kitting.onnx_detector import OnnxDetector, OnnxModelError, letterbox
from kitting.parts import PART_CLASSES
from kitting.sim_scene import SimScene
from kitting.vision import BeltVision

SIZE = 320  # model input, px (square)
STRIDE, WINDOW, BIG = 4, 32, 64
NAMES = {0: "nut_yellow", 1: "washer_silver", 2: "screwdriver"}  # class 2: not a kitting part
GAINS = (1.0, 0.9, 1.0)  # the silver class never scores above 0.9


def _const(name, array):
    array = np.asarray(array, np.float32)
    return helper.make_tensor(name, TensorProto.FLOAT, array.shape, array.ravel().tolist())


def build_model(path, names=NAMES, metadata=True, obb_angle=None, extra_rows=0):
    """The colour-moment model described in the module docstring, saved to ``path``."""
    cells = (SIZE + 2 * (WINDOW // 2 - 2) - WINDOW) // STRIDE + 1  # 80
    anchors = 3 * cells * cells
    columns = np.arange(SIZE, dtype=np.float32) + 0.5  # pixel centres
    xmap = np.broadcast_to(columns[None, None, None, :], (1, 1, SIZE, SIZE))
    ymap = np.broadcast_to(columns[None, None, :, None], (1, 1, SIZE, SIZE))
    eye = np.eye(3, dtype=np.float32).reshape(1, 3, 3, 1)
    inits = [
        _const("xmap", xmap),
        _const("ymap", ymap),
        _const("eye", eye),
        _const("w_small", np.ones((3, 1, WINDOW, WINDOW))),
        _const("w_big", np.ones((3, 1, BIG, BIG))),
        _const("eps", 1e-3),
        _const("twelve", 12.0),
        _const("one", 1.0),
        _const("zero", 0.0),
        _const("power", 16.0),
        _const("area_min", 1.0 / 12.0),
        _const("gains", np.reshape(GAINS, (1, 3, 1, 1))),
        _const("t_sat_hi", 0.5),
        _const("t_sat_lo", 0.2),
        _const("t_bright", 0.35),
        _const("t_silver", 0.6),
        _const("t_dark", 0.25),
        helper.make_tensor("flat", TensorProto.INT64, [3], [1, 1, anchors]),
        helper.make_tensor("score_shape", TensorProto.INT64, [4], [1, 1, 3, cells * cells]),
        helper.make_tensor("out_shape", TensorProto.INT64, [3], [1, 3, anchors]),
    ]
    nodes = [helper.make_node("Split", ["images"], ["r", "g", "b"], axis=1, split=[1, 1, 1])]

    def node(op, inputs, output, **attrs):
        nodes.append(helper.make_node(op, inputs, [output], **attrs))
        return output

    def mask(op, a, b, name):
        return node("Cast", [node(op, [a, b], name + "_b")], name, to=TensorProto.FLOAT)

    top = node("Max", ["r", "g", "b"], "top")
    spread = node("Sub", [top, node("Min", ["r", "g", "b"], "bottom")], "spread")
    sat = node("Div", [spread, node("Add", [top, "eps"], "top_eps")], "sat")
    coloured = mask("Greater", sat, "t_sat_hi", "coloured")
    yellow = node(
        "Mul",
        [
            node("Mul", [coloured, mask("Greater", "g", "t_bright", "g_hi")], "y1"),
            mask("Greater", "r", "t_bright", "r_hi"),
        ],
        "yellow",
    )
    silver = node("Mul", [mask("Less", sat, "t_sat_lo", "grey"), mask("Greater", top, "t_silver", "bright")], "silver")
    red = node("Mul", [node("Mul", [coloured, "r_hi"], "red1"), mask("Less", "g", "t_dark", "g_lo")], "red")
    masks = node("Concat", [yellow, silver, red], "masks", axis=1)

    def window_sum(x, name, weights="w_small", kernel=WINDOW):
        pad = kernel // 2 - 2
        return node("Conv", [x, weights], name, group=3, strides=[STRIDE, STRIDE], pads=[pad] * 4)

    area = window_sum(masks, "area")
    big = window_sum(masks, "big", "w_big", BIG)
    area_eps = node("Add", [area, "eps"], "area_eps")
    boxes = []
    for axis, cmap in (("x", "xmap"), ("y", "ymap")):
        weighted = node("Mul", [masks, cmap], f"m{axis}")
        mean = node("Div", [window_sum(weighted, f"s{axis}"), area_eps], f"c{axis}")
        second = node(
            "Div",
            [window_sum(node("Mul", [weighted, cmap], f"m{axis}{axis}"), f"s{axis}{axis}"), area_eps],
            f"e{axis}{axis}",
        )
        variance = node(
            "Relu", [node("Sub", [second, node("Mul", [mean, mean], f"c{axis}2")], f"v{axis}0")], f"v{axis}"
        )
        extent = node(
            "Sqrt", [node("Add", [node("Mul", [variance, "twelve"], f"v{axis}12"), "one"], f"v{axis}1")], f"l{axis}"
        )
        boxes.append((mean, extent))
    fraction = node("Div", [area, node("Add", [big, "eps"], "big_eps")], "fraction")
    enough = node("Clip", [node("Mul", [area, "area_min"], "area_scaled"), "zero", "one"], "enough")
    score = node("Mul", [node("Mul", [node("Pow", [fraction, "power"], "sharp"), enough], "score0"), "gains"], "score")
    rows = [node("Reshape", [t, "flat"], f"row_{t}") for t in (boxes[0][0], boxes[1][0], boxes[0][1], boxes[1][1])]
    per_class = node("Mul", [node("Reshape", [score, "score_shape"], "score4"), "eye"], "onehot")
    rows.append(node("Reshape", [per_class, "out_shape"], "scores"))
    if obb_angle is not None:
        inits.append(_const("angle", np.full((1, 1, anchors), obb_angle)))
        rows.append("angle")
    for i in range(extra_rows):
        inits.append(_const(f"extra{i}", np.zeros((1, 1, anchors))))
        rows.append(f"extra{i}")
    nodes.append(helper.make_node("Concat", rows, ["output0"], axis=1))
    out_rows = 4 + len(names) + (obb_angle is not None) + extra_rows
    graph = helper.make_graph(
        nodes,
        "colour_moments",
        [helper.make_tensor_value_info("images", TensorProto.FLOAT, [1, 3, SIZE, SIZE])],
        [helper.make_tensor_value_info("output0", TensorProto.FLOAT, [1, out_rows, anchors])],
        inits,
    )
    model = helper.make_model(graph, opset_imports=[helper.make_opsetid("", 12)], producer_name="test_kitting_onnx")
    model.ir_version = 7
    if metadata:  # as ultralytics' exporter writes them: str() of Python values
        helper.set_model_props(
            model,
            {
                "names": str(dict(names)),
                "imgsz": str([SIZE, SIZE]),
                "task": "obb" if obb_angle is not None else "detect",
                "stride": "32",
            },
        )
    onnx.checker.check_model(model)
    onnx.save(model, str(path))
    return str(path)


@pytest.fixture(scope="module")
def cell():
    return load_cell()


@pytest.fixture(scope="module")
def camera(cell):
    return PinholeCamera.from_spec(cell.camera)


@pytest.fixture(scope="module")
def model(tmp_path_factory):
    return build_model(tmp_path_factory.mktemp("onnx") / "colour_moments.onnx")


@pytest.fixture(scope="module")
def belt_scene(cell, camera):
    """One rendered image: a yellow nut and a silver washer on the belt, a yellow nut on
    the belt's edge, a red block (the model's 'screwdriver'), seeded yaws."""
    rng = np.random.default_rng(20)
    cid = p.connect(p.DIRECT)
    try:
        scene = SimScene(cid, cell)
        belt = cell.belt
        parts = {"nut_yellow": (-0.46, belt.y - 0.03), "washer_silver": (-0.30, belt.y + 0.04)}
        for name, (x, y) in parts.items():
            scene.add_part(name, x, y, rng.uniform(-math.pi, math.pi))
        scene.add_part("nut_yellow", -0.37, belt.y + belt.width / 2, rng.uniform(-math.pi, math.pi))  # on the edge
        scene.add_foreign_object(x=-0.15, y=belt.y - 0.02)
        image = render(cid, camera)
    finally:
        p.disconnect(cid)
    return image, parts


def _expected_pixel(camera, cell, name, x, y):
    part = PART_CLASSES[name]
    return camera.project(np.array([[x, y, cell.belt.height + part.centroid_height]]))[0]


def test_letterbox_maps_points_as_documented():
    image = np.zeros((480, 640, 3), np.uint8)
    image[100:110, 200:220] = 255  # continuous box x 200..220, y 100..110
    padded, (sx, sy), (left, top) = letterbox(image, (320, 320))
    assert padded.shape == (320, 320, 3) and (sx, sy, left, top) == (0.5, 0.5, 0, 40)
    assert padded[0, 0].tolist() == [114, 114, 114] and padded[40, 0].tolist() == [0, 0, 0]
    ys, xs = np.nonzero(padded[:, :, 0] > 200)
    assert (xs.min(), xs.max() + 1) == (200 * sx + left, 220 * sx + left)
    assert (ys.min(), ys.max() + 1) == (100 * sy + top, 110 * sy + top)


def test_detects_classes_at_their_projected_pixels(model, belt_scene, cell, camera):
    image, parts = belt_scene
    detector = OnnxDetector(model, belt_mask=belt_mask_for(camera, cell.belt))
    assert detector.input_size == (SIZE, SIZE) and detector.task == "detect"
    assert detector.class_names == NAMES  # from the model's metadata
    result = detector.detect(image)
    found = {d.class_name: d for d in result.detections}
    assert sorted(found) == sorted(parts), result
    for name, (x, y) in parts.items():
        detection = found[name]
        error = np.hypot(*(np.asarray(detection.pixel) - _expected_pixel(camera, cell, name, x, y)))
        print(f"{name}: pixel {np.round(detection.pixel, 2)} error {error:.2f} px, score {detection.confidence:.3f}")
        assert error < 2.0
        assert detection.angle == 0.0  # a detect model gives no orientation
        assert detection.confidence == pytest.approx(GAINS[[k for k, v in NAMES.items() if v == name][0]], abs=0.02)
    reasons = sorted((r.reason, r.detail.split(" ")[0]) for r in result.rejections)
    assert reasons == [("edge", "nut_yellow"), ("unknown object", "model")], result.rejections
    unknown = next(r for r in result.rejections if r.reason == "unknown object")
    assert "'screwdriver'" in unknown.detail
    assert unknown.pixel[0] > 400  # the red block, right of the washer


def test_belt_vision_takes_the_onnx_detector(model, belt_scene, cell, camera):
    image, parts = belt_scene
    vision = BeltVision(camera, cell.belt, detector=OnnxDetector(model, belt_mask=belt_mask_for(camera, cell.belt)))
    observations, _ = vision.observe(image)
    assert sorted(o.class_name for o in observations) == sorted(parts)
    for obs in observations:
        x, y = parts[obs.class_name]
        assert math.hypot(obs.x - x, obs.y - y) < 0.003


def test_without_a_belt_mask_the_image_border_is_still_an_edge(model, belt_scene):
    image, parts = belt_scene
    result = OnnxDetector(model).detect(image)
    # The markers' white squares beside the belt are "silver" to this model: without a mask
    # they count; the nut on the belt's edge is inside the image, so it is a detection now.
    names = [d.class_name for d in result.detections]
    assert names.count("nut_yellow") == 2 and "washer_silver" in names
    cut = np.ascontiguousarray(image[:, :328])  # the washer (x 308-331 px) cut by the right border
    border = OnnxDetector(model).detect(cut)
    assert "washer_silver" not in [d.class_name for d in border.detections]
    assert [r.reason for r in border.rejections if r.detail.startswith("washer_silver")] == ["edge"]
    # 328 x 480 letterboxes with 50 px side bands: boxes come back centred on the pixel, nut-sized.
    nuts = [d for d in border.detections if d.class_name == "nut_yellow"]
    assert len(nuts) == 2
    for nut in nuts:
        x0, y0, x1, y1 = nut.features["box"]
        assert np.allclose([(x0 + x1) / 2 - 0.5, (y0 + y1) / 2 - 0.5], nut.pixel, atol=0.01)
        assert 12 < x1 - x0 < 30 and 12 < y1 - y0 < 30


def test_rejects_corrupt_images(model):
    detector = OnnxDetector(model)
    for bad in (
        None,
        np.zeros((0, 0, 3), np.uint8),
        np.zeros((240, 320), np.float32),
        np.zeros((240, 320, 3), np.uint8),
    ):
        result = detector.detect(bad)
        assert result.corrupt and not result.detections
    masked = OnnxDetector(model, belt_mask=np.full((480, 640), 255, np.uint8))
    result = masked.detect(np.random.default_rng(4).integers(0, 255, (240, 320, 3), dtype=np.uint8))
    assert result.corrupt and "belt mask" in result.rejections[0].detail


def test_both_detectors_are_part_detectors_with_one_image_check(model):
    from kitting.detector import ClassicalDetector, PartDetector

    classical, learned = ClassicalDetector(), OnnxDetector(model)
    assert isinstance(classical, PartDetector) and isinstance(learned, PartDetector)
    for bad in (None, np.zeros((240, 320), np.float32), np.zeros((240, 320, 3), np.uint8)):
        assert classical.detect(bad).rejections == learned.detect(bad).rejections
        assert classical.detect(bad).corrupt


def test_low_scores_are_rejected_with_the_reason(model, belt_scene, cell, camera):
    image, _ = belt_scene
    detector = OnnxDetector(model, belt_mask=belt_mask_for(camera, cell.belt), score_threshold=0.95)
    result = detector.detect(image)
    assert [d.class_name for d in result.detections] == ["nut_yellow"]
    low = [r for r in result.rejections if "low score" in r.detail]
    assert len(low) == 1 and low[0].reason == "unknown object" and "washer_silver" in low[0].detail


def test_class_names_argument_overrides_and_is_required_without_metadata(tmp_path, belt_scene, cell, camera):
    bare = build_model(tmp_path / "bare.onnx", metadata=False)
    with pytest.raises(OnnxModelError, match="class_names"):
        OnnxDetector(bare)
    detector = OnnxDetector(
        bare, class_names=["nut_silver", "washer_yellow", "bolt_yellow"], belt_mask=belt_mask_for(camera, cell.belt)
    )
    assert detector.input_size == (SIZE, SIZE)  # from the static input shape
    result = detector.detect(belt_scene[0])
    assert sorted(d.class_name for d in result.detections) == ["bolt_yellow", "nut_silver", "washer_yellow"]
    with pytest.raises(OnnxModelError, match=r"does not fit a 'detect' model of 2 classes"):
        OnnxDetector(bare, class_names=["nut_yellow", "washer_silver"])


def test_obb_layout_gives_the_angle(tmp_path, belt_scene, cell, camera):
    obb = build_model(tmp_path / "obb.onnx", obb_angle=1.3)
    detector = OnnxDetector(obb, belt_mask=belt_mask_for(camera, cell.belt))
    assert detector.task == "obb"
    found = {d.class_name: d for d in detector.detect(belt_scene[0]).detections}
    assert sorted(found) == ["nut_yellow", "washer_silver"]
    assert found["nut_yellow"].angle == pytest.approx(1.3 % (math.pi / 3))  # a nut: mod 60°
    assert found["washer_silver"].angle == 0.0


def test_model_file_errors_say_what_to_do(tmp_path):
    with pytest.raises(OnnxModelError, match="not found.*README.*detector: classical"):
        OnnxDetector(tmp_path / "missing.onnx")
    garbage = tmp_path / "garbage.onnx"
    garbage.write_bytes(b"this is not a protobuf" * 10)
    with pytest.raises(OnnxModelError, match="not a model onnxruntime can load.*yolo export"):
        OnnxDetector(garbage)
    odd = build_model(tmp_path / "odd.onnx", extra_rows=3)
    with pytest.raises(OnnxModelError, match=r"'detect' model of 3 classes .*expected 1 x 7 x N"):
        OnnxDetector(odd)
    obb = build_model(tmp_path / "obb.onnx", metadata=False, obb_angle=0.0)
    with pytest.raises(OnnxModelError, match="pass task='obb'"):
        OnnxDetector(obb, class_names=NAMES)
    assert OnnxDetector(obb, class_names=NAMES, task="obb").task == "obb"
    with pytest.raises(OnnxModelError, match="multiples of 32"):
        OnnxDetector(build_model(tmp_path / "m.onnx", metadata=False), class_names=NAMES, input_size=300)


def test_belt_inner_is_eroded_again_for_a_new_belt_mask():
    """Each re-registration gives the detectors a new belt mask: the edge zone must follow it
    (the ONNX detector used to keep the first mask's)."""
    from kitting.detector import BeltInner

    inner = BeltInner()
    first = np.zeros((60, 80), np.uint8)
    first[10:50, 10:40] = 255
    moved = np.zeros((60, 80), np.uint8)
    moved[10:50, 40:70] = 255
    a = inner.get(first, first.shape, 3)
    assert a[30, 25] and not a[30, 55]
    assert inner.get(first, first.shape, 3) is a  # same mask: reused, not eroded again
    b = inner.get(moved, moved.shape, 3)
    assert b[30, 55] and not b[30, 25]
    whole = inner.get(None, (60, 80), 3)  # no mask: only the image border is edge
    assert whole[30, 40] and not whole[1, 40]
