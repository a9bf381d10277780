"""RViz helpers: hand markers from the rich Hand message and from the driver-compatible
DriverHuman, a text marker of the pipeline's latency, a drone body made of primitive
markers, and a bounded pose trail for nav_msgs/Path. Message building only: no node, no
master needed (the ROS adapters are nodes/hand_markers.py, nodes/sender.py and
nodes/ardrone_sim.py)."""
import collections
import math

import rospy
from geometry_msgs.msg import Point, PoseStamped
from nav_msgs.msg import Path
from std_msgs.msg import ColorRGBA
from visualization_msgs.msg import Marker, MarkerArray

from leap_teleop.msg import Hand

SIDE_NAMES = {Hand.SIDE_RIGHT: 'right', Hand.SIDE_LEFT: 'left'}
# Recognised state -> colour (r, g, b); the first flag set wins, in this order.
STATE_COLOURS = collections.OrderedDict([
    ('fist', (0.90, 0.15, 0.10)),
    ('thumb_up', (0.10, 0.80, 0.20)),
    ('pinch', (0.15, 0.45, 1.00)),
    ('rock', (1.00, 0.75, 0.00)),
    ('thumb_down', (0.60, 0.20, 0.70)),
])
IDLE_COLOUR = (0.75, 0.75, 0.75)     # open / no recognised gesture
FOLDED_ALPHA = 0.35                   # folded fingertips are drawn faint

# Marker ids inside each hand's namespace ("hand_right", "hand_left").
PALM, TIPS, BONES, NORMAL, LABEL = range(5)
HAND_MARKER_IDS = (PALM, TIPS, BONES, NORMAL, LABEL)


def hand_state(hand):
    """The name of the state that colours the hand: fist, thumb_up, pinch, rock,
    thumb_down or open."""
    for name in STATE_COLOURS:
        if getattr(hand, name):
            return name
    return 'open'


def hand_namespace(hand):
    try:
        return 'hand_' + SIDE_NAMES[hand.side]
    except KeyError:
        raise ValueError('Hand.side %r is neither SIDE_RIGHT (0) nor SIDE_LEFT (1)' % hand.side)


def _colour(rgb, alpha=1.0):
    return ColorRGBA(rgb[0], rgb[1], rgb[2], alpha)


# Farther than this (m) from the frame's origin is no hand: huge finite coordinates make
# RViz's renderer fail its bounding-box assertions.
MAX_MARKER_COORD_M = 1000.0


def _finite_point(p, what):
    if not all(math.isfinite(v) and abs(v) <= MAX_MARKER_COORD_M for v in (p.x, p.y, p.z)):
        raise ValueError('%s is not finite or beyond %g m: (%r, %r, %r)'
                         % (what, MAX_MARKER_COORD_M, p.x, p.y, p.z))
    return Point(p.x, p.y, p.z)


def _marker(hand, ns, marker_id, marker_type, frame_id, lifetime):
    m = Marker()
    m.header.stamp = hand.header.stamp
    m.header.frame_id = frame_id or hand.header.frame_id
    m.ns, m.id, m.type, m.action = ns, marker_id, marker_type, Marker.ADD
    m.pose.orientation.w = 1.0
    m.lifetime = rospy.Duration.from_sec(lifetime)
    return m


