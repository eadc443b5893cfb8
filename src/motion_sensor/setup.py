"""Python package of the motion_sensor catkin package (installed by catkin_python_setup)."""

from catkin_pkg.python_setup import generate_distutils_setup
from setuptools import setup

setup(
    **generate_distutils_setup(
        packages=[
            "motion_sensor",
            "motion_sensor.devices",
            "motion_sensor.sequencing",
            "motion_sensor.gestures",
            "motion_sensor.registration",
            "motion_sensor.testing",
        ],
        package_dir={"": "."},
    )
)
