"""Python package of the motion_common catkin package (installed by catkin_python_setup)."""

from catkin_pkg.python_setup import generate_distutils_setup
from setuptools import setup

setup(**generate_distutils_setup(packages=["motion_common"], package_dir={"": "."}))