def hand_markers(hand, frame_id='', lifetime=0.5, scale=1.0):
    """MarkerArray for one leap_teleop/Hand message.

    Present hand: palm sphere, fingertip spheres (folded ones faint), lines palm -> tips,
    an arrow along the palm normal and a text label, all coloured by the recognised
    state (STATE_COLOURS). Absent hand: DELETE for each of those markers. frame_id ''
    keeps the message's frame; lifetime (s) makes markers vanish if the input stops.
    Raises ValueError for a bad side or coordinates that are not finite or beyond
    MAX_MARKER_COORD_M.
    """
    ns = hand_namespace(hand)
    frame_id = frame_id or hand.header.frame_id
    if not frame_id:
        raise ValueError('the Hand message has no header.frame_id and none was given')
    out = MarkerArray()
    if not hand.present:
        for marker_id in HAND_MARKER_IDS:
            m = _marker(hand, ns, marker_id, Marker.SPHERE, frame_id, 0.0)
            m.action = Marker.DELETE
            out.markers.append(m)
        return out

    palm = _finite_point(hand.palm_position, 'palm_position')
    tips = [_finite_point(t, 'finger_tips[%d]' % i) for i, t in enumerate(hand.finger_tips)]
    state = hand_state(hand)
    rgb = STATE_COLOURS.get(state, IDLE_COLOUR)

    m = _marker(hand, ns, PALM, Marker.SPHERE, frame_id, lifetime)
    m.pose.position = palm
    m.scale.x = m.scale.y = m.scale.z = 0.04 * scale
    m.color = _colour(rgb)
    out.markers.append(m)

    m = _marker(hand, ns, TIPS, Marker.SPHERE_LIST, frame_id, lifetime)
    m.scale.x = m.scale.y = m.scale.z = 0.016 * scale
    m.points = tips
    m.colors = [_colour(rgb, 1.0 if ext else FOLDED_ALPHA) for ext in hand.finger_extended]
    m.color = _colour(rgb)
    out.markers.append(m)

    m = _marker(hand, ns, BONES, Marker.LINE_LIST, frame_id, lifetime)
    m.scale.x = 0.004 * scale
    m.points = [q for tip in tips for q in (palm, tip)]
    m.color = _colour(rgb, 0.8)
    out.markers.append(m)

    n = _finite_point(hand.palm_normal, 'palm_normal')
    m = _marker(hand, ns, NORMAL, Marker.ARROW, frame_id, lifetime)
    length = 0.06 * scale
    m.points = [palm, Point(palm.x + n.x * length, palm.y + n.y * length,
                            palm.z + n.z * length)]
    m.scale.x, m.scale.y, m.scale.z = 0.006 * scale, 0.012 * scale, 0.015 * scale
    m.color = _colour(rgb, 0.9)
    out.markers.append(m)

    m = _marker(hand, ns, LABEL, Marker.TEXT_VIEW_FACING, frame_id, lifetime)
    # Above the palm along Leap +y (up), clear of the fingers.
    m.pose.position = Point(palm.x, palm.y + 0.08 * scale, palm.z)
    m.scale.z = 0.025 * scale
    m.text = '%s: %s' % (SIDE_NAMES[hand.side], state)
    m.color = _colour(rgb)
    out.markers.append(m)
    return out


# The leap_motion driver's visualizer: per present hand of a DriverHuman, namespace "Right" /
# "Left" for the palm and knuckle outline, "<side>_<Finger>" for each finger's bones and joints.
DRIVER_PALM_RGB, DRIVER_JOINT_RGB = (0.0, 0.0, 1.0), (1.0, 0.0, 0.0)
DRIVER_BONE_RGB = (1.0, 1.0, 1.0)
DRIVER_FINGER_NAMES = ('Thumb', 'Index', 'Middle', 'Ring', 'Pinky')


