"""Questions a node asks about the ROS graph."""
import rosgraph
import rospy


def wait_for_subscribers(own, topics, who, log_every=5.0):
    """Block until every topic in `topics` (resolved names) has a subscriber; False on
    shutdown. `own` maps this node's resolved topic names to its publishers: those count
    once connected, any other topic once the master lists a subscriber. Logs what it
    waits for every `log_every` s, prefixed by `who`."""
    master = rosgraph.Master(rospy.get_name())
    last_log = rospy.get_time()
    while not rospy.is_shutdown():
        others = [t for t in topics if t not in own]
        listened = set()
        if others:
            try:
                listened = {t for t, nodes in master.getSystemState()[1] if nodes}
            except (rosgraph.MasterError, OSError):
                pass
        waiting = [t for t in topics if (own[t].get_num_connections() == 0 if t in own
                                         else t not in listened)]
        if not waiting:
            return True
        if rospy.get_time() - last_log >= log_every:
            last_log = rospy.get_time()
            rospy.loginfo('%s: waiting for subscribers on %s', who, ', '.join(waiting))
        rospy.sleep(0.05)
    return False
