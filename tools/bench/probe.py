"""A measuring subscriber for benchmarks: records, per message, the receipt wall time,
the header stamp and (where present) leap_frame_id, then writes them as JSON.

usage: python -m tools.bench.probe --topic T --type pkg/Msg --duration S --out F
"""
import argparse
import json
import time

import psutil
import roslib.message
import rospy


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument('--topic', required=True)
    ap.add_argument('--type', required=True)
    ap.add_argument('--duration', type=float, required=True)
    ap.add_argument('--warmup', type=float, default=1.0,
                    help='s after the first message before recording starts')
    ap.add_argument('--timeout', type=float, default=30.0, help='s to wait for the first message')
    ap.add_argument('--cpu-pid', type=int, default=0,
                    help='also record this process\'s CPU seconds over the recording window')
    ap.add_argument('--out', required=True)
    args = ap.parse_args(rospy.myargv()[1:] if argv is None else argv)
    msg_class = roslib.message.get_message_class(args.type)
    if msg_class is None:
        raise SystemExit('unknown message type %s' % args.type)
    rospy.init_node('bench_probe', anonymous=True, disable_signals=True)
    rows = []
    state = {'record_from': None}

    def callback(msg):
        now = time.time()
        if state['record_from'] is None:
            state['record_from'] = now + args.warmup
        if now >= state['record_from']:
            rows.append((now, msg.header.stamp.to_sec(), getattr(msg, 'leap_frame_id', 0)))

    rospy.Subscriber(args.topic, msg_class, callback, queue_size=10000, tcp_nodelay=True)
    deadline = time.time() + args.timeout
    while state['record_from'] is None and time.time() < deadline:
        time.sleep(0.01)
    if state['record_from'] is None:
        raise SystemExit('no message on %s within %.0f s' % (args.topic, args.timeout))
    cpu = [None, None]
    while time.time() < state['record_from'] + args.duration:
        if args.cpu_pid and cpu[0] is None and time.time() >= state['record_from']:
            cpu[0] = sum(psutil.Process(args.cpu_pid).cpu_times()[:2])
        time.sleep(0.01)
    if args.cpu_pid:
        cpu[1] = sum(psutil.Process(args.cpu_pid).cpu_times()[:2])
    recorded = list(rows)
    with open(args.out, 'w') as f:
        json.dump({'receipt': [r[0] for r in recorded], 'stamp': [r[1] for r in recorded],
                   'frame_id': [r[2] for r in recorded],
                   'window': [state['record_from'], state['record_from'] + args.duration],
                   'cpu_s': (cpu[1] - cpu[0]) if args.cpu_pid else None}, f)
    rospy.signal_shutdown('done')


if __name__ == '__main__':
    main()
