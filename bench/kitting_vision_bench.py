#!/usr/bin/env python3
"""Kitting vision benchmark: rendering, detection, classification and belt-plane pose error
over seeded random part placements.

    bench/run kitting_vision_bench [--images N] [--seed S] [--parts-per-image K] [--worker-frames F]
                                   [--exposure-time T]

Per image, K parts of random classes are placed at random, separated positions and yaws
on the belt in the camera's view; the cell's camera renders it at 640x480 (TinyRenderer,
in process); the classical detector finds and classifies them; each detection is matched
to the nearest true part. The camera pose used for pixel->belt is the one calibrated from
the cell's ArUco markers (one supersampled image), as the vision node will do; the pose
error with the true camera is reported alongside. Also: ChArUco intrinsics on rendered
board views, and the render round trip through the separate render process.

"realistic": the same placements again as the simulated cell's camera now draws them: the
arm (none, at its wait position, or coming down on one of the parts at a random height),
the belt's parts blurred over the exposure time (``--exposure-time``, default the cell
camera's declared one) at a belt speed drawn as the campaign perturbs it (x 0.7-1.3), the
lighting (x 0.7-1.2) and the exposure's gain, offset and gamma drawn from their declared
ranges; the vision masks the arm from its joints. Reported: render cost, detection rate
of the parts the arm does not cover, confusions, pose error, and detections that are no
part (the arm seen as a part).
Prints p50/p99 timings, accuracy, pose-error percentiles, rejections and every part that
was missed or confused (with the detector's reason). Writes
bench/results/kitting_vision_bench.json (seed 1) or kitting_vision_bench_seed<S>.json.
"""

import argparse
import math
import os
import sys
import time

import numpy as np

ROOT = os.path.abspath(os.path.join(os.path.dirname(__file__), ".."))
for package in ("motion_common", "kitting"):
    sys.path.insert(0, os.path.join(ROOT, "src", package))
sys.path.insert(0, os.path.join(ROOT, "bench"))

import pybullet as p  # noqa: E402

from bench_common import write_results  # noqa: E402
from kitting.calibration import BoardSpec, calibrate_intrinsics, extrinsics_from_marker, pose_error  # noqa: E402
from kitting.camera import Lighting, PinholeCamera, render  # noqa: E402
from kitting.camera_effects import Exposure  # noqa: E402
from kitting.cell import load_cell  # noqa: E402
from kitting.interfaces import KITTING_CELL_SIM  # noqa: E402
from kitting.parts import CLASS_NAMES, PART_CLASSES  # noqa: E402
from kitting.render_worker import RenderWorker, RobotBody, realistic_image  # noqa: E402
from kitting.robot_silhouette import RobotSilhouette, robot_urdf  # noqa: E402
from kitting.sim_scene import SimScene, render_board_views  # noqa: E402
from kitting.vision import BeltVision  # noqa: E402
from motion_common.kinematics import RobotKinematics, pose_to_se3  # noqa: E402


def pct(values, q):
    return round(float(np.percentile(values, q)), 3) if len(values) else None


def placements(rng, cell, count, view):
    """``count`` positions on the belt inside the camera's view, at least 6 cm apart."""
    belt = cell.belt
    chosen = []
    while len(chosen) < count:
        x = rng.uniform(*view)
        y = rng.uniform(belt.y - belt.width / 2 + 0.03, belt.y + belt.width / 2 - 0.03)
        if all(math.hypot(x - a, y - b) > 0.06 for a, b in chosen):
            chosen.append((x, y))
    return chosen


WAIT = [-0.20, 0.55, 0.35]  # m, the kitting node's wait position (config/kitting.yaml)
HOME = np.array([0.0, -1.5707963, 1.5707963, -1.5707963, -1.5707963, 0.0])


