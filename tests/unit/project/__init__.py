"""Unit tests that span the packages: layering, launch files and their docs, public surfaces
(see ../__init__.py for the layout)."""
