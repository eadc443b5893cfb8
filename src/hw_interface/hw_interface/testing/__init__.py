"""Test doubles shipped with hw_interface for dry runs without hardware (``fake_rtde``)."""
