"""Motion-sensing layer: hand devices, their parsing, and the filtering, sequencing,
registration and gesture recognition of hand frames.

Its modules, by role:

- ``interfaces``: the one declaration of each of this package's nodes (parameters, topics,
  services; see ``motion_common.interface``), from which docs/interfaces.md is generated;
- ``device_interface``: what every device node shares (wrapper parameters and topics)
  merged with a device class's own parameters into that node's declaration;
- the hand frame: ``hand_sample`` (``HandSample``, the ROS-free form of a
  ``motion_sensor/hand`` message), ``errors``;
- devices (plain Python: each is a ``HandDevice`` a node wrapper runs): ``device`` (the
  base class, reconnect and streaming logic), ``leap_v6`` (Leap protocol v6 parsing and
  recordings), ``leap_client`` (its WebSocket client and device), ``leap_server`` (a Leap
  service replaying a recording), ``spacemouse`` (HID report decoding, rate-to-pose
  integration), ``replay`` (recorded streams as a device), ``camera_intrinsics``,
  ``depth_image``, ``depth_hand`` and ``depth_device`` (hand tracking in depth images and
  the depth-topic device), ``kinect`` and ``fakenect`` (Kinect v1 through libfreenect, and
  its dump player), ``hand_landmarks``, ``mediapipe_hands``, ``webcam_hand`` and
  ``webcam_device`` (webcam hand tracking with MediaPipe Hands), ``synthetic_depth``
  (ray-cast depth images of a hand for tests and benchmarks);
- the stream: ``filters`` (pose filters), ``sequencer`` (irregular device frames in, a
  clean pose stream out), ``registration`` (hand space to robot space by DTW);
- gestures: ``gesture_frame``, ``static_poses``, ``gesture_features``,
  ``dtw_classifier``, ``gesture_spotter``, ``gesture_templates``, ``gesture_recognizer``;
- ROS edges, the only modules that need ROS: ``device_node`` (the one node wrapper of
  every device; rospy), ``depth_node`` (its depth-camera variant; rospy) and
  ``ros_conversions`` (``hand`` message <-> ``HandSample``; the generated messages).

The names in ``__all__`` are imported from their module on first use, so ``import
motion_sensor`` loads none of cv2, mediapipe, scipy or rospy.
"""

from importlib import import_module as _import_module

# Public name -> the submodule that defines it.
_PUBLIC = {
    "HandSample": "hand_sample",
    "MotionSensorError": "errors",
    "DeviceUnavailable": "errors",
    "EndOfStream": "errors",
    # devices
    "HandDevice": "device",
    "DeviceRunner": "device",
    "Backoff": "device",
    "reconnect_loop": "device",
    "wait_until_ready": "device",
    "LeapFrame": "leap_v6",
    "LeapHand": "leap_v6",
    "LeapRecording": "leap_v6",
    "parse_message": "leap_v6",
    "select_primary": "leap_v6",
    "frame_to_sample": "leap_v6",
    "read_recording": "leap_v6",
    "LeapClient": "leap_client",
    "LeapDevice": "leap_client",
    "LeapReplayServer": "leap_server",
    "Faults": "leap_server",
    "SpaceMouseDevice": "spacemouse",
    "SpaceMouseDecoder": "spacemouse",
    "SpaceMouseReader": "spacemouse",
    "RateIntegrator": "spacemouse",
    "read_report_log": "spacemouse",
    "ReplayDevice": "replay",
    "read_csv": "replay",
    "load_samples": "replay",
    "Intrinsics": "camera_intrinsics",
    "DepthImageError": "depth_image",
    "decode_depth": "depth_image",
    "encode_depth_mm": "depth_image",
    "DepthHand": "depth_hand",
    "DepthHandTracker": "depth_hand",
    "DepthHandDevice": "depth_device",
    "DepthTopicDevice": "depth_device",
    "KinectDevice": "kinect",
    "FakenectKinectDevice": "kinect",
    "write_dump": "fakenect",
    "DetectedHand": "hand_landmarks",
    "PalmPose": "hand_landmarks",
    "palm_pose": "hand_landmarks",
    "calibrate_depth_scale": "hand_landmarks",
    "HandDetector": "mediapipe_hands",
    "MediaPipeHandDetector": "mediapipe_hands",
    "WebcamHandTracker": "webcam_hand",
    "WebcamHandDevice": "webcam_device",
    "HandPose": "synthetic_depth",
    "render_hand": "synthetic_depth",
    "hand_path": "synthetic_depth",
    # the stream
    "FILTERS": "filters",
    "make_filter": "filters",
    "MeanFilter": "filters",
    "OneEuroFilter": "filters",
    "KalmanFilter": "filters",
    "Sequencer": "sequencer",
    "SequencerConfig": "sequencer",
    "SequencedPose": "sequencer",
    "sequencer_setup": "sequencer",
    "Registration": "registration",
    "register": "registration",
    # gestures
    "GestureFrame": "gesture_frame",
    "GestureEvent": "gesture_frame",
    "frames_from_recording": "gesture_frame",
    "StaticPoseDetector": "static_poses",
    "FeatureConfig": "gesture_features",
    "DTWClassifier": "dtw_classifier",
    "GestureSpotter": "gesture_spotter",
    "save_template": "gesture_templates",
    "load_templates": "gesture_templates",
    "load_dataset": "gesture_templates",
    "GestureRecognizer": "gesture_recognizer",
    "load_classifier": "gesture_recognizer",
    # ROS edges
    "DeviceNode": "device_node",
    "run_device_node": "device_node",
    "run_depth_node": "depth_node",
    "run_kinect_node": "depth_node",
    "sample_to_msg": "ros_conversions",
    "msg_to_sample": "ros_conversions",
}
__all__ = list(_PUBLIC)


def __getattr__(name):
    """Imports the submodule that defines ``name`` on first use (PEP 562)."""
    module = _PUBLIC.get(name)
    if module is None:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    value = getattr(_import_module(f"{__name__}.{module}"), name)
    globals()[name] = value  # the next look-up finds it without this function
    return value


def __dir__():
    return sorted(set(globals()) | set(__all__))
