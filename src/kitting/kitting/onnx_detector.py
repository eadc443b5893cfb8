"""The pluggable learned detector: a YOLOv8 model exported to ONNX, run with onnxruntime on
the CPU. A ``PartDetector`` like ``ClassicalDetector``: ``detect(image) -> DetectionResult``
with the same ``Detection`` / ``Rejection`` records and the same image check, so
``BeltVision(camera, belt, detector=...)`` takes either.

What the model must be (the layout of ``yolo export format=onnx`` of a YOLOv8 detect or
OBB model; the README's "ONNX detector: training and export" says how to make one):

* Input: one tensor 1 x 3 x H x W, float32, RGB, values in [0, 1] (``images``), H x W the
  training ``imgsz`` (a static export; a dynamic one is fed ``input_size``).
* Output: the first output, 1 x (4 + nc) x N (detect) or 1 x (4 + nc + 1) x N (OBB), one
  column per anchor: box centre x, centre y, width, height in input pixels (of the
  letterboxed H x W image, pixel edges at integers: the top-left pixel spans [0, 1]), then
  nc class scores in [0, 1] (sigmoid already applied: there is no separate objectness),
  then, for OBB, the box angle in radians (the width side's direction, x towards y:
  clockwise on screen). No NMS in the graph (not ``nms=True``; not the 1 x 300 x 6
  end-to-end layout of YOLOv10 / YOLO26).
* Class names: the ``names`` metadata entry of the export (``{0: 'bolt_yellow', ...}``),
  unless ``class_names`` is given (a list in class-index order, or a dict index -> name).
  ``task`` (detect | obb) and ``imgsz`` are read from the metadata too when present.

Preprocessing (ultralytics' ``LetterBox(auto=False)``, as in its own ONNX predictor): the
RGB uint8 image (the kitting convention; a BGR camera frame must be converted first) is
scaled by r = min(H / h, W / w) to round(w r) x round(h r) with ``cv2.INTER_LINEAR``
(unless already that size), centred, and padded to H x W with grey (114, 114, 114); then
/ 255, HWC -> CHW, float32, a batch of one.

Postprocessing:

1. Candidates: each anchor's best class and its score; anchors scoring below
   ``report_threshold`` are background.
2. NMS across classes (parts on a belt do not overlap, and one part scored as two classes
   must give one answer): ``cv2.dnn.NMSBoxes`` on the boxes (``cv2.dnn.NMSBoxesRotated``
   for OBB) with IoU threshold ``nms_iou``.
3. Each kept box is mapped back to image pixels (the letterbox undone). With a
   ``belt_mask`` (uint8, 255 = belt, the image's size) a box with no pixel on the belt is
   ignored (a part in the tray, a marker: not the belt's business, as the classical
   detector ignores them); a box that reaches past the belt region's border (within
   ``edge_px``), or the image's border (with or without a mask), is rejected as
   ``"edge"``. The box is the part's extent, so this is the classical check on the
   silhouette whenever the belt's edges run along the image axes (the cell's camera looks
   across the belt) and conservative otherwise.
4. A class the model knows but ``kitting.parts.PART_CLASSES`` does not (a model trained
   with a "foreign" class, or on other parts) is rejected as ``"unknown object"``; so is a
   kitting class scoring below ``score_threshold`` (detail "low score ..."). The rejection
   reasons are the classical detector's: "corrupt image", "edge", "unknown object".
5. A detection's ``pixel`` is the box centre in pixel-index coordinates (pixel i's centre
   at i, as ``ClassicalDetector`` and ``PinholeCamera.project`` use); ``confidence`` is the
   class score; ``angle`` is 0 for a detect model (it gives no orientation), and for an
   OBB model the box angle reduced as the classical detector reports it: a bolt's axis
   (the box's long side, mod pi), a nut's flat direction (mod pi/3), 0 for a washer.

The box centre is not quite the footprint's area centroid for a bolt (the head is wider
than the shaft: ~1.4 mm along the axis), which ``BeltVision`` takes as the part's position.
"""

import ast
import math
import os
from collections.abc import Sequence

import cv2
import numpy as np

from .detector import Detection, PartDetector, Rejection
from .parts import PART_CLASSES

LETTERBOX_GREY = 114
README_HINT = "see src/kitting/README.md, 'ONNX detector: training and export'"


class OnnxModelError(ValueError):
    """A model file the detector cannot use; the message says what to do."""


