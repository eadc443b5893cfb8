"""Unit tests of the motion_commander package (see ../__init__.py for the layout)."""
