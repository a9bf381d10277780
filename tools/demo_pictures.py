"""The demo's pictures for people: the drone's flight as a chase-view GIF and a plot, and
the arm snapshots with an inset of the hand that drives each arm.

Inputs are what the demo recorded from the ROS graph: the drone's odometry track
[(t, x, y, z, qx, qy, qz, qw)], its navdata states [(t, state)], the pilot's gesture
events [(t, name)], front-camera frames [(t, rgb)], and per arm snapshot the latest
Hand message of each side. The chase view is re-rendered afterwards from the recorded
poses (in a PyBullet client of this process, with the simulator's scene and drone body),
so the GIF can slow the flip down without loading the running simulation.
"""
import math

import numpy as np
from PIL import Image, ImageDraw, ImageFont

from leap_teleop.drone.sim import STATE_NAMES

# What the pilot does on each gesture (the drone's gestures in the README).
GESTURE_ACTIONS = {'unfold': 'takeoff', 'fold': 'land', 'circle_cw': 'flip',
                   'circle_ccw': 'flip'}
STATE_COLOURS = {2: (90, 90, 90), 6: (40, 120, 220), 3: (30, 150, 60), 4: (30, 150, 60),
                 9: (220, 60, 40), 8: (230, 150, 20), 0: (200, 0, 0)}
FRAME_S = 0.25               # chase-view frame spacing (shown in real time)
FLIP_FRAME_S = 0.05          # frame spacing around a flip, shown at FLIP_SLOWDOWN
FLIP_SLOWDOWN = 3


def _font(size):
    for name in ('DejaVuSans-Bold.ttf', '/usr/share/fonts/truetype/dejavu/DejaVuSans-Bold.ttf'):
        try:
            return ImageFont.truetype(name, size)
        except OSError:
            continue
    return ImageFont.load_default()


def state_at(states, t):
    """The navdata state in force at time t (states: [(t, state)] in time order)."""
    current = states[0][1] if states else 2
    for ts, s in states:
        if ts > t:
            break
        current = s
    return current


def _yaw(q):
    x, y, z, w = q
    return math.atan2(2 * (w * z + x * y), 1 - 2 * (y * y + z * z))


def frame_times(track, states):
    """Chase-view times: every FRAME_S, every FLIP_FRAME_S from 0.3 s before a flip to
    0.5 s after it. Returns [(t, shown ms)]."""
    if not track:
        return []
    t0, t1 = track[0][0], track[-1][0]
    landed = [ts for ts, s in states if s == 2 and ts > t0]
    if landed and any(s == 6 for _, s in states):
        t1 = min(t1, landed[-1] + 2.0)            # a moment on the ground, then stop
    flips = []
    for i, (ts, s) in enumerate(states):
        if s == 9:
            end = states[i + 1][0] if i + 1 < len(states) else t1
            flips.append((ts - 0.3, end + 0.5))
    out, t = [], t0
    while t <= t1:
        if any(a <= t <= b for a, b in flips):
            out.append((t, int(round(FLIP_FRAME_S * 1000 * FLIP_SLOWDOWN))))
            t += FLIP_FRAME_S
        else:
            out.append((t, int(FRAME_S * 1000)))
            t += FRAME_S
    return out


def _sample(track, t):
    """The track's pose at time t (nearest sample at or before t)."""
    times = [row[0] for row in track]
    i = max(0, int(np.searchsorted(times, t, side='right')) - 1)
    return track[i]


def chase_gif(track, states, gestures, path, camera_frames=(), size=(480, 360)):
    """Render the chase-view GIF of the recorded flight; returns the number of frames."""
    import pybullet as pb

    from leap_teleop.drone.cameras import chase_view
    from leap_teleop.drone.sim import ArDroneSim
    drone = ArDroneSim()          # its client holds the drone body, and the scene:
    drone.show_scene()
    frames, durations = [], []
    try:
        z_rest = drone.p.hull[2]
        cam_yaw = None
        t_start = track[0][0] if track else 0.0
        for t, shown_ms in frame_times(track, states):
            row = _sample(track, t)
            pos, quat = row[1:4], row[4:8]
            state = state_at(states, t)
            yaw = _yaw(quat)
            if cam_yaw is None:
                cam_yaw = yaw
            elif state != 9:      # the camera keeps its heading through a flip
                cam_yaw += 0.35 * math.atan2(math.sin(yaw - cam_yaw), math.cos(yaw - cam_yaw))
            pb.resetBasePositionAndOrientation(drone.body, (pos[0], pos[1], pos[2] + z_rest),
                                               quat, physicsClientId=drone.client)
            img = chase_view(drone.client, (pos[0], pos[1], pos[2] + z_rest), cam_yaw,
                             size[0], size[1], behind=1.6, above=0.7)
            pic = Image.fromarray(img)
            slow = shown_ms != int(FRAME_S * 1000)
            _annotate_flight(pic, t - t_start, state, pos, _last_gesture(gestures, t), slow)
            cam = _nearest_before(camera_frames, t)
            if cam is not None:
                _inset(pic, Image.fromarray(cam), 'front camera')
            frames.append(pic.convert('P', palette=Image.ADAPTIVE, colors=128))
            durations.append(shown_ms)
    finally:
        drone.close()
    if frames:
        frames[0].save(path, save_all=True, append_images=frames[1:], duration=durations,
                       loop=0, optimize=True)
    return len(frames)