def letterbox(image: np.ndarray, size: tuple[int, int]) -> tuple[np.ndarray, tuple[float, float], tuple[int, int]]:
    """``image`` (h x w x 3) scaled to fit ``size`` = (H, W), centred and padded with grey.

    Returns (padded image, (sx, sy) scale of the resized image, (left, top) padding): an
    image point x (continuous, pixel edges at integers) lands at x * sx + left."""
    height, width = size
    h, w = image.shape[:2]
    r = min(height / h, width / w)
    new_w, new_h = int(round(w * r)), int(round(h * r))
    if (new_w, new_h) != (w, h):
        image = cv2.resize(image, (new_w, new_h), interpolation=cv2.INTER_LINEAR)
    dw, dh = (width - new_w) / 2, (height - new_h) / 2
    top, bottom = int(round(dh - 0.1)), int(round(dh + 0.1))
    left, right = int(round(dw - 0.1)), int(round(dw + 0.1))
    if top or bottom or left or right:
        image = cv2.copyMakeBorder(image, top, bottom, left, right, cv2.BORDER_CONSTANT, value=(LETTERBOX_GREY,) * 3)
    return image, (new_w / w, new_h / h), (left, top)


def _parse_names(value) -> dict[int, str]:
    """Class names from a list / tuple / dict or the metadata string ``"{0: 'a', 1: 'b'}"``."""
    if isinstance(value, str):
        try:
            value = ast.literal_eval(value)
        except (ValueError, SyntaxError) as error:
            raise OnnxModelError(
                f"the model's 'names' metadata {value[:80]!r} is not a dict of class names "
                f"({error}): pass class_names=[...] in the model's class order"
            ) from None
    if isinstance(value, dict):
        names = {int(k): str(v) for k, v in value.items()}
    elif isinstance(value, (list, tuple)):
        names = {i: str(v) for i, v in enumerate(value)}
    else:
        raise OnnxModelError(f"class names must be a list or a dict index -> name, not {type(value).__name__}")
    if sorted(names) != list(range(len(names))):
        raise OnnxModelError(f"class indices {sorted(names)} are not 0..{len(names) - 1}")
    return names


def _size(value) -> tuple[int, int]:
    """(H, W) from an int, a pair, or the metadata string ``"[640, 640]"``."""
    try:
        if isinstance(value, str):
            value = ast.literal_eval(value)
        if isinstance(value, (int, np.integer)):
            value = (value, value)
        height, width = (int(v) for v in value)
    except (ValueError, TypeError, SyntaxError):
        raise OnnxModelError(
            f"input size {value!r} is not an int or (H, W): pass input_size=640 or (480, 640)"
        ) from None
    if height < 32 or width < 32 or height % 32 or width % 32:
        raise OnnxModelError(f"input size {height}x{width}: YOLOv8 needs multiples of 32 (imgsz)")
    return height, width


