"""Work-cell configuration (config/ur10_cell.yaml, config/ur10_dual_cell.yaml) as objects.

Everything a consumer needs to script the cell: where each arm's base is in the world,
its home joints, its tray, and where the cubes start. Poses for IK are in an arm's
base_link frame; ArmConfig.to_base / to_world convert 4x4 world <-> base poses.
"""
import difflib
import functools
import math
import os
import re
from dataclasses import dataclass, field

import numpy as np

from leap_teleop.package_files import package_path
from leap_teleop.params import Param, ParamError, check_params
from leap_teleop.ur10.kinematics import HOME_Q, JOINT_LOWER, JOINT_UPPER
from leap_teleop.vectors import rpy_matrix
from leap_teleop.yaml_file import load_yaml_file


def config_path(name):
    """A config path: absolute / existing paths as is, else a file name in config/."""
    if os.path.exists(name):
        return name
    cand = package_path('config', name)
    if not cand.endswith('.yaml'):
        cand += '.yaml'
    return cand


DEFAULT_CELL_CONFIG = 'ur10_cell.yaml'


class CellConfigError(ValueError):
    """A cell config that cannot be read or does not describe a cell, or an arm it lacks:
    one line naming the file."""


def read_cell_config(name):
    """load_config, each way a file can be bad (missing, not YAML, entries of the wrong
    shape) as one CellConfigError line instead of the error of whichever step tripped."""
    path = config_path(name)
    try:
        return load_config(name)
    except ValueError as e:
        why = str(e)
        if why.startswith('cell config'):
            raise CellConfigError(why) from None
    raise CellConfigError('cell config %s: %s' % (path, why)) from None


@dataclass
class TrayConfig:
    xyz: np.ndarray            # centre of the tray's underside, world
    inner: tuple = (0.2, 0.2)
    wall: tuple = (0.01, 0.04)  # thickness, height

    @property
    def floor_z(self):
        """z of the tray's inner floor (a cube rests on it at floor_z + size / 2)."""
        return float(self.xyz[2]) + float(self.wall[0])


@dataclass
class ArmConfig:
    name: str
    base_xyz: np.ndarray
    base_rpy: np.ndarray
    home: np.ndarray
    tray: TrayConfig

    @property
    def prefix(self):
        """Prefix of this arm's joint and link names (e.g. ur10_1_)."""
        return self.name + '_'

    @property
    def world_T_base(self):
        return _placement(self.base_xyz, self.base_rpy)

    def to_base(self, T_world):
        """A world 4x4 pose in this arm's base_link frame."""
        key = (np.asarray(self.base_xyz, dtype=float).tobytes(),
               np.asarray(self.base_rpy, dtype=float).tobytes())
        return _base_T_world(*key) @ np.asarray(T_world, dtype=float)

    def to_world(self, T_base):
        return self.world_T_base @ np.asarray(T_base, dtype=float)

    def point_to_base(self, xyz_world):
        Tb = self.world_T_base
        return Tb[:3, :3].T @ (np.asarray(xyz_world, dtype=float) - Tb[:3, 3])


def _placement(xyz, rpy):
    """world_T_base of an arm whose base is at xyz, turned by rpy."""
    T = np.eye(4)
    T[:3, :3] = np.reshape(rpy_matrix(*rpy), (3, 3))
    T[:3, 3] = xyz
    return T


@functools.lru_cache(maxsize=64)
def _base_T_world(xyz_bytes, rpy_bytes):
    """The inverse of an arm's placement, once per placement: np.linalg.inv leaves an
    OpenBLAS worker thread spinning ~0.1 s after each call (a core's worth of CPU when a
    control loop calls it every period)."""
    inverse = np.linalg.inv(_placement(np.frombuffer(xyz_bytes), np.frombuffer(rpy_bytes)))
    inverse.flags.writeable = False
    return inverse


