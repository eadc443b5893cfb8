"""Framework core: kinematics, teleop mapping, safety and the paper's manipulation API.

Everything here except the ``nodes/`` wrappers is plain Python with no rospy import.
"""
