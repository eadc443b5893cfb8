"""Unit tests of the motion_sensor package (see ../__init__.py for the layout)."""