@dataclass
class CubeConfig:
    name: str
    xyz: np.ndarray           # initial centre, world
    rgba: tuple
    arm: str = ''
    yaw: float = 0.0          # rad about the vertical, lying on a face

    @property
    def quaternion(self):
        """(x, y, z, w) of the cube's initial orientation."""
        return (0.0, 0.0, math.sin(self.yaw / 2), math.cos(self.yaw / 2))


@dataclass
class CellConfig:
    arms: list
    cubes: list
    table_center: tuple
    table_size: tuple
    table_height: float
    cube_size: float = 0.05
    cube_mass: float = 0.1
    physics_hz: float = 240.0
    camera: dict = field(default_factory=dict)
    path: str = ''

    def arm(self, name):
        for a in self.arms:
            if a.name == name:
                return a
        raise KeyError('no arm %r in the cell (arms: %s)' % (name, [a.name for a in self.arms]))

    def cube(self, name):
        for c in self.cubes:
            if c.name == name:
                return c
        raise KeyError('no cube %r' % name)


def _vec(v, n, what, lo=-1e3, hi=1e3):
    """v as n numbers within [lo, hi] (metres or radians: a cell is a few metres)."""
    try:
        a = np.asarray(v, dtype=float)
    except (TypeError, ValueError, OverflowError):
        a = None
    if a is None or a.shape != (n,) or not np.all((a >= lo) & (a <= hi)):   # NaN fails
        raise ValueError('%s must be %d numbers in [%s, %s], got %r' % (
            what, n, np.round(lo, 4).tolist() if np.ndim(lo) else '%g' % lo,
            np.round(hi, 4).tolist() if np.ndim(hi) else '%g' % hi, v))
    return a


# An arm's name is its ROS namespace and its joints' name prefix.
ARM_NAME = re.compile(r'[A-Za-z][A-Za-z0-9_]*')


# The cell file's scalars (a physics rate of 0 or NaN would stop or corrupt the simulation).
# Below 120 Hz the contacts give way: closing fingers sink into a cube and drop it during a
# lift (60-90 Hz), a cube dropped from 1-2 m passes through the 5 cm table top (60-100 Hz).
# A cube wider than the open gripper (85 mm) forced its fingers open past their travel when
# lowered around it (pads sunk into the cube, the knuckle reading below 0), and was still
# lifted, which a real 2F-85 cannot do.
CELL_PARAMS = {
    'physics_hz': Param(240.0, 'physics steps per simulated second (grasps and the table hold '
                        'from 120)', unit='Hz', ge=120.0, le=2000.0),
    # A cube at any yaw to the fingers (its own, or the tool turned) is up to its diagonal
    # across them: 60 mm (85 mm diagonal) fits the open gripper's 85 mm whatever the turn.
    'cube_size': Param(0.05, 'cube edge (at most 60 mm: its diagonal fits the 85 mm open '
                       'gripper)', unit='m', gt=0.0, le=0.06),
    'cube_mass': Param(0.1, 'cube mass', unit='kg', gt=0.0, le=10.0),
    'table_height': Param(0.75, 'z of the table top', unit='m', ge=0.0, le=2.0),
}


# The keys each part of a cell YAML may hold: a misspelt one (base_xzy) was ignored, and its
# default silently used (an arm placed at the origin).
_KEYS = {'cell': ('arms', 'cubes', 'table', 'camera', 'physics_hz', 'cube_size', 'cube_mass'),
         'table': ('center', 'size', 'height'),
         'arm': ('name', 'base_xyz', 'base_rpy', 'home', 'tray'),
         'tray': ('xyz', 'inner', 'wall'),
         'cube': ('name', 'xyz', 'rgba', 'arm', 'yaw'),
         'camera': ('eye', 'target', 'fov')}


def _known_keys(entry, kind, where):
    """ValueError naming a key of `entry` (a dict) that a `kind` part does not have."""
    if not isinstance(entry, dict):
        return
    for key in entry:
        if key not in _KEYS[kind]:
            close = difflib.get_close_matches(str(key), _KEYS[kind], n=1)
            raise ValueError('%sunknown key %r%s (%s keys: %s)'
                             % (where + ': ' if where else '', key,
                                ' (did you mean %s?)' % close[0] if close else '', kind,
                                ', '.join(_KEYS[kind])))


