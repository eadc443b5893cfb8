"""Unit tests of the motion_apps package (see ../__init__.py for the layout)."""
