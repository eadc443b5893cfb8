"""Application layer: gesture-taught programs.

``program`` (the program file, atomic save), ``teach`` (teach-mode state machine fed with
gesture events and tool poses), ``program_check`` (reachability, workspace fence and
collision check before the arm moves), ``program_runner`` (replays a program through the
manipulation API / MotionControllerClient). Plain Python: no rospy outside ``nodes/``.
"""
