"""Hardware interface layer: the robot driver template, the driver registry, the drivers,
and the command dispatcher behind motion_controller_server.

Its modules, by role:

- ``interfaces``: the one declaration of each of this package's nodes (parameters, topics,
  services; see ``motion_common.interface``), from which docs/interfaces.md is generated;
- the driver contract: ``robot_hw`` (``RobotDriver``, the template every driver
  implements: the paper's API plus what real controllers need), ``registry`` (drivers by
  name: the built-ins and any package's ``hw_interface.drivers`` entry point);
- drivers: ``sim_driver`` (pybullet simulation; ``scene_camera`` renders its cell in a
  process of its own), ``ur_driver`` (Universal Robots over
  ur_rtde), ``industrial_driver`` (ROS-Industrial controllers over ``simple_message``, the
  wire format, ``tcp``, how its sockets close, and ``arrival_stamps``, when the controller
  sampled the states it sends without a time), with ``trajectory`` (MoveJ/MoveL time
  parameterisation), ``stream_follower`` (streamed joint targets within the velocity
  limits), ``timed_targets`` (the simulation's streamed targets applied at the step
  scheduled after their arrival, however late the physics thread runs it) and
  ``timed_path`` (FOLLOW_PATH's timed joint path, checked whole and sampled by the
  driver's clock); the two
  drivers of real controllers share ``real_controller`` (arming, reconnect backoff, moves
  watched on the measured joints) and ``driver_params`` (the parameters they declare
  alike);
- the server's core: ``protocol`` (commander.srv's command and result tables as enums),
  ``dispatcher`` (checks every request, then calls the driver), ``server_params`` (the
  server's parameters and its drivers' parameter check), ``status_log`` (which driver
  status changes reach the console, and how loudly);
- ``controller_client``: ``MotionControllerClient``, the Python client of
  /motion_controller; a ROS edge (rospy and the generated ``motion_commander/commander``
  service);
- ``path_file``: a timed joint path read and checked from a CSV or ``.npy`` file, for
  ``motion_controller_client follow_path``;
- ``path_call``: ``PathCall``, a FOLLOW_PATH call on a thread of its own that a caller
  leaving early STOPs until it answers (the client's ``follow_path``, the episode replay);
- ``errors``: ``HwInterfaceError``;
- ``testing``: test doubles (the fake UR controller, the simulated simple_message
  controller), injected by registry name and
  never imported by production code.

The names in ``__all__`` are imported from their module on first use, so ``import
hw_interface`` loads neither pybullet nor rospy.
"""

from motion_common.lazy_exports import lazy_exports

# Public name -> the submodule that defines it.
_PUBLIC = {
    "RobotDriver": "robot_hw",
    "DriverStatus": "robot_hw",
    "UrdfModelMixin": "robot_hw",
    "SimulatedScene": "robot_hw",
    "register_driver": "registry",
    "available_drivers": "registry",
    "driver_factory": "registry",
    "driver_parameters": "registry",
    "create_driver": "registry",
    "ENTRY_POINT_GROUP": "registry",
    "PybulletSimDriver": "sim_driver",
    "load_scene": "sim_driver",
    "URRtdeDriver": "ur_driver",
    "SimpleMessageDriver": "industrial_driver",
    "JointPath": "trajectory",
    "StreamFollower": "stream_follower",
    "TimedPath": "timed_path",
    "CommandIndex": "protocol",
    "Result": "protocol",
    "CommandDispatcher": "dispatcher",
    "CommandResult": "dispatcher",
    "Workspace": "dispatcher",
    "stop_driver": "dispatcher",
    "SERVER_PARAMETERS": "server_params",
    "check_server_params": "server_params",
    "MotionControllerClient": "controller_client",
    "PathCall": "path_call",
    "HwInterfaceError": "errors",
}
__all__ = list(_PUBLIC)

__getattr__, __dir__ = lazy_exports(__name__, _PUBLIC, globals())
