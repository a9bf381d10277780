# Used by catkin_python_setup(); do not run directly.
from catkin_pkg.python_setup import generate_distutils_setup
from setuptools import setup

setup(**generate_distutils_setup(
    packages=['leap_teleop', 'leap_teleop.sources', 'leap_teleop.nodes',
              'leap_teleop.tools', 'leap_teleop.ur10', 'leap_teleop.drone',
              'leap_teleop.bench', 'leap_teleop.teleop'],
    package_dir={'': 'src'},
))
