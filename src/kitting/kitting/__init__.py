"""Application layer: the vision-fed kitting cell (its README has a line per module).

Its modules, by role:

- ``interfaces``: the one declaration of each of this package's nodes (parameters, topics,
  services; see ``motion_common.interface``), from which docs/interfaces.md is generated;
- the cell as data: ``parts`` (the six part classes), ``cell`` (robot, belt, tray,
  markers and camera from ``config/cell.yaml``), ``meshes`` (the parts' render meshes);
- simulation: ``sim_scene`` (the cell in pybullet), ``cell_sim`` (its physics around the
  simulated arm), ``camera`` (pybullet rendering of the pinhole camera of
  ``motion_common.camera_model``), ``render_worker`` (rendering in a process of its own,
  with the arm drawn), ``camera_effects`` (a real camera's motion blur and exposure);
- camera input: ``frame_source`` (webcam, video file, image folder: the frame sources of
  ``motion_common.video_capture``, a lost camera reopened with backoff), ``image_msgs``
  (``sensor_msgs`` image and camera info conversions without cv_bridge),
  ``intrinsics_file``, ``calibration`` (ChArUco intrinsics, marker extrinsics),
  ``calibration_views`` (choosing calibration views from a stream), ``belt_edge`` (the
  belt's far edge joining the marker corners in the camera registration);
- vision: ``detector`` (the detectors' base and the classical OpenCV detector), ``onnx_detector`` (a YOLOv8 ONNX
  model through onnxruntime), ``geometry`` (pixel to belt plane), ``vision`` (detections
  to belt-plane poses), ``robot_silhouette`` (where the arm and gripper are in the image,
  from the joints), ``vision_pipeline`` (one image in, the parts on the belt out),
  ``annotated_image`` (the image with its detections drawn, for the operator's dashboard);
- picking: ``tracking`` (a Kalman filter per part), ``intercept`` (where and when to meet
  a part on the moving belt), ``picker`` (the kitting cycle), ``slot_program`` (tray slot
  poses from a program taught by gesture), ``kits`` (kits of one part per slot, kit order
  files, ARIAC's kitting score), ``campaign`` (trials and their statistics), ``cycle_phases``
  (where a pick's cycle goes).

No module here imports rospy (``image_msgs`` uses the generated ``sensor_msgs`` classes
only); the nodes are the ROS edges. The names in ``__all__`` are imported from their
module on first use, so ``import kitting`` loads none of pybullet, cv2 or onnxruntime.
"""

from motion_common.lazy_exports import lazy_exports

# Public name -> the submodule that defines it.
_PUBLIC = {
    "PartClass": "parts",
    "PART_CLASSES": "parts",
    "CLASS_NAMES": "parts",
    "part_class": "parts",
    "Cell": "cell",
    "load_cell": "cell",
    "cell_from_dict": "cell",
    "DEFAULT_CELL": "cell",
    "part_mesh": "meshes",
    "SimScene": "sim_scene",
    "render_board_views": "sim_scene",
    "CellSimulation": "cell_sim",
    "Lighting": "camera",
    "render": "camera",
    "RenderWorker": "render_worker",
    "Exposure": "camera_effects",
    "ExposureDrift": "camera_effects",
    "RobotSilhouette": "robot_silhouette",
    "FrameSource": "frame_source",
    "FrameSourceError": "frame_source",
    "open_source": "frame_source",
    "DeviceSource": "frame_source",
    "VideoSource": "frame_source",
    "ImageFolderSource": "frame_source",
    "image_to_bgr": "image_msgs",
    "bgr_to_image": "image_msgs",
    "camera_info_from_intrinsics": "image_msgs",
    "intrinsics_from_camera_info": "image_msgs",
    "IntrinsicsFileError": "intrinsics_file",
    "load_camera_info_yaml": "intrinsics_file",
    "resolve_camera_info_url": "intrinsics_file",
    "BoardSpec": "calibration",
    "CalibrationResult": "calibration",
    "Extrinsics": "calibration",
    "calibrate_intrinsics": "calibration",
    "write_intrinsics_yaml": "calibration",
    "extrinsics_from_marker": "calibration",
    "BeltLine": "belt_edge",
    "far_edge": "belt_edge",
    "measure_line": "belt_edge",
    "refine_with_lines": "belt_edge",
    "ViewCollector": "calibration_views",
    "PartDetector": "detector",
    "ClassicalDetector": "detector",
    "Detection": "detector",
    "DetectionResult": "detector",
    "OnnxDetector": "onnx_detector",
    "OnnxModelError": "onnx_detector",
    "pixel_to_belt": "geometry",
    "pixels_to_plane": "geometry",
    "BeltVision": "vision",
    "PartObservation": "vision",
    "VisionPipeline": "vision_pipeline",
    "VisionResult": "vision_pipeline",
    "BeltTracker": "tracking",
    "Observation": "tracking",
    "Track": "tracking",
    "plan_intercept": "intercept",
    "Intercept": "intercept",
    "KittingPicker": "picker",
    "PickAborted": "picker",
    "PickMissed": "picker",
    "KittingEvent": "picker",
    "slots_from_program": "slot_program",
    "TaughtSlots": "slot_program",
    "SlotProgramError": "slot_program",
    "plan_trials": "campaign",
    "Trial": "campaign",
    "CampaignStats": "campaign",
    "PHASES": "cycle_phases",
    "phase_summary": "cycle_phases",
    "Kit": "kits",
    "KitScore": "kits",
    "KitOrderError": "kits",
    "load_kit_order": "kits",
    "score_kit": "kits",
}
__all__ = list(_PUBLIC)

__getattr__, __dir__ = lazy_exports(__name__, _PUBLIC, globals())
