"""Where the package's own files are (config/, scripts/): the source tree this module lives
in, else the installed package that rospkg finds (an install space keeps the Python apart
from config/ and scripts/)."""
import os

_SOURCE_ROOT = os.path.normpath(os.path.join(os.path.dirname(os.path.abspath(__file__)), '..', '..'))


def package_path(*parts):
    """A path inside the package: package_path('config', 'ur10_cell.yaml')."""
    if os.path.isfile(os.path.join(_SOURCE_ROOT, 'package.xml')):
        return os.path.join(_SOURCE_ROOT, *parts)
    import rospkg  # only outside a source tree; rospkg needs no master
    return os.path.join(rospkg.RosPack().get_path('leap_teleop'), *parts)