def parse_config(data, path=''):
    """CellConfig from the YAML's dict; ValueError, naming the field, on a malformed file."""
    if not isinstance(data, dict) or not isinstance(data.get('arms'), list) or not data['arms']:
        raise ValueError('cell config %s: needs a non-empty "arms" list' % path)
    try:
        return _parse(data, path)
    except KeyError as e:           # an entry's ['name'], ['xyz'] and the like
        raise ValueError('cell config %s: an entry lacks %r' % (path, e.args[0]))
    except (TypeError, AttributeError) as e:
        raise ValueError('cell config %s: an entry of the wrong shape (%s)' % (path, e))
    except ValueError as e:
        if str(e).startswith('cell config'):
            raise
        raise ValueError('cell config %s: %s' % (path, e))


def _parse(data, path):
    _known_keys(data, 'cell', '')
    table = data.get('table', {})
    _known_keys(table, 'table', 'table')
    _known_keys(data.get('camera'), 'camera', 'camera')
    try:
        scalars = check_params(CELL_PARAMS, {k: v for k, v in dict(
            data, table_height=table.get('height', 0.75)).items() if k in CELL_PARAMS})
    except ParamError as e:
        raise ValueError('cell config %s: %s' % (path, str(e).lstrip('~')))
    height, size = scalars['table_height'], scalars['cube_size']
    arms = []
    for i, a in enumerate(data['arms']):
        name = a['name']
        if not isinstance(name, str) or not ARM_NAME.fullmatch(name):
            raise ValueError('arms[%d].name must be a ROS name (a letter, then letters, digits '
                             'or _), got %r' % (i, name))
        _known_keys(a, 'arm', 'arms[%d]' % i)
        tray = a.get('tray', {})
        _known_keys(tray, 'tray', 'arms[%d].tray' % i)
        arms.append(ArmConfig(
            name=name,
            base_xyz=_vec(a.get('base_xyz', [0, 0, height]), 3, name + ' base_xyz'),
            base_rpy=_vec(a.get('base_rpy', [0, 0, 0]), 3, name + ' base_rpy', -7.0, 7.0),
            home=_vec(a.get('home', HOME_Q), 6, name + ' home (rad)', JOINT_LOWER, JOINT_UPPER),
            tray=TrayConfig(xyz=_vec(tray.get('xyz', [0.45, 0.5, height]), 3, name + ' tray xyz'),
                            inner=tuple(_vec(tray.get('inner', (0.2, 0.2)), 2,
                                             name + ' tray inner', 1e-3, 5.0).tolist()),
                            wall=tuple(_vec(tray.get('wall', (0.01, 0.04)), 2,
                                            name + ' tray wall', 1e-3, 1.0).tolist()))))
    names = [a.name for a in arms]
    if len(set(names)) != len(names):
        raise ValueError('cell config %s: arm names must be unique' % path)
    cubes = []
    for i, c in enumerate(data.get('cubes') or []):
        what = 'cubes[%d]' % i
        _known_keys(c, 'cube', what)
        xyz = list(c['xyz'])
        if len(xyz) == 2:
            xyz.append(_rest_z(xyz, arms, height) + size / 2)
        arm = str(c.get('arm', ''))
        if arm and arm not in names:
            raise ValueError('%s.arm: no arm %r (arms: %s)' % (what, arm, ', '.join(names)))
        rgba = _vec(c.get('rgba', (0.8, 0.2, 0.2, 1)), 4, what + '.rgba', 0.0, 1.0)
        cubes.append(CubeConfig(name=str(c['name']), xyz=_vec(xyz, 3, what + '.xyz'),
                                rgba=tuple(rgba.tolist()), arm=arm,
                                yaw=float(_vec([c.get('yaw', 0.0)], 1, what + '.yaw', -7.0,
                                               7.0)[0])))
    _check_cubes(cubes, height, size,
                 _vec(table.get('center', (0.45, 0.0)), 2, 'table center'),
                 _vec(table.get('size', (1.4, 1.4)), 2, 'table size', 1e-2, 100.0))
    camera = dict(data.get('camera') or {})
    for key, n, lo, hi in (('eye', 3, -1e3, 1e3), ('target', 3, -1e3, 1e3), ('fov', 1, 1.0, 179.0)):
        if key in camera:
            v = _vec(np.atleast_1d(camera[key]), n, 'camera.' + key, lo, hi)
            camera[key] = v.tolist() if n > 1 else float(v[0])
    return CellConfig(arms=arms, cubes=cubes,
                      table_center=tuple(_vec(table.get('center', (0.45, 0.0)), 2,
                                              'table center').tolist()),
                      table_size=tuple(_vec(table.get('size', (1.4, 1.4)), 2, 'table size',
                                            1e-2, 100.0).tolist()),
                      table_height=height, cube_size=size,
                      cube_mass=scalars['cube_mass'], physics_hz=scalars['physics_hz'],
                      camera=camera, path=path)


