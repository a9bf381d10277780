"""The whole chain without ROS: scripted hand -> LeapInterface -> DronePilot -> ArDroneSim."""
import pytest

from leap_teleop.drone import sim as ds
from leap_teleop.drone.pilot import DronePilot, PilotInput, PilotParams
from leap_teleop.drone.sim import ArDroneSim
from leap_teleop.hands.leap_interface import LeapInterface
from leap_teleop.hands.sources.scripted import ScriptedSource
from leap_teleop.package_files import package_path

# needs a ROS master, a simulator, a subprocess or a build: not in make check
pytestmark = pytest.mark.integration

SCRIPT = package_path('config', 'gestures', 'drone_flight.yaml')


def fly_script(path, mode='tilt'):
    source = ScriptedSource(path, realtime=False)
    li = LeapInterface(sides=('right',))
    drone = ArDroneSim()
    pilot = DronePilot(PilotParams(mode=mode))
    events, t0, mono = [], None, 0.0
    for frame in source.frames():
        t0 = frame.timestamp if t0 is None else t0
        t = frame.timestamp - t0
        while drone.time < t:
            drone.step()
        nav = drone.navdata()
        pilot.on_navdata(nav['state'], nav['altd'], t)
        st = li.on_frame(frame)['right']
        pilot.on_hand(PilotInput(st.present, tuple(v * 1e-3 for v in st.palm_position),
                                st.palm_normal, st.direction), t)
        for e in st.events:
            events.append(e.gesture)
            pilot.on_gesture(e.gesture, e.active, t, e.value)
        pilot.watchdog(t)
        mono += 1.0          # pacing is the node's business; drain everything here
        while True:
            cmd, _ = pilot.pop(mono)
            if cmd is None:
                break
            mono += 1.0
            if cmd.kind == 'twist':
                drone.set_cmd_vel(*cmd.twist)
            elif cmd.kind == 'takeoff':
                drone.takeoff()
            elif cmd.kind == 'land':
                drone.land()
            elif cmd.kind == 'flip':
                drone.flight_animation(*cmd.anim)
    drone.advance(3.0)
    return drone, events


def test_scripted_flight_takeoff_forward_flip_land():
    drone, events = fly_script(SCRIPT)
    seq = [s for _, s in drone.events]
    assert 'unfold' in events and 'fold' in events
    assert any(e.startswith('circle_') for e in events)
    assert seq[0] == ds.TAKING_OFF and seq[-2:] == [ds.LANDING, ds.LANDED]
    assert ds.LOOPING in seq and drone.flip_count == 1
    x, y = drone.pos[0], drone.pos[1]
    assert x == pytest.approx(1.0, abs=0.3)          # ~1 m forward
    assert abs(y) < 0.3
    assert drone.altitude < 0.02
