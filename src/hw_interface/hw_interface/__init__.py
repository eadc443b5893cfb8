"""Hardware interface layer: the robot driver template, the driver registry, the drivers,
and the command dispatcher behind motion_controller_server. No rospy import outside nodes/."""
