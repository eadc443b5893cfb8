"""Vision-fed kitting cell: plain-Python foundations (no rospy). See the package README."""
