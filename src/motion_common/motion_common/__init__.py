"""Foundation layer of the framework, below sensing, hardware interface and core.

It holds what more than one layer needs and none of them owns, and imports none of the
framework's packages, so every other package may import it without breaking the one-way
layering. Its modules, by role:

- ``lazy_exports``: the public names of every package of the framework, imported from
  their module on first use (PEP 562);
- node interfaces: ``interface`` (``NodeInterface``: the one declaration of a node's
  parameters, topics and services, relative names) and ``ros_interface`` (publishers,
  subscribers and services made from it: a ROS edge);
- robot model: ``kinematics`` (URDF loading with pinocchio, forward/inverse kinematics,
  Jacobians, joint limits; the shipped URDFs are in ``urdf/``, start poses in
  ``config/robots/``);
- parameters: ``params`` (``ParamSchema``, the one validator every node's parameters go
  through) and ``ros_params`` (reads a node's private parameters from the parameter
  server through a schema; like ``ros_interface``, a ROS edge that imports rospy);
- geometry: ``rotations`` (quaternions x, y, z, w and rotation matrices in plain numpy: the
  unit-quaternion check, matrix to quaternion, the Hamilton product);
- cameras: ``camera_model`` (the pinhole model: ``Intrinsics``, ``PinholeCamera``, and
  CameraInfo to intrinsics with its checks), ``video_capture`` (frames from OpenCV: a camera,
  a video file or an image folder, paced and stamped, with one set of counters);
- per-frame and file helpers: ``float_list`` (small vectors as plain floats on the
  latency path), ``startup_heap`` (keeps a node's start-up heap out of the garbage
  collector's scans), ``atomic_file`` (a saved file is either the old one or the new one);
- sessions: ``launch_args`` (the arguments a launch file declares, and ``name:=value``
  command lines checked against them with "did you mean"), ``tools_check`` (the install
  command of a program a launch argument needs), ``ros_log_link`` (a race-free ``latest``
  link in the ROS log folder; installed by ``ros_interface``), ``native_output`` (what native
  libraries print to the file descriptors, silenced around known-noisy start-up calls),
  ``quiet_pybullet`` (pybullet imported and connected without its console chatter), ``session_end`` (a finishing node
  stops the hand-started roslaunch that runs it, without the REQUIRED banner);
- recording: ``frame_tap`` (a fast stamped stream thinned to what a dataset recorder's
  frame instants need, published by the stream's own node: the messages around each
  instant, or one value at it), ``frame_blend`` (a stream's value at an instant between
  two stamped samples), ``frame_sample`` (that value as the one message a frame the server
  and the core send);
- ``errors``: ``RobotModelError``, ``ParameterError``.

The names in ``__all__`` are imported from their module on first use, so ``import
motion_common`` loads neither pinocchio nor rospy. ``float_list`` is not among them: the
function shares its module's name, so use ``motion_common.float_list.float_list``.
"""

from .lazy_exports import lazy_exports

# Public name -> the submodule that defines it.
_PUBLIC = {
    "RobotKinematics": "kinematics",
    "IkResult": "kinematics",
    "LinePath": "kinematics",
    "pose_to_se3": "kinematics",
    "se3_to_pose": "kinematics",
    "quat_to_matrix": "kinematics",
    "matrix_to_quat": "kinematics",
    "slerp": "kinematics",
    "singular_values": "kinematics",
    "solve_positive_definite": "kinematics",
    "UNIT_QUATERNION_TOLERANCE": "rotations",
    "is_unit_quaternion": "rotations",
    "quaternion_norm": "rotations",
    "matrix_to_quaternion": "rotations",
    "multiply_quaternions": "rotations",
    "with_positive_w": "rotations",
    "FrameTap": "frame_tap",
    "FrameSampler": "frame_sample",
    "Intrinsics": "camera_model",
    "PinholeCamera": "camera_model",
    "CameraInfoError": "camera_model",
    "intrinsics_from_camera_info": "camera_model",
    "camera_info_fields": "camera_model",
    "Frame": "video_capture",
    "FrameSource": "video_capture",
    "FrameSourceError": "video_capture",
    "DeviceSource": "video_capture",
    "VideoSource": "video_capture",
    "ImageFolderSource": "video_capture",
    "open_source": "video_capture",
    "Param": "params",
    "ParamSchema": "params",
    "read_yaml_file": "params",
    "check_ordered": "params",
    "load_private_params": "ros_params",
    "parameter_source": "ros_params",
    "LAUNCH_KEYS": "ros_params",
    "freeze_startup_heap": "startup_heap",
    "write_atomic": "atomic_file",
    "LaunchArg": "launch_args",
    "declared_args": "launch_args",
    "parse_assignments": "launch_args",
    "unknown_args": "launch_args",
    "RobotModelError": "errors",
    "ParameterError": "errors",
}
__all__ = list(_PUBLIC)

__getattr__, __dir__ = lazy_exports(__name__, _PUBLIC, globals())
