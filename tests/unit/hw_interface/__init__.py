"""Unit tests of the hw_interface package (see ../__init__.py for the layout)."""