def _last_gesture(gestures, t, hold_s=2.5):
    recent = [(ts, g) for ts, g in gestures if ts <= t and t - ts < hold_s]
    return recent[-1][1] if recent else None


def _nearest_before(samples, t):
    best = None
    for ts, img in samples:
        if ts > t:
            break
        best = img
    return best


def _annotate_flight(pic, t, state, pos, gesture, slow):
    draw = ImageDraw.Draw(pic, 'RGBA')
    w, _ = pic.size
    big, small = _font(20), _font(14)
    draw.rectangle([0, 0, w, 34], fill=(0, 0, 0, 150))
    name = STATE_NAMES.get(state, str(state)).upper()
    colour = STATE_COLOURS.get(state, (255, 255, 255))
    draw.rounded_rectangle([6, 5, 14 + draw.textlength(name, font=big), 30], 5, fill=colour)
    draw.text((10, 6), name, font=big, fill=(255, 255, 255))
    text = 't %4.1f s   alt %.2f m   x %+.2f m' % (t, pos[2], pos[0])
    draw.text((w - 8 - draw.textlength(text, font=small), 9), text, font=small,
              fill=(255, 255, 255))
    lines = []
    if gesture:
        lines.append('hand: %s -> %s' % (gesture.split('_')[0],
                                         GESTURE_ACTIONS.get(gesture, gesture)))
    if slow:
        lines.append('slow motion x%d' % FLIP_SLOWDOWN)
    for i, text in enumerate(lines):
        y = pic.size[1] - 30 - 28 * i
        draw.rectangle([6, y - 3, 14 + draw.textlength(text, font=big), y + 24],
                       fill=(0, 0, 0, 160))
        draw.text((10, y), text, font=big, fill=(255, 230, 90))


def _inset(pic, small, label, scale=0.3):
    w, h = pic.size
    iw = int(w * scale)
    ih = int(small.size[1] * iw / small.size[0])
    small = small.resize((iw, ih))
    x, y = w - iw - 6, h - ih - 6
    draw = ImageDraw.Draw(pic)
    draw.rectangle([x - 2, y - 18, x + iw + 1, y + ih + 1], fill=(20, 20, 20))
    pic.paste(small, (x, y))
    draw.text((x + 3, y - 16), label, font=_font(12), fill=(255, 255, 255))


