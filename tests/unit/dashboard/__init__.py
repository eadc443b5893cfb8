"""Unit tests of the dashboard package (see ../__init__.py for the layout)."""