class Arm:
    """The cell's robot: joints for a tool position (tool z down) and its image mask."""

    def __init__(self, cell):
        self.cell = cell
        self.kinematics = RobotKinematics(robot_urdf(cell.robot))
        self.names = [self.kinematics.model.names[j] for j in range(1, self.kinematics.model.njoints)]
        self.silhouette = RobotSilhouette(robot_urdf(cell.robot), cell.gripper.tcp_length)

    def joints(self, tool):
        result = self.kinematics.solve_ik(pose_to_se3(tool, [1.0, 0.0, 0.0, 0.0]), HOME, max_iterations=300)
        return (self.names, list(result.joints)) if result.success else None

    def random_pose(self, rng, truth):
        """None (no arm in view), the wait position, or the magnet over one of the parts."""
        draw = rng.uniform()
        if draw < 0.25:
            return None
        if draw < 0.5:
            return self.joints(WAIT)
        name, x, y, _ = truth[int(rng.integers(len(truth)))]
        gap = rng.uniform(0.002, 0.08)
        top = self.cell.belt.height + PART_CLASSES[name].height
        return self.joints([x, y, top + gap + self.cell.gripper.tcp_length])


def charuco(client):
    spec = BoardSpec()
    camera = PinholeCamera(640, 480, np.array([[600.0, 0, 319.5], [0, 600.0, 239.5], [0, 0, 1]]))
    images = render_board_views(client, spec, camera, 15)
    result = calibrate_intrinsics(images, spec)
    return {
        "views": result.views_used,
        "fx": round(result.fx, 3),
        "fy": round(result.fy, 3),
        "true_f": 600.0,
        "focal_error_pct": round(100 * max(abs(result.fx / 600 - 1), abs(result.fy / 600 - 1)), 3),
        "cx": round(float(result.K[0, 2]), 3),
        "cy": round(float(result.K[1, 2]), 3),
        "reprojection_rms_px": round(result.rms, 4),
    }


