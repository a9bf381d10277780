"""Where the package's own files are (config/, scripts/): the source tree this module lives
in, else the installed package that rospkg finds (an install space keeps the Python apart
from config/ and scripts/), and where a path the user gave relative points."""
import glob
import os

_SOURCE_ROOT = os.path.normpath(os.path.join(os.path.dirname(os.path.abspath(__file__)), '..', '..'))


def package_path(*parts):
    """A path inside the package: package_path('config', 'ur10_cell.yaml')."""
    if os.path.isfile(os.path.join(_SOURCE_ROOT, 'package.xml')):
        return os.path.join(_SOURCE_ROOT, *parts)
    import rospkg  # only outside a source tree; rospkg needs no master
    return os.path.join(rospkg.RosPack().get_path('leap_teleop'), *parts)


def user_path(path):
    """`path` as the user meant it: a relative one that names something (a glob: matches
    something) from the directory the command ran in is made absolute there; any other path
    is returned as it is. roslaunch starts nodes in ROS_HOME, but they inherit the shell's
    PWD."""
    if not path or os.path.isabs(path):
        return path
    pwd = os.environ.get('PWD', '')
    if not os.path.isabs(pwd):
        return path
    there = os.path.join(pwd, path)
    found = (glob.glob(os.path.join(glob.escape(pwd), path)) if glob.has_magic(path)
             else os.path.exists(there))
    return there if found else path
