"""Unit tests of the kitting package (see ../__init__.py for the layout)."""
