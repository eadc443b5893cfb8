"""The hand devices: each is a plain-Python ``HandDevice`` (``device``) that one node wrapper
(``device_node``; ``depth_node`` for the camera devices) runs, declared by
``device_interface``.

Its modules:

- ``device``: the base class, reconnect with backoff, the streaming loop;
- ``device_interface``: what every device node declares (wrapper parameters and topics);
- ``device_node``: the ROS node wrapper of every device (a ROS edge);
- ``device_loader``: a device class of one's own named ``module:Class`` (``device:=module:Class``);
- ``depth_node``: the ROS edge of the depth-camera devices (image subscribers, the Kinect choice);
- ``leap_v6``: Leap protocol v6 parsing and recordings;
- ``leap_client``: the Leap WebSocket client and device;
- ``leap_server``: a Leap service replaying a recording (for tests and demos);
- ``spacemouse``: SpaceMouse HID report decoding and rate-to-pose integration;
- ``replay``: recorded streams (Leap v6, rosbag, CSV) as a device;
- ``hand_csv``: the CSV layout of hand streams and their skeletons (read and write);
- ``hand_bag``: a session's rosbag (record_hands) read back with its skeletons;
- ``camera_intrinsics``: the pinhole camera model's re-export for the camera devices;
- ``depth_image``: depth image decoding (16UC1 mm, 32FC1 m, Kinect 11-bit);
- ``depth_hand``: hand tracking in depth images;
- ``depth_palm_model``: the learned correction of the depth tracker's palm centre (ONNX);
- ``depth_device``: depth images from a topic as a device;
- ``kinect``: a Kinect v1 through libfreenect (or a fakenect dump) as a device;
- ``fakenect``: fakenect dumps: writing them, and the stub Debian lacks;
- ``hand_landmarks``: palm pose, depth and strengths from 21 hand landmarks (no MediaPipe);
- ``mediapipe_hands``: MediaPipe Hands as a landmark detector;
- ``webcam_hand``: hand tracking in webcam images;
- ``webcam_device``: a webcam or video file as a device;
- ``shrec_stream``: a SHREC'17 skeleton file (.npz) played as a live hand with idle gaps.
"""

from motion_common.lazy_exports import lazy_exports

# Public name -> the module of this subpackage that defines it.
_PUBLIC = {
    "HandDevice": "device",
    "device_class": "device_loader",
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
    "read_csv": "hand_csv",
    "write_csv": "hand_csv",
    "read_bag": "hand_bag",
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
    "DeviceNode": "device_node",
    "run_device_node": "device_node",
    "run_depth_node": "depth_node",
    "run_kinect_node": "depth_node",
}
__all__ = list(_PUBLIC)

__getattr__, __dir__ = lazy_exports(__name__, _PUBLIC, globals())