# The table top is a slab this thick (m) whose top is at the table height.
TABLE_THICKNESS = 0.05


def _rest_z(xy, arms, table_height):
    """z a cube given as [x, y] rests on: the floor of a tray whose footprint holds that
    point (a cube at table height sat 1 cm inside it and was thrown up), else the table."""
    try:
        x, y = (float(v) for v in xy)
    except (TypeError, ValueError):
        return table_height          # _vec names the bad entry
    floors = [a.tray.floor_z for a in arms
              if abs(x - a.tray.xyz[0]) < a.tray.inner[0] / 2 + a.tray.wall[0]
              and abs(y - a.tray.xyz[1]) < a.tray.inner[1] / 2 + a.tray.wall[0]]
    # a tray's floor even when it stands lower than the table, beside it (the table's
    # height there dropped the cube 14 cm into the tray)
    return max(floors) if floors else table_height


def _check_cubes(cubes, table_height, size, table_center, table_size):
    """ValueError for cubes the physics cannot start from: two of one name (the cell's
    poses would report one), one inside the table top or in or under the floor (one 1 m
    under it was thrown 9.6 m up), two inside each other (both thrown apart at the first
    step)."""
    names = [c.name for c in cubes]
    twice = sorted({n for n in names if names.count(n) > 1})
    if twice:
        raise ValueError('cube names must be unique, %s twice' % ', '.join(map(repr, twice)))
    tolerance = 1e-3 * size
    for c in cubes:
        if c.xyz[2] < size / 2 - tolerance:      # cubes lie on a face: size / 2 above z 0
            raise ValueError('cube %r at z %.3f m is %s the floor (z 0): rest it at %.3f m or '
                             'higher' % (c.name, c.xyz[2], 'under' if c.xyz[2] <= -size / 2
                                         else 'inside', size / 2))
        over_table = bool((np.abs(c.xyz[:2] - table_center) < table_size / 2 + size / 2).all())
        if over_table and (table_height - TABLE_THICKNESS - size / 2 < c.xyz[2]
                           < table_height + size / 2 - tolerance):
            raise ValueError('cube %r at z %.3f m is inside the table top (%.3f m): rest it at '
                             '%.3f m or give xyz as [x, y]' % (c.name, c.xyz[2], table_height,
                                                               table_height + size / 2))
    for i, a in enumerate(cubes):
        for b in cubes[i + 1:]:
            # closer than a cube's inscribed spheres allow, whatever their yaws
            if np.linalg.norm(a.xyz - b.xyz) < size - tolerance:
                raise ValueError('cubes %r and %r are inside each other (centres %s and %s, '
                                 'size %.3f m)' % (a.name, b.name, a.xyz.tolist(), b.xyz.tolist(),
                                                   size))


def load_config(name='ur10_cell.yaml'):
    """Load a cell config by path or by file name in config/ (e.g. 'ur10_dual_cell')."""
    path = config_path(name)
    return parse_config(load_yaml_file(path, 'cell config'), path)
