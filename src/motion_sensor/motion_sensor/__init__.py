"""Motion-sensing layer: hand devices, their parsing, and the filtering, sequencing,
registration and gesture recognition of hand frames.

Its subpackages and modules, by role:

- ``devices``: the hand devices, each a plain-Python ``HandDevice`` that one node wrapper
  runs (``device``, ``device_interface``, ``device_node`` and ``depth_node``, the ROS
  edges; Leap v6, SpaceMouse, replay, depth camera and Kinect, webcam with MediaPipe);
- ``sequencing``: ``filters`` (pose filters) and ``sequencer`` (irregular device frames
  in, a clean pose stream out);
- ``gestures``: static poses, dynamic (DTW) gestures, the recognizer the node runs, and
  the hand-skeleton gesture network;
- ``skeleton_joints``: the one canonical 22-joint hand skeleton and the mapping of Leap
  bones, MediaPipe landmarks and SHREC'17 joints onto it; ``skeleton_sample``
  (``SkeletonSample``, the ROS-free form of a ``motion_sensor/HandSkeleton`` message);
- ``registration``: hand space to robot space by DTW-aligned paths;
- ``testing``: test doubles (``synthetic_depth``: ray-cast depth images of a hand), for
  tests and benchmarks only;
- ``interfaces``: the one declaration of each of this package's nodes (parameters, topics,
  services; see ``motion_common.interface``), from which docs/interfaces.md is generated;
- the hand frame: ``hand_sample`` (``HandSample``, the ROS-free form of a
  ``motion_sensor/hand`` message), ``errors``; ``ros_conversions`` (``hand`` message <->
  ``HandSample``; needs the generated messages);
- ``onnx_session``: the onnxruntime session of a shipped network (gestures, depth palm).

The names in ``__all__`` are imported from their module on first use, so ``import
motion_sensor`` loads none of cv2, mediapipe, scipy or rospy.
"""

from motion_common.lazy_exports import lazy_exports

# Public name -> the submodule that defines it.
_PUBLIC = {
    "HandSample": "hand_sample",
    "MotionSensorError": "errors",
    "DeviceUnavailable": "errors",
    "EndOfStream": "errors",
    # devices
    "HandDevice": "devices.device",
    "DeviceRunner": "devices.device",
    "Backoff": "devices.device",
    "reconnect_loop": "devices.device",
    "wait_until_ready": "devices.device",
    "LeapFrame": "devices.leap_v6",
    "LeapHand": "devices.leap_v6",
    "LeapRecording": "devices.leap_v6",
    "parse_message": "devices.leap_v6",
    "select_primary": "devices.leap_v6",
    "frame_to_sample": "devices.leap_v6",
    "read_recording": "devices.leap_v6",
    "LeapClient": "devices.leap_client",
    "LeapDevice": "devices.leap_client",
    "LeapReplayServer": "devices.leap_server",
    "Faults": "devices.leap_server",
    "SpaceMouseDevice": "devices.spacemouse",
    "SpaceMouseDecoder": "devices.spacemouse",
    "SpaceMouseReader": "devices.spacemouse",
    "RateIntegrator": "devices.spacemouse",
    "read_report_log": "devices.spacemouse",
    "ReplayDevice": "devices.replay",
    "read_csv": "devices.hand_csv",
    "write_csv": "devices.hand_csv",
    "read_bag": "devices.hand_bag",
    "load_samples": "devices.replay",
    "Intrinsics": "devices.camera_intrinsics",
    "DepthImageError": "devices.depth_image",
    "decode_depth": "devices.depth_image",
    "encode_depth_mm": "devices.depth_image",
    "DepthHand": "devices.depth_hand",
    "DepthHandTracker": "devices.depth_hand",
    "DepthHandDevice": "devices.depth_device",
    "DepthTopicDevice": "devices.depth_device",
    "KinectDevice": "devices.kinect",
    "FakenectKinectDevice": "devices.kinect",
    "write_dump": "devices.fakenect",
    "DetectedHand": "devices.hand_landmarks",
    "PalmPose": "devices.hand_landmarks",
    "palm_pose": "devices.hand_landmarks",
    "calibrate_depth_scale": "devices.hand_landmarks",
    "HandDetector": "devices.mediapipe_hands",
    "MediaPipeHandDetector": "devices.mediapipe_hands",
    "WebcamHandTracker": "devices.webcam_hand",
    "WebcamHandDevice": "devices.webcam_device",
    "HandPose": "testing.synthetic_depth",
    "render_hand": "testing.synthetic_depth",
    "hand_path": "testing.synthetic_depth",
    # the stream
    "FILTERS": "sequencing.filters",
    "make_filter": "sequencing.filters",
    "MeanFilter": "sequencing.filters",
    "OneEuroFilter": "sequencing.filters",
    "KalmanFilter": "sequencing.filters",
    "Sequencer": "sequencing.sequencer",
    "SequencerConfig": "sequencing.sequencer",
    "SequencedPose": "sequencing.sequencer",
    "sequencer_setup": "sequencing.sequencer",
    "Registration": "registration.device_registration",
    "register": "registration.device_registration",
    # gestures
    "GestureFrame": "gestures.gesture_frame",
    "GestureEvent": "gestures.gesture_frame",
    "frames_from_recording": "gestures.gesture_frame",
    "StaticPoseDetector": "gestures.static_poses",
    "FeatureConfig": "gestures.gesture_features",
    "DTWClassifier": "gestures.dtw_classifier",
    "GestureSpotter": "gestures.gesture_spotter",
    "save_template": "gestures.gesture_templates",
    "load_templates": "gestures.gesture_templates",
    "load_dataset": "gestures.gesture_templates",
    "GestureRecognizer": "gestures.gesture_recognizer",
    "load_classifier": "gestures.gesture_recognizer",
    "JOINT_NAMES": "skeleton_joints",
    "SkeletonClassifier": "gestures.skeleton_classifier",
    # ROS edges
    "DeviceNode": "devices.device_node",
    "run_device_node": "devices.device_node",
    "run_depth_node": "devices.depth_node",
    "run_kinect_node": "devices.depth_node",
    "sample_to_msg": "ros_conversions",
    "msg_to_sample": "ros_conversions",
}
__all__ = list(_PUBLIC)

__getattr__, __dir__ = lazy_exports(__name__, _PUBLIC, globals())