def realistic(real, rng, args, cell, client, scene, robot, arm, true_camera, vision, truth):
    """The image of ``truth`` as the cell's camera draws it now (module docstring), through
    the vision with the arm masked; statistics added to ``real``."""
    declared = KITTING_CELL_SIM.params
    joints = arm.random_pose(rng, truth)
    robot.pose(joints)
    level = rng.uniform(0.7, 1.2)
    base = Lighting()
    lighting = Lighting(base.direction, base.color, base.ambient * level, base.diffuse * level, base.specular)
    exposure = Exposure(
        *(float(rng.uniform(*declared.default(name))) for name in ("gain_range", "offset_range", "gamma_range"))
    )
    blur = (args.exposure_time, cell.belt.speed * rng.uniform(0.7, 1.3))
    start = time.perf_counter()
    image = realistic_image(client, scene, cell, true_camera, lighting, 1, blur, exposure)
    real["render_ms"].append(1000 * (time.perf_counter() - start))
    robot.pose(None)  # the plain images have no arm
    start = time.perf_counter()
    q = None if joints is None else arm.silhouette.configuration(*joints)
    margin = 6.0  # the vision pipeline's declared robot_mask_margin_px
    vision.detector.occluded = None if q is None else arm.silhouette.mask(vision.camera, q, margin)
    observations, result = vision.observe(image)
    real["detect_ms"].append(1000 * (time.perf_counter() - start))
    vision.detector.occluded = None
    covered = np.zeros((true_camera.height, true_camera.width), bool)
    if q is not None:
        covered = arm.silhouette.mask(true_camera, q) > 0
        real["arm_in_view"] += bool(covered.any())
    for rejection in result.rejections:
        real["rejections"][rejection.reason] = real["rejections"].get(rejection.reason, 0) + 1
    for obs in observations:
        name, x, y, _ = min(truth, key=lambda t: math.hypot(t[1] - obs.x, t[2] - obs.y))
        error = 1000 * math.hypot(x - obs.x, y - obs.y)
        if error > 15:
            real["not_a_part"] += 1  # e.g. the arm seen as a part
            continue
        pixel = np.round(true_camera.project([[x, y, cell.belt.height]])[0]).astype(int)
        inside = 0 <= pixel[0] < true_camera.width and 0 <= pixel[1] < true_camera.height
        if inside and covered[pixel[1], pixel[0]]:
            real["hidden_seen"] += 1
        real["correct"] += obs.class_name == name
        real["errors"].append(error)
    for name, x, y, _ in truth:
        # A part counts as visible when no pixel of its bounding circle is under the arm.
        centre = true_camera.project([[x, y, cell.belt.height]])[0]
        distance = true_camera.pose[2, 3] - cell.belt.height
        radius = 1.2 * PART_CLASSES[name].length / 2 * true_camera.fx / distance
        ys, xs = np.ogrid[: true_camera.height, : true_camera.width]
        near = (xs - centre[0]) ** 2 + (ys - centre[1]) ** 2 <= radius**2
        if np.any(near & covered):
            real["hidden"] += 1
            continue
        real["visible"] += 1
        real["detected"] += any(
            o.class_name == name and 1000 * math.hypot(x - o.x, y - o.y) <= 15 for o in observations
        )


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--images", type=int, default=120, help="rendered images (default 120)")
    parser.add_argument("--parts-per-image", type=int, default=3, help="random parts per image (default 3)")
    parser.add_argument(
        "--seed",
        type=int,
        default=1,
        help="seed of the placements, classes and yaws (default 1; another seed also "
        "names the result file kitting_vision_bench_seed<S>.json)",
    )
    parser.add_argument("--worker-frames", type=int, default=20, help="frames through the render process (default 20)")
    declared = KITTING_CELL_SIM.params
    parser.add_argument(
        "--exposure-time",
        type=float,
        default=declared.default("exposure_time"),
        help="exposure time of the realistic images (s; default the cell camera's, %(default)s)",
    )
    args = parser.parse_args()

    cell = load_cell()
    client = p.connect(p.DIRECT)
    intrinsics = charuco(client)
    p.resetSimulation(physicsClientId=client)
    scene = SimScene(client, cell)
    true_camera = PinholeCamera.from_spec(cell.camera)
    calibration = extrinsics_from_marker(
        render(client, true_camera, supersample=2), cell.markers, true_camera.K, true_camera.distortion
    )
    if not calibration.ok:
        sys.exit(f"marker calibration failed: {calibration.reason}")
    position_error, angle_error = pose_error(calibration.T_base_cam, true_camera.pose)
    camera = true_camera.with_pose(calibration.T_base_cam)
    vision = BeltVision(camera, cell.belt)
    vision_true = BeltVision(true_camera, cell.belt)

    rng = np.random.default_rng(args.seed)
    view = (true_camera.pose[0, 3] - 0.24, true_camera.pose[0, 3] + 0.24)
    render_ms, detect_ms, errors, errors_true = [], [], [], []
    per_class = {name: {"placed": 0, "detected": 0, "correct": 0, "errors_mm": []} for name in CLASS_NAMES}
    confusion = {name: {} for name in CLASS_NAMES}
    rejections, misses = {}, []
    arm = Arm(cell)
    robot = RobotBody(client, cell)
    robot.pose(None)
    real = {"render_ms": [], "detect_ms": [], "errors": [], "visible": 0, "detected": 0, "correct": 0}
    real.update({"hidden": 0, "hidden_seen": 0, "not_a_part": 0, "rejections": {}, "arm_in_view": 0})
    real_rng = np.random.default_rng(args.seed + 1000)
    for image_index in range(args.images):
        for part_id in list(scene.parts):
            scene.remove_part(part_id)
        truth = []
        for x, y in placements(rng, cell, args.parts_per_image, view):
            name = CLASS_NAMES[int(rng.integers(len(CLASS_NAMES)))]
            yaw = rng.uniform(-math.pi, math.pi)
            scene.add_part(name, x, y, yaw)
            truth.append((name, x, y, yaw))
            per_class[name]["placed"] += 1
        start = time.perf_counter()
        image = render(client, true_camera)
        render_ms.append(1000 * (time.perf_counter() - start))
        start = time.perf_counter()
        observations, result = vision.observe(image)
        detect_ms.append(1000 * (time.perf_counter() - start))
        observations_true, _ = vision_true.observe(image)
        for rejection in result.rejections:
            rejections[rejection.reason] = rejections.get(rejection.reason, 0) + 1
        # The two visions have their own belt masks: a part on the mask's border may be seen by
        # one only, so pair them by pixel (the same blob has the same centroid), not by order.
        by_pixel = {tuple(np.round(o.pixel, 3)): o for o in observations_true}
        found = {}
        for obs in observations:
            obs_true = by_pixel.get(tuple(np.round(obs.pixel, 3)))
            name, x, y, _ = min(truth, key=lambda t: math.hypot(t[1] - obs.x, t[2] - obs.y))
            error = 1000 * math.hypot(x - obs.x, y - obs.y)
            if error > 15:
                continue  # not this part
            stats = per_class[name]
            stats["detected"] += 1
            stats["correct"] += obs.class_name == name
            confusion[name][obs.class_name] = confusion[name].get(obs.class_name, 0) + 1
            stats["errors_mm"].append(error)
            errors.append(error)
            if obs_true is not None:
                errors_true.append(1000 * math.hypot(x - obs_true.x, y - obs_true.y))
            found[(x, y)] = obs.class_name
        for name, x, y, yaw in truth:
            if found.get((x, y)) == name:
                continue
            pixel = camera.project([[x, y, cell.belt.height]])[0]
            near = [
                r
                for r in result.rejections
                if r.pixel is not None and math.hypot(r.pixel[0] - pixel[0], r.pixel[1] - pixel[1]) < 25
            ]
            nearest = min(observations, key=lambda o: math.hypot(x - o.x, y - o.y), default=None)
            misses.append(
                {
                    "image": image_index,
                    "class": name,
                    "x": round(x, 4),
                    "y": round(y, 4),
                    "yaw_deg": round(math.degrees(yaw), 1),
                    "seen_as": found.get((x, y)),
                    "reason": near[0].reason if near else None,
                    "detail": near[0].detail if near else "",
                    "nearest_detection": None
                    if nearest is None
                    else [nearest.class_name, round(1000 * math.hypot(x - nearest.x, y - nearest.y), 1)],
                }
            )
        realistic(real, real_rng, args, cell, client, scene, robot, arm, true_camera, vision, truth)
    robot.pose(None)

    worker_ms = []
    with RenderWorker() as worker:
        poses = scene.part_poses()
        for k in range(args.worker_frames):
            start = time.perf_counter()
            worker.render(float(k), poses)
            worker_ms.append(1000 * (time.perf_counter() - start))

    classes = {}
    for name, stats in per_class.items():
        classes[name] = {
            "placed": stats["placed"],
            "detected": stats["detected"],
            "accuracy": round(stats["correct"] / stats["placed"], 4) if stats["placed"] else None,
            "pose_error_mm_p50": pct(stats["errors_mm"], 50),
            "pose_error_mm_p95": pct(stats["errors_mm"], 95),
        }
    placed = sum(s["placed"] for s in per_class.values())
    seen = max(len(real["errors"]), 1)
    realistic_results = {
        "exposure_time_s": args.exposure_time,
        "render_ms_p50": pct(real["render_ms"], 50),
        "render_ms_p99": pct(real["render_ms"], 99),
        "render_ms_ratio_p50": round(pct(real["render_ms"], 50) / pct(render_ms, 50), 3),
        "detector_ms_p50": pct(real["detect_ms"], 50),
        "detector_ms_p99": pct(real["detect_ms"], 99),
        "images_with_arm_in_view": real["arm_in_view"],
        "parts_visible": real["visible"],
        "parts_under_the_arm": real["hidden"],
        "detection_rate_visible": round(real["detected"] / max(real["visible"], 1), 4),
        "classification_accuracy_seen": round(real["correct"] / seen, 4),
        "detections_of_no_part": real["not_a_part"],
        "detections_of_parts_under_the_arm": real["hidden_seen"],
        "pose_error_mm_p50": pct(real["errors"], 50),
        "pose_error_mm_p95": pct(real["errors"], 95),
        "pose_error_mm_p99": pct(real["errors"], 99),
        "pose_error_mm_max": pct(real["errors"], 100),
        "rejections": real["rejections"],
    }
    results = {
        "images": args.images,
        "parts_per_image": args.parts_per_image,
        "seed": args.seed,
        "image_size": [true_camera.width, true_camera.height],
        "render_ms_p50": pct(render_ms, 50),
        "render_ms_p99": pct(render_ms, 99),
        "render_worker_roundtrip_ms_p50": pct(worker_ms, 50),
        "render_worker_roundtrip_ms_p99": pct(worker_ms, 99),
        "detector_ms_p50": pct(detect_ms, 50),
        "detector_ms_p99": pct(detect_ms, 99),
        "classification_accuracy": round(sum(s["correct"] for s in per_class.values()) / placed, 4),
        "detection_rate": round(sum(s["detected"] for s in per_class.values()) / placed, 4),
        "pose_error_mm_p50": pct(errors, 50),
        "pose_error_mm_p95": pct(errors, 95),
        "pose_error_mm_p99": pct(errors, 99),
        "pose_error_mm_max": pct(errors, 100),
        "pose_error_true_camera_mm_p50": pct(errors_true, 50),
        "pose_error_true_camera_mm_p95": pct(errors_true, 95),
        "marker_extrinsics": {
            "markers": calibration.used,
            "position_error_mm": round(1000 * position_error, 3),
            "rotation_error_deg": round(angle_error, 4),
            "reprojection_px": round(calibration.reprojection_px, 4),
        },
        "charuco_intrinsics": intrinsics,
        "rejections": rejections,
        "per_class": classes,
        "confusion": confusion,
        "confusions": sum(n for name, row in confusion.items() for other, n in row.items() if other != name),
        "misses": misses,
        "realistic": realistic_results,
    }
    write_results(
        "kitting_vision_bench" if args.seed == 1 else f"kitting_vision_bench_seed{args.seed}", results, show=False
    )
    print(f"\nseed {args.seed}: {args.images} images x {args.parts_per_image} parts, {placed} placed")
    print(
        f"render 640x480 p50/p99 {results['render_ms_p50']}/{results['render_ms_p99']} ms, through the render "
        f"process {results['render_worker_roundtrip_ms_p50']}/{results['render_worker_roundtrip_ms_p99']} ms; "
        f"detector p50/p99 {results['detector_ms_p50']}/{results['detector_ms_p99']} ms"
    )
    print(
        f"classification accuracy {100 * results['classification_accuracy']:.2f} % "
        f"(detected {100 * results['detection_rate']:.2f} %, confusions {results['confusions']}); "
        f"rejections {rejections}"
    )
    print(
        f"pose error p50/p95/p99/max {results['pose_error_mm_p50']}/{results['pose_error_mm_p95']}/"
        f"{results['pose_error_mm_p99']}/{results['pose_error_mm_max']} mm (true camera p50/p95 "
        f"{results['pose_error_true_camera_mm_p50']}/{results['pose_error_true_camera_mm_p95']} mm)"
    )
    print(
        f"ChArUco focal error {intrinsics['focal_error_pct']} %, reprojection {intrinsics['reprojection_rms_px']} px; "
        f"marker extrinsics {results['marker_extrinsics']['position_error_mm']} mm / "
        f"{results['marker_extrinsics']['rotation_error_deg']} deg"
    )
    r = realistic_results
    print(
        f"realistic (arm, blur {1000 * args.exposure_time:g} ms exposure, exposure drift): render p50 "
        f"{r['render_ms_p50']} ms (x{r['render_ms_ratio_p50']}), detector p50 {r['detector_ms_p50']} ms; "
        f"arm in view in {r['images_with_arm_in_view']} images; visible parts detected "
        f"{100 * r['detection_rate_visible']:.2f} % of {r['parts_visible']} ({r['parts_under_the_arm']} under the "
        f"arm); accuracy {100 * r['classification_accuracy_seen']:.2f} %; detections of no part "
        f"{r['detections_of_no_part']}; pose error p50/p95/p99/max {r['pose_error_mm_p50']}/"
        f"{r['pose_error_mm_p95']}/{r['pose_error_mm_p99']}/{r['pose_error_mm_max']} mm; rejections {r['rejections']}"
    )
    for miss in misses:
        print(
            f"  missed: image {miss['image']} {miss['class']} at ({miss['x']}, {miss['y']}) yaw {miss['yaw_deg']}°: "
            f"{miss['seen_as'] or miss['reason']} {miss['detail']} (nearest detection: {miss['nearest_detection']})"
        )
    print(f"\n{'class':15s} {'placed':>6s} {'det':>5s} {'acc':>6s} {'p50 mm':>7s} {'p95 mm':>7s}")
    for name, row in classes.items():
        print(
            f"{name:15s} {row['placed']:6d} {row['detected']:5d} {row['accuracy']!s:>6s} "
            f"{row['pose_error_mm_p50']!s:>7s} {row['pose_error_mm_p95']!s:>7s}"
        )


if __name__ == "__main__":
    main()
