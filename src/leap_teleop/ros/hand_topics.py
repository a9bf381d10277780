"""The sender's hand topics: per side leapcobot (what the arms read), Hand and the shared
GestureEvent topic (what the pilot reads); on request the old leapros and leap messages of
one side and the leap_motion driver's topics (LeapMotionTopics)."""
import time

import rospy

from leap_teleop.control.input_age import StageAges
from leap_teleop.hands.sender_setup import PeriodThrottle
from leap_teleop.msg import GestureEvent, Hand, leap, leapros
from leap_teleop.ros import hand_conversions
from leap_teleop.ros.graph import wait_for_subscribers
from leap_teleop.ros.leap_motion_topics import LeapMotionTopics
from leap_teleop.ros.signals import quiet_at_shutdown


def stage_clock():
    """rospy.get_time's clock, cheaply: without /use_sim_time it is time.time, which costs
    a few percent of what rospy.get_time does (it builds a rospy.Time) on the per-frame path."""
    return rospy.get_time if rospy.get_param('/use_sim_time', False) else time.time


class HandTopics:
    """Publishes each hand of a LeapInterface as soon as it is recognised (on the source's
    thread), from the sender's checked ~params `p`. `ages` gets each hand's capture ->
    recognized and capture -> published (read them on another thread: StageAges)."""

    def __init__(self, p, interface, clock=None):
        self.p = p
        self.clock = clock or stage_clock()
        self.ages = StageAges(('recognized', 'published'))
        self.interface = interface
        self.sides = list(p['sides'])
        q = int(p['queue_size'])
        gestures = rospy.Publisher(p['gesture_topic'], GestureEvent, queue_size=q)
        self.pubs = {side: {'leapcobot': rospy.Publisher(p['leapcobot_topic_' + side],
                                                         hand_conversions.LEAPCOBOT_TYPES[side],
                                                         queue_size=q),
                            'hand': rospy.Publisher(p['hand_topic_' + side], Hand, queue_size=q),
                            'gesture': gestures}
                     for side in self.sides}
        # One leapcobot message per side, refilled every frame (hand_conversions.to_leapcobot).
        self._leapcobot = {side: hand_conversions.LEAPCOBOT_TYPES[side]() for side in self.sides}
        self.throttle = PeriodThrottle(p['freq'])
        self._present_sent = {}         # side: Hand.present of the last message sent
        self.published = 0
        self.leapros_side = p['leapros_side']
        self.leapros = (rospy.Publisher(p['leapros_topic'], leapros, queue_size=q)
                        if p['leapros_topic'] else None)
        self.leap = (rospy.Publisher(p['leap_topic'], leap, queue_size=q)
                     if p['leap_topic'] else None)
        self._classic_last = None       # (state, hand) last present on leapros_side
        # On the source's thread, which can outlive the node's shutdown by a frame.
        interface.add_hand_listener(quiet_at_shutdown(self.on_hand))
        self.driver = LeapMotionTopics(p, q)
        if self.driver.pubs:
            interface.add_listener(quiet_at_shutdown(self.driver.on_frame))

    def _publish_classic(self, state):
        """The old sender's leapros / leap of one side: the last pose seen (on_hand keeps
        it), with this frame's stamp, also while the hand is away, as the classic sender
        went on publishing what it had last seen (its consumers saw the palm drop to the
        device and zero directions); before any, only the header."""
        last, hand = self._classic_last or (state, None)
        frame_id = self.p['frame_id']
        for pub, msg in ((self.leapros, lambda: hand_conversions.to_leapros(last, hand, frame_id)),
                         (self.leap, lambda: hand_conversions.to_leap(last, frame_id))):
            if pub is not None:
                msg = msg()
                msg.header.stamp = rospy.Time.from_sec(state.timestamp)
                pub.publish(msg)

    def wait_for_subscribers(self, topics=()):
        """Block until every topic in `topics` (default: every leapcobot topic) has a
        subscriber; False on shutdown."""
        own = {pub.resolved_name: pub for pubs in self.pubs.values() for pub in pubs.values()}
        for pub in [self.leapros, self.leap] + list(self.driver.pubs.values()):
            if pub is not None:
                own[pub.resolved_name] = pub
        names = [rospy.resolve_name(t) for t in topics] or [
            pubs['leapcobot'].resolved_name for pubs in self.pubs.values()]
        return wait_for_subscribers(own, names, 'sender')

    def report(self):
        """The sender's /diagnostics (level, summary, values); the stage ages follow them."""
        i = self.interface
        failed = i.error is not None
        return ('error' if failed else 'ok',
                ('the hand source failed: %s; ' % i.error if failed else '')
                + '%d frames, %d hands published' % (i.frames_seen, self.published),
                [('frames', str(i.frames_seen)), ('frames without a capture time', str(i.rejected_frames)),
                 ('hands published', str(self.published))])

    def on_hand(self, frame, state):
        """Publish one side's messages as soon as that side is recognised."""
        side = state.side
        pubs = self.pubs.get(side)
        if pubs is None:
            return
        self.ages.add('recognized', self.clock(), frame.timestamp)
        classic = side == self.leapros_side and (self.leapros is not None or self.leap is not None)
        if classic and state.present:       # the last pose seen, sent or not (~freq)
            self._classic_last = (state, frame.hand(side))
        # a frame with gesture events (edges: a fold, a lost hand) or a hand that came or
        # went always goes out, whatever ~freq says
        if not self.throttle.due(side, frame.timestamp, change=bool(state.events) or (
                state.present != self._present_sent.get(side))):
            return
        self._present_sent[side] = state.present
        for kind, msg in hand_conversions.hand_messages(state, self.p['frame_id'],
                                                   self._leapcobot[side]):
            pubs[kind].publish(msg)
        if classic:
            self._publish_classic(state)
        self.ages.add('published', self.clock(), frame.timestamp)
        self.published += 1