def driver_markers(human, lifetime=0.1):
    """MarkerArray for one DriverHuman, as the driver's visualizer draws it: a palm sphere,
    lines across the knuckles, and per finger its bones as lines and its joints (and tip) as
    spheres; metres, the message's frame. Absent hands get no markers: the short lifetime
    (s) clears them. Raises ValueError for coordinates that are not finite or beyond
    MAX_MARKER_COORD_M."""
    out = MarkerArray()
    for side, hand in (('Right', human.right_hand), ('Left', human.left_hand)):
        if not hand.is_present:
            continue

        def marker(ns, marker_id, marker_type, rgb, size):
            m = Marker()
            m.header = human.header
            m.ns, m.id, m.type, m.action = ns, marker_id, marker_type, Marker.ADD
            m.pose.orientation.w = 1.0
            m.scale.x = m.scale.y = m.scale.z = size
            m.color = _colour(rgb)
            m.lifetime = rospy.Duration.from_sec(lifetime)
            out.markers.append(m)
            return m

        m = marker(side, 0, Marker.SPHERE, DRIVER_PALM_RGB, 0.025)
        m.pose.position = _finite_point(hand.palm_center, 'palm_center')
        fingers = hand.finger_list
        if len(fingers) == 5 and all(len(f.bone_list) == 4 for f in fingers):
            knuckles = [_finite_point(f.bone_list[1].bone_start.position, 'knuckle')
                        for f in fingers]
            m = marker(side, 1, Marker.LINE_LIST, DRIVER_BONE_RGB, 0.0075)
            m.points = [q for a, b in zip(knuckles, knuckles[1:]) for q in (a, b)]
        for f in fingers:
            ns = '%s_%s' % (side, DRIVER_FINGER_NAMES[f.type % 5])
            ends = [_finite_point(b.bone_end.position, 'bone_end') for b in f.bone_list]
            starts = [_finite_point(b.bone_start.position, 'bone_start') for b in f.bone_list]
            m = marker(ns, 0, Marker.LINE_LIST, DRIVER_BONE_RGB, 0.0075)
            m.points = [q for a, b in zip(starts, ends) for q in (a, b)]
            m = marker(ns, 1, Marker.SPHERE_LIST, DRIVER_JOINT_RGB, 0.015)
            m.points = starts[1:] + ends[-1:]
    return out


class HandMarkerThrottle:
    """Decides per message whether markers go out: present hands at most max_rate Hz
    (a state change goes out at once), DELETEs once when a hand leaves, nothing while it
    stays away. RViz needs no more than its frame rate, the sender sends ~120 Hz per hand."""

    def __init__(self, max_rate=30.0, frame_id='', lifetime=0.5, scale=1.0):
        if max_rate < 0 or lifetime < 0 or scale <= 0:
            raise ValueError('need max_rate >= 0, lifetime >= 0, scale > 0 '
                             '(got %r, %r, %r)' % (max_rate, lifetime, scale))
        self.min_period = 1.0 / max_rate if max_rate > 0 else 0.0
        self.frame_id, self.lifetime, self.scale = frame_id, lifetime, scale
        self._last = {}     # side -> (time sent, state name or None when absent)

    def update(self, hand, now):
        """MarkerArray to publish for this Hand at time now (s), or None."""
        last = self._last.get(hand.side)
        if not hand.present:
            if last is not None and last[1] is None:
                return None
            out = hand_markers(hand, self.frame_id, self.lifetime, self.scale)
            self._last[hand.side] = (now, None)
            return out
        state = hand_state(hand)
        if (last is not None and last[1] == state
                and 0.0 <= now - last[0] < self.min_period):
            return None
        out = hand_markers(hand, self.frame_id, self.lifetime, self.scale)
        self._last[hand.side] = (now, state)
        return out


LATENCY_NS = 'latency'
LATENCY_RGB = (1.0, 1.0, 1.0)


def latency_marker(lines, frame_id, position, stamp, scale=1.0, lifetime=3.0):
    """A TEXT_VIEW_FACING Marker (namespace 'latency') of `lines` at `position` (x, y, z)
    in frame_id, stamped `stamp` (s); with no lines, a DELETE (nothing is reporting). The
    lifetime clears it when its publisher stops."""
    m = Marker()
    m.header.stamp = rospy.Time.from_sec(stamp)
    m.header.frame_id = frame_id
    m.ns, m.id, m.type = LATENCY_NS, 0, Marker.TEXT_VIEW_FACING
    if not lines:
        m.action = Marker.DELETE
        return m
    m.action = Marker.ADD
    m.pose.position = Point(*[float(v) for v in position])
    m.pose.orientation.w = 1.0
    m.scale.z = 0.05 * scale            # line height, m: readable beside a whole arm
    m.color = _colour(LATENCY_RGB)
    m.text = '\n'.join(lines)
    m.lifetime = rospy.Duration.from_sec(lifetime)
    return m


