"""Foundation layer of the framework, below sensing, hardware interface and core.

It holds what more than one layer needs and none of them owns: the robot model (URDF
loading, forward/inverse kinematics, joint limits, the shipped URDFs and start poses) and
the one parameter validator every node uses. It imports none of the framework's packages,
so every other package may import it without breaking the one-way layering.
"""
