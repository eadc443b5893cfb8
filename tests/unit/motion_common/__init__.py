"""Unit tests of the motion_common package (see ../__init__.py for the layout)."""
