"""The rotated-cube task in the closed loop (no ROS, simulated time): both arms in yaw
orientation mode pick a cube lying at 30 / 60 deg across its faces and place it square.
Returns per-arm results and writes a picture of the turned grasp.

usage: python -m tools.rotated_task [--png docs/rotated_grasp.png]
"""
import argparse
import json
import math
import sys

import numpy as np

from leap_teleop.package_files import package_path
from tools.closed_loop import run_session, sim_params

SCRIPT = 'ur10_pick_place_rotated.yaml'
CELL = 'ur10_dual_rotated_cell.yaml'
TASKS = {'ur10_1': ('right', 'cube_red'), 'ur10_2': ('left', 'cube_yellow')}
# A close view of ur10_1's cube, taken when the open jaws, turned with the hand, have come
# down around it (the square cube beside it for comparison).
GRASP_VIEW = {'eye': [1.2, -0.6, 1.1], 'target': [0.68, -0.92, 0.82], 'fov': 38}



def run(png=None, orientation='yaw'):
    shot = {}

    def on_period(cell, t):
        if png and 'done' not in shot:
            tcp = cell.tcp_pose('ur10_1')[:3, 3]
            cube = cell.object_poses()['cube_red'][0]
            if np.linalg.norm(tcp - cube) < 0.006:
                cell.snapshot(png, width=800, height=600, **GRASP_VIEW)
                shot['done'] = True

    cell, runs = run_session(package_path('config', 'gestures', SCRIPT), CELL,
                             {arm: side for arm, (side, _) in TASKS.items()},
                             sim_params(orientation=orientation), on_period=on_period)
    try:
        out = {}
        for arm, (_, cube) in TASKS.items():
            tray = cell.config.arm(arm).tray.xyz
            err = float(np.linalg.norm(cell.object_poses()[cube][0][:2] - np.asarray(tray[:2])))
            yaw = math.degrees(cell.cube_yaw_error(cube))
            start = math.degrees(cell.config.cube(cube).yaw)
            ok = bool(cell.in_tray(cube, arm) and err < 0.03 and yaw < 5.0)
            out['%s_rotated_cube' % arm] = {
                'success': ok, 'cube': '%s at %.0f deg' % (cube, start),
                'placement_error_m': round(err, 4), 'yaw_from_square_deg': round(yaw, 2),
                'state_sequence': [s for _, s in runs[arm].states]}
        return out
    finally:
        cell.close()


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument('--png', default=None)
    ap.add_argument('--orientation', default='yaw', choices=['fixed', 'yaw', 'full'])
    args = ap.parse_args(argv)
    result = run(args.png, args.orientation)
    print(json.dumps(result, indent=1))
    return 0 if all(r['success'] for r in result.values()) else 1


if __name__ == '__main__':
    sys.exit(main())