class OnnxDetector(PartDetector):
    """A YOLOv8 ONNX model as a part detector (``PartDetector``; see the module docstring for
    the layout).

    ``model_path``: the .onnx file. ``class_names``: overrides the model's ``names``
    metadata. ``input_size``: int or (H, W); default the metadata's ``imgsz``, else the
    model's static input shape, else 640. ``score_threshold``: a kitting class scoring at
    least this is a detection; ``report_threshold``: boxes scoring at least this (but less
    than ``score_threshold``) are reported as low-score rejections, lower ones are
    background. ``nms_iou``: NMS IoU threshold. ``belt_mask``/``edge_px``: as
    ``ClassicalDetector``. ``threads``: onnxruntime intra-op threads (None: its default).
    ``task``: "detect" or "obb"; default the metadata's ``task``, else "detect".
    """

    name = "onnx"

    def __init__(
        self,
        model_path: str,
        class_names: Sequence[str] | dict[int, str] | None = None,
        input_size: int | tuple[int, int] | None = None,
        score_threshold: float = 0.5,
        nms_iou: float = 0.45,
        belt_mask: np.ndarray | None = None,
        report_threshold: float = 0.25,
        edge_px: int = 2,
        max_detections: int = 100,
        threads: int | None = None,
        task: str | None = None,
    ):
        if not 0.0 < score_threshold <= 1.0:
            raise ValueError(f"score_threshold {score_threshold} must be in (0, 1]")
        if not 0.0 < report_threshold <= score_threshold:
            raise ValueError(f"report_threshold {report_threshold} must be in (0, score_threshold={score_threshold}]")
        if not 0.0 < nms_iou <= 1.0:
            raise ValueError(f"nms_iou {nms_iou} must be in (0, 1]")
        super().__init__(belt_mask)
        self.model_path = os.path.abspath(os.path.expanduser(str(model_path)))
        self.score_threshold, self.report_threshold, self.nms_iou = score_threshold, report_threshold, nms_iou
        self.edge_px, self.max_detections = int(edge_px), int(max_detections)
        self.session = self._open(threads)
        meta = self.session.get_modelmeta().custom_metadata_map or {}
        self.metadata = dict(meta)
        model_input = self.session.get_inputs()[0]
        self.input_name = model_input.name
        shape = list(model_input.shape)
        if len(shape) != 4 or (isinstance(shape[1], int) and shape[1] != 3):
            raise OnnxModelError(
                f"{self.model_path}: input {model_input.name} has shape {shape}; expected "
                f"1 x 3 x H x W (a YOLOv8 image model): re-export it, {README_HINT}"
            )
        static = tuple(shape[2:]) if all(isinstance(v, int) and v > 0 for v in shape[2:]) else None
        if input_size is not None:
            self.input_size = _size(input_size)
            if static and static != self.input_size:
                raise OnnxModelError(
                    f"{self.model_path}: input_size {self.input_size} but the model takes a fixed "
                    f"{static[0]}x{static[1]} input: drop input_size or re-export with that imgsz"
                )
        elif "imgsz" in meta:
            self.input_size = _size(meta["imgsz"])
        elif static:
            self.input_size = _size(static)
        else:
            self.input_size = (640, 640)
        if class_names is None and "names" not in meta:
            raise OnnxModelError(
                f"{self.model_path} has no class names in its metadata (not an ultralytics "
                f"export?): pass class_names=[...] in the model's class order"
            )
        self.class_names = _parse_names(meta["names"] if class_names is None else class_names)
        self.task = task or meta.get("task") or "detect"
        if self.task not in ("detect", "obb"):
            raise OnnxModelError(
                f"{self.model_path} is a YOLOv8 '{self.task}' model; the detector runs 'detect' "
                f"or 'obb' models: train one of those, {README_HINT}"
            )
        output = self.session.get_outputs()[0]
        self.output_name = output.name
        self._layout_checked = False
        if len(output.shape) == 3 and isinstance(output.shape[1], int):
            self._check_layout(output.shape)

    def _open(self, threads):
        if not os.path.isfile(self.model_path):
            raise OnnxModelError(
                f"ONNX model {self.model_path} not found: train and export a YOLOv8 model "
                f"({README_HINT}) and set onnx_model to its path, or use detector: classical"
            )
        try:
            import onnxruntime
        except ImportError as error:
            raise OnnxModelError(
                f"onnxruntime is not installed ({error}): run scripts/setup (it installs the pinned requirements.txt)"
            ) from None
        options = onnxruntime.SessionOptions()
        options.log_severity_level = 3
        if threads:
            options.intra_op_num_threads = int(threads)
        try:
            return onnxruntime.InferenceSession(self.model_path, options, providers=["CPUExecutionProvider"])
        except Exception as error:  # onnxruntime raises its own (pybind) types: InvalidProtobuf, Fail, ...
            raise OnnxModelError(
                f"{self.model_path} is not a model onnxruntime can load "
                f"({type(error).__name__}: {str(error)[:300]}): re-export it with "
                f"`yolo export model=best.pt format=onnx opset=12` ({README_HINT})"
            ) from None

    def _check_layout(self, shape):
        """The output has 4 + nc rows (detect) or 4 + nc + 1 (obb)."""
        nc = len(self.class_names)
        expected = 4 + nc + (self.task == "obb")
        if shape[1] != expected:
            hint = ""
            if self.task == "detect" and shape[1] == expected + 1:
                hint = " (one row more: an OBB model without metadata? pass task='obb')"
            elif len(shape) == 3 and shape[2] in (expected, 6):
                hint = (
                    " (it looks transposed or end-to-end: export a YOLOv8 model without nms=True,"
                    " whose output is 1 x (4 + nc) x anchors)"
                )
            raise OnnxModelError(
                f"{self.model_path}: output {list(shape)} does not fit a '{self.task}' model of "
                f"{nc} classes {list(self.class_names.values())}: expected 1 x {expected} x N"
                f"{hint}; pass the model's own class_names or re-export it, {README_HINT}"
            )
        self._layout_checked = True

    # -- detection --------------------------------------------------------------------------
    def preprocess(self, image: np.ndarray):
        """(1 x 3 x H x W float32 blob, scale (sx, sy), padding (left, top))."""
        padded, scale, pad = letterbox(image, self.input_size)
        blob = np.ascontiguousarray(padded.transpose(2, 0, 1)[None], dtype=np.float32) / np.float32(255.0)
        return blob, scale, pad

    def _detect(self, image, result):
        h, w = image.shape[:2]
        blob, (sx, sy), (left, top) = self.preprocess(image)
        output = self.session.run([self.output_name], {self.input_name: blob})[0]
        output = np.asarray(output, np.float32)
        if output.ndim != 3 or output.shape[0] != 1:
            raise OnnxModelError(f"{self.model_path}: output shape {output.shape}, expected 1 x (4 + nc) x N")
        if not self._layout_checked:
            self._check_layout(output.shape)
        rows = output[0].T  # N x (4 + nc [+ 1])
        nc = len(self.class_names)
        scores_all = rows[:, 4 : 4 + nc]
        classes = scores_all.argmax(axis=1)
        scores = scores_all[np.arange(len(rows)), classes]
        keep = np.flatnonzero(scores >= self.report_threshold)
        if keep.size == 0:
            return
        keep = keep[np.argsort(-scores[keep], kind="stable")][:30000]
        boxes = rows[keep, :4].astype(float)
        angles = rows[keep, 4 + nc].astype(float) if self.task == "obb" else np.zeros(len(keep))
        chosen = self._nms(boxes, angles, scores[keep])
        for i in chosen[: self.max_detections]:
            self._judge(
                boxes[i],
                angles[i],
                int(classes[keep[i]]),
                float(scores[keep[i]]),
                (sx, sy),
                (left, top),
                (h, w),
                result,
            )

    def _nms(self, boxes, angles, scores) -> list[int]:
        score_list = [float(s) for s in scores]
        if self.task == "obb":
            rects = [
                ((float(cx), float(cy)), (float(bw), float(bh)), math.degrees(a))
                for (cx, cy, bw, bh), a in zip(boxes, angles)
            ]
            indices = cv2.dnn.NMSBoxesRotated(rects, score_list, self.report_threshold, self.nms_iou)
        else:
            rects = [(float(cx - bw / 2), float(cy - bh / 2), float(bw), float(bh)) for cx, cy, bw, bh in boxes]
            indices = cv2.dnn.NMSBoxes(rects, score_list, self.report_threshold, self.nms_iou)
        return [int(i) for i in np.asarray(indices).reshape(-1)]

    def _judge(self, box, angle, class_id, score, scale, pad, image_size, result):
        """One kept box: a detection, a rejection, or nothing (off the belt)."""
        cx, cy, bw, bh = box
        if self.task == "obb":
            corners = cv2.boxPoints(((cx, cy), (bw, bh), math.degrees(angle)))
            x0, y0 = corners.min(axis=0)
            x1, y1 = corners.max(axis=0)
        else:
            x0, y0, x1, y1 = cx - bw / 2, cy - bh / 2, cx + bw / 2, cy + bh / 2
        (sx, sy), (left, top) = scale, pad
        # Back to image coordinates (continuous, pixel edges at integers), then pixel indices.
        x0, x1 = (x0 - left) / sx, (x1 - left) / sx
        y0, y1 = (y0 - top) / sy, (y1 - top) / sy
        pixel = ((cx - left) / sx - 0.5, (cy - top) / sy - 0.5)
        box_px = (float(x0), float(y0), float(x1), float(y1))
        name = self.class_names[class_id]
        place = self._placement(box_px, image_size)
        if place == "off belt":
            return
        if place == "edge":
            result.rejections.append(
                Rejection("edge", pixel, f"{name} box {np.round(box_px, 1).tolist()} reaches the image or belt border")
            )
            return
        if name not in PART_CLASSES:
            result.rejections.append(
                Rejection("unknown object", pixel, f"model class {name!r} (score {score:.2f}) is not a kitting part")
            )
            return
        if score < self.score_threshold:
            result.rejections.append(
                Rejection("unknown object", pixel, f"low score {score:.2f} < {self.score_threshold:.2f} (best: {name})")
            )
            return
        features = {"box": box_px, "class_id": class_id, "score": score, "detector": self.name}
        result.detections.append(Detection(name, pixel, self._angle(name, bw, bh, angle), score, features))

    def _placement(self, box, image_size) -> str:
        """ "ok", "edge" or "off belt" for a box (x0, y0, x1, y1) in image coordinates."""
        h, w = image_size
        margin = self.edge_px
        c0, r0 = int(math.floor(box[0])), int(math.floor(box[1]))
        c1, r1 = int(math.ceil(box[2])) - 1, int(math.ceil(box[3])) - 1  # last pixel indices covered
        if self.belt_mask is not None:
            region = self.belt_mask[max(r0, 0) : min(r1, h - 1) + 1, max(c0, 0) : min(c1, w - 1) + 1]
            if region.size == 0 or not region.any():
                return "off belt"
        if c0 < margin + 1 or r0 < margin + 1 or c1 > w - margin - 2 or r1 > h - margin - 2:
            return "edge"
        if self.belt_mask is not None:
            inner = self.belt_inner(self.belt_mask.shape, margin + 1)
            if not inner[r0 : r1 + 1, c0 : c1 + 1].all():
                return "edge"
        return "ok"

    def _angle(self, name, bw, bh, angle) -> float:
        """Image orientation as ``ClassicalDetector`` reports it (0 without an OBB angle)."""
        if self.task != "obb":
            return 0.0
        kind = PART_CLASSES[name].kind
        if kind == "washer":
            return 0.0
        if kind == "bolt":
            axis = angle if bw >= bh else angle + math.pi / 2
            return float(axis % math.pi)
        return float(angle % (math.pi / 3))
