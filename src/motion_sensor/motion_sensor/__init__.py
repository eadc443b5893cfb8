"""Motion-sensing layer: device parsing, filtering and sequencing of hand frames.

Everything in this package except the ``nodes/`` wrappers is plain Python with no rospy
import, so it can be unit-tested without a roscore.
"""
