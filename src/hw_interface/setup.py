"""Python package of the hw_interface catkin package (installed by catkin_python_setup)."""

from catkin_pkg.python_setup import generate_distutils_setup
from setuptools import setup

setup(**generate_distutils_setup(packages=["hw_interface", "hw_interface.testing"], package_dir={"": "."}))
