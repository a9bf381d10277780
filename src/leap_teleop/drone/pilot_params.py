"""The gesture pilot's parameters, declared once: the `Param` tables are the single source of
PilotParams (its fields and defaults are generated from PILOT_PARAMS), of drone_pilot's
~params and --help, of its dynamic_reconfigure server and of the docs' parameter table.
The drone_pilot block of config/ardrone.yaml sets the same names (a test keeps it inside
these declarations).
"""
from leap_teleop.control.stream_health import HAND_SUBSCRIPTION_PARAMS
from leap_teleop.params import Param, ParamError, check_params, declared_fields

# Every PilotParams field. Watchdog times have upper bounds too: a huge timeout is a
# disabled watchdog.
PILOT_PARAMS = {
    'mode': Param('tilt', 'tilt (palm offset -> tilt, dead zone, clamps) or paper '
                          '(the original drone paper\'s mapping, exactly)', choices=('tilt', 'paper')),
    'rate': Param(200.0, 'max steering twist publishing rate (queue drain rate; a hover '
                         'after steering goes at once)', unit='Hz',
                  ge=1.0, le=1000.0),
    'queue_size': Param(10, 'command FIFO bound (oldest twist dropped when full)',
                        ge=1, le=1000),
    'flip_type': Param(19, 'flight animation for a circle gesture (19 = flip right)',
                       ge=0, le=19),
    'flip_duration': Param(0, 'its duration (0 = default)', unit='ms', ge=0, le=10000),
    # a flip loses up to 0.45 m (the simulated one, at its lowest): lower, it strikes the floor
    'flip_min_altitude': Param(0.6, 'no flip below this altitude', unit='m', ge=0.5, le=10.0),
    'flip_min_radius': Param(0.025, 'no flip on a smaller circle (fingertip loops are 4-20 '
                                    'mm)', unit='m', ge=0.0, le=0.5),
    # Lower bounds above the message intervals (Hand ~10 ms, navdata 20 ms at 50 Hz): below
    # them every ordinary gap is a loss, and the drone hovers between each two commands.
    'hand_timeout': Param(0.15, 'no Hand message this long = hand lost (hover); above the '
                                'Hand interval', unit='s', ge=0.05, le=10.0),
    'land_after': Param(3.0, 'lost hand or navdata this long -> land', unit='s',
                        gt=0.0, le=120.0),
    'disarm_after': Param(1.0, 'lost hand this long -> steering off until a new unfold; back '
                               'sooner, it steers on (see recapture_beyond)', unit='s',
                          gt=0.0, le=120.0),
    'recapture_beyond': Param(0.05, 'tilt: back within disarm_after, the reference is '
                                    're-captured where the hand is only when its palm came '
                                    'back this far or further from where it was lost; nearer, '
                                    'the reference is kept (0: always re-captured)',
                              unit='m', ge=0.0, le=1.0),
    'navdata_timeout': Param(0.5, 'no navdata this long = drone state unknown: no takeoff, '
                                  'hover, then land; above the navdata interval', unit='s',
                             ge=0.1, le=10.0),
    'dead_zone': Param(0.03, 'tilt: horizontal palm dead zone', unit='m', ge=0.0, le=0.5),
    'full_scale': Param(0.10, 'tilt: offset beyond the dead zone for full tilt', unit='m',
                        gt=0.0, le=1.0),
    'z_dead_zone': Param(0.03, 'tilt: vertical dead zone', unit='m', ge=0.0, le=0.5),
    'z_full_scale': Param(0.10, 'tilt: offset beyond it for full climb rate', unit='m',
                          gt=0.0, le=1.0),
    'yaw_dead_zone': Param(15.0, 'tilt: dead zone of the hand\'s turn about the vertical '
                                 'since the unfold', unit='deg', ge=0.0, lt=180.0),
    'yaw_full_scale': Param(45.0, 'tilt: yaw beyond it for full yaw rate', unit='deg',
                            gt=0.0, le=180.0),
    'max_cmd': Param(1.0, 'tilt: cap on every cmd_vel component', gt=0.0, le=1.0),
    'paper_angle': Param(25.0, 'paper: pitch and roll above this capture the reference',
                         unit='deg', ge=0.0, lt=90.0),
    'paper_scale': Param(3000.0, 'paper: palm mm per unit command', unit='mm',
                         ge=100.0, le=100000.0),
    'max_input_age': Param(0.25, 'drop a Hand (or gesture event) arriving this much later '
                                 'than the Hand stream\'s best latency', unit='s', gt=0.0,
                           le=10.0),
}

# drone_pilot's own ~params (its wiring), then every pilot one.
PILOT_NODE_PARAMS = {
    'side': Param('right', 'hand to follow', choices=('right', 'left')),
    'hand_topic': Param('', 'Hand topic (default leapmotion/hand_<side>)', ros_name=True),
    'gesture_topic': Param('leapmotion/gestures', 'GestureEvent topic', empty_ok=False, ros_name=True),
    'service_timeout': Param(0.5, 'a flight animation call (its own thread) is abandoned '
                                  'after this long', unit='s', gt=0.0, le=10.0),
    'takeoff_hold': Param(1.0, 'a takeoff sent before the driver listens on ardrone/takeoff '
                               'waits this long for it, then is dropped (a land waits until '
                               'it listens)', unit='s', ge=0.0, le=5.0),
    **HAND_SUBSCRIPTION_PARAMS,
    **PILOT_PARAMS,
}

# Changeable while running (dynamic_reconfigure); the pilot reads each where it uses it.
PILOT_RECONFIGURABLE = ('dead_zone', 'full_scale', 'z_dead_zone', 'z_full_scale',
                        'yaw_dead_zone', 'yaw_full_scale', 'max_cmd', 'paper_angle',
                        'paper_scale', 'flip_min_altitude', 'flip_min_radius',
                        'recapture_beyond')


@declared_fields(PILOT_PARAMS)
class PilotParams:
    """The pilot's configuration: one field per PILOT_PARAMS entry, its default."""

    def update(self, values):
        """Set the keys of `values`, then check every field against PILOT_PARAMS
        (ParamError, a ValueError, names the first bad one); a key it does not declare is
        refused by name (a misspelt one was dropped without a word)."""
        unknown = sorted(set(values) - set(PILOT_PARAMS))
        if unknown:
            raise ParamError('unknown pilot parameters: %s' % ', '.join(unknown))
        for key, value in values.items():
            setattr(self, key, value)
        return self.validate()

    def validate(self):
        for name, value in check_params(PILOT_PARAMS, vars(self)).items():
            setattr(self, name, value)
        return self
