"""The operator's dashboard: a web page for operation and settings (the paper's /dashboard_gui).

Plain-Python state and rules here (no rospy, no NiceGUI) are unit-tested; ``page.py`` is
the NiceGUI page and ``dashboard_node.py`` the ROS edge that feeds both.
"""