def drone_markers(frame_id='ardrone_base_link', ns='ardrone'):
    """An AR.Drone 2.0 with the indoor hull drawn from primitives in its body frame
    (x forward): body, four rotor discs, a red nose. frame_locked, so RViz moves them
    with TF; publish once on a latched topic."""
    out = MarkerArray()

    def add(marker_type, xyz, size, rgba):
        m = Marker()
        m.header.frame_id = frame_id
        m.ns, m.id, m.type, m.action = ns, len(out.markers), marker_type, Marker.ADD
        m.frame_locked = True
        m.pose.position.x, m.pose.position.y, m.pose.position.z = xyz
        m.pose.orientation.w = 1.0
        m.scale.x, m.scale.y, m.scale.z = size
        m.color = ColorRGBA(*rgba)
        out.markers.append(m)

    add(Marker.CUBE, (0.0, 0.0, 0.0), (0.30, 0.10, 0.06), (0.15, 0.15, 0.15, 1.0))
    add(Marker.CUBE, (0.0, 0.0, 0.0), (0.45, 0.03, 0.02), (0.25, 0.25, 0.25, 1.0))
    add(Marker.CUBE, (0.0, 0.0, 0.0), (0.03, 0.45, 0.02), (0.25, 0.25, 0.25, 1.0))
    for x in (0.16, -0.16):
        for y in (0.16, -0.16):
            add(Marker.CYLINDER, (x, y, 0.02), (0.20, 0.20, 0.01), (0.2, 0.6, 0.9, 0.6))
    add(Marker.SPHERE, (0.17, 0.0, 0.0), (0.06, 0.06, 0.06), (0.9, 0.1, 0.1, 1.0))
    return out


class PathTrail:
    """The last max_points poses, a new one only after moving min_step metres: a
    bounded nav_msgs/Path however long the flight. Each pose becomes its PoseStamped when
    added, so a publish only lists them (building 2000 at once took 16 ms of the drone
    simulator's 20 ms physics tick)."""

    def __init__(self, max_points=2000, min_step=0.02, frame_id=''):
        if int(max_points) < 2 or min_step < 0:
            raise ValueError('path needs max_points >= 2 and min_step >= 0 (got %r, %r)'
                             % (max_points, min_step))
        self.poses = collections.deque(maxlen=int(max_points))      # PoseStamped
        self.min_step = float(min_step)
        self.frame_id = frame_id
        self.changed = False
        self._last_xyz = None

    def add(self, stamp, xyz, quat_xyzw):
        """Append a pose (stamp: rospy.Time) if far enough from the last; True if added."""
        if not all(math.isfinite(v) for v in tuple(xyz) + tuple(quat_xyzw)):
            return False
        if self.poses and math.dist(self._last_xyz, xyz) < self.min_step:
            return False
        ps = PoseStamped()
        ps.header.frame_id, ps.header.stamp = self.frame_id, stamp
        ps.pose.position.x, ps.pose.position.y, ps.pose.position.z = xyz
        o = ps.pose.orientation
        o.x, o.y, o.z, o.w = quat_xyzw
        self.poses.append(ps)
        self._last_xyz = tuple(xyz)
        self.changed = True
        return True

    def clear(self):
        self.poses.clear()
        self.changed = True

    def to_msg(self, frame_id, stamp=None):
        if frame_id != self.frame_id:       # once, if ever: the poses are kept in this frame
            self.frame_id = frame_id
            for ps in self.poses:
                ps.header.frame_id = frame_id
        path = Path()
        path.header.frame_id = frame_id
        if stamp is not None:
            path.header.stamp = stamp
        elif self.poses:
            path.header.stamp = self.poses[-1].header.stamp
        path.poses = list(self.poses)
        self.changed = False
        return path