def flight_plot(track, states, gestures, path):
    """Altitude, x, y and state against time, with the gestures that changed the state."""
    import matplotlib
    matplotlib.use('Agg')
    import matplotlib.pyplot as plt
    t0 = track[0][0]
    t = np.array([r[0] for r in track]) - t0
    xyz = np.array([r[1:4] for r in track])
    fig, axes = plt.subplots(4, 1, figsize=(9, 7.5), sharex=True,
                             gridspec_kw={'height_ratios': [2, 1.2, 1.2, 1.4]})
    for ax, col, label in zip(axes, (2, 0, 1), ('altitude (m)', 'x forward (m)',
                                                 'y left (m)')):
        ax.plot(t, xyz[:, col], color='tab:blue', lw=1.8)
        ax.set_ylabel(label)
        ax.grid(alpha=0.3)
    order = [2, 6, 4, 3, 9, 8]
    names = ['landed', 'taking off', 'hovering', 'flying', 'flip', 'landing']
    st_t = [max(0.0, s_t - t0) for s_t, _ in states] + [t[-1]]
    st_v = [order.index(s) if s in order else 0 for _, s in states]
    ax = axes[3]
    for i, v in enumerate(st_v):
        state = states[i][1]
        c = np.array(STATE_COLOURS.get(state, (128, 128, 128))) / 255.0
        ax.fill_between([st_t[i], st_t[i + 1]], v - 0.35, v + 0.35, color=c, step='pre')
    ax.set_yticks(range(len(names)))
    ax.set_yticklabels(names)
    ax.set_ylim(-0.6, len(names) - 0.4)
    ax.set_xlabel('time since the gesture session started (s)')
    ax.grid(alpha=0.3, axis='x')
    for ts, g in gestures:
        if g not in GESTURE_ACTIONS:
            continue
        x = ts - t0
        for a in axes:
            a.axvline(x, color='tab:red', ls='--', lw=1.0)
        axes[0].annotate('%s\n-> %s' % (g.split('_')[0], GESTURE_ACTIONS[g]), (x, 1.0),
                         xycoords=('data', 'axes fraction'), xytext=(3, -4),
                         textcoords='offset points', va='top', fontsize=10,
                         color='tab:red', fontweight='bold')
    axes[0].set_title('AR.Drone flown by a scripted hand: gestures (red) and what the '
                      'drone did', fontsize=11)
    axes[0].set_ylim(bottom=min(-0.05, float(xyz[:, 2].min()) - 0.05),
                     top=max(1.5, float(xyz[:, 2].max()) + 0.3))
    fig.tight_layout()
    fig.savefig(path, dpi=90)
    plt.close(fig)


# -- hands ------------------------------------------------------------------------------

def hand_label(hand):
    """The hand's pose as the recognizer reported it, for a caption."""
    if hand is None or not hand.present:
        return 'no hand'
    if hand.fist:
        return 'fist'
    if hand.thumb_up:
        return 'thumbs up'
    if hand.pinch:
        return 'pinch %.2f' % hand.pinch_value
    if hand.rock:
        return 'rock (set origin)'
    if hand.open:
        return 'open'
    return '%d fingers' % sum(bool(e) for e in hand.finger_extended)


def hand_inset(hand, title, size=(128, 118)):
    """The hand seen from above (Leap x right, fingers away from the user up): palm,
    fingers (folded ones faint), and the recognized pose."""
    w, h = size
    pic = Image.new('RGB', size, (245, 245, 240))
    draw = ImageDraw.Draw(pic)
    if hand is not None and hand.present:
        _draw_hand(draw, hand, w, h)
    # Caption strips drawn last, over any fingertip.
    draw.rectangle([0, 0, w, 15], fill=(225, 225, 215))
    draw.text((4, 1), title, font=_font(11), fill=(30, 30, 30))
    draw.rectangle([0, h - 19, w, h], fill=(225, 225, 215))
    draw.text((4, h - 18), hand_label(hand), font=_font(12), fill=(180, 40, 30))
    draw.rectangle([0, 0, w - 1, h - 1], outline=(60, 60, 60), width=2)
    return pic


def _draw_hand(draw, hand, w, h):
    px, pz = hand.palm_position.x, hand.palm_position.z
    scale = 0.3 * min(w, h) / 0.11            # ~11 cm from palm to fingertip
    cy = h / 2 + 14

    def to_px(x, z):
        return (w / 2 + (x - px) * scale, cy + (z - pz) * scale)

    palm = to_px(px, pz)
    d = hand.direction
    wrist = to_px(px - 0.05 * d.x, pz - 0.05 * d.z)
    draw.line([wrist, palm], fill=(120, 90, 70), width=7)
    for i, tip in enumerate(hand.finger_tips):
        extended = bool(hand.finger_extended[i])
        colour = (40, 40, 40) if extended else (175, 175, 175)
        end = to_px(tip.x, tip.z)
        draw.line([palm, end], fill=colour, width=4 if extended else 2)
        r = 4 if extended else 3
        draw.ellipse([end[0] - r, end[1] - r, end[0] + r, end[1] + r], fill=colour)
    fill = (200, 60, 50) if hand.fist else (60, 110, 200) if hand.pinch else (90, 170, 90)
    draw.ellipse([palm[0] - 8, palm[1] - 8, palm[0] + 8, palm[1] + 8], fill=fill,
                 outline=(30, 30, 30))


def arm_frame_with_insets(png_path, insets):
    """Paste the hand insets [(corner 'left' | 'right', PIL image)] on an arm snapshot."""
    pic = Image.open(png_path).convert('RGB')
    w, _ = pic.size
    for corner, inset in insets:
        x = 6 if corner == 'left' else w - inset.size[0] - 6
        pic.paste(inset, (x, 6))
    pic.save(png_path)
    return pic
