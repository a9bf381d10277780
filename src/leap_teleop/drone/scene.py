"""The drone's world, as pictures see it: a gridded field on a wide ground, and landmarks.

Visual shapes only (no collision, no cost to the physics): the same scene is built in the
physics client (chase views) and in the camera renderer's own client, so the drone's
cameras and the pictures show motion against fixed references. Grid lines every metre
(bolder every 5 m) with a 0.5 m checker, coloured pillars round the start and a
landing pad with an arrow pointing +x at the start.
"""
import atexit
import math
import os
import tempfile

import numpy as np
import pybullet as pb

FIELD_HALF = 15.0             # m, half side of the gridded field
GROUND_HALF = 150.0           # m, half side of the plain ground under it (to the horizon)
TEXTURE_PX = 2048             # texture side, px (~68 px per metre of field)
# (x, y, radius, height, rgba): pillars at 5-9 m in every direction, none on the way of
# the demo's short flights (which stay within ~3 m of the start).
PILLARS = (
    (7.0, 0.0, 0.3, 2.5, (0.85, 0.15, 0.1, 1)), (5.0, 4.0, 0.25, 1.8, (0.1, 0.3, 0.85, 1)),
    (0.0, 6.0, 0.3, 2.2, (0.95, 0.75, 0.1, 1)), (-5.0, 5.0, 0.25, 1.6, (0.6, 0.1, 0.7, 1)),
    (-7.0, 0.0, 0.3, 2.5, (0.1, 0.65, 0.3, 1)), (-5.0, -5.0, 0.25, 1.8, (0.95, 0.45, 0.1, 1)),
    (0.0, -6.0, 0.3, 2.2, (0.1, 0.7, 0.8, 1)), (5.0, -4.0, 0.25, 1.6, (0.9, 0.3, 0.6, 1)),
    (9.0, 6.0, 0.4, 3.0, (0.4, 0.4, 0.4, 1)), (9.0, -6.0, 0.4, 3.0, (0.4, 0.4, 0.4, 1)),
)
# (x, y, half extents, rgba): crates on the ground, seen by the bottom camera too.
CRATES = (
    (3.0, 1.5, (0.25, 0.25, 0.2), (0.7, 0.5, 0.25, 1)),
    (2.0, -2.0, (0.3, 0.2, 0.15), (0.55, 0.35, 0.2, 1)),
    (-2.5, 1.0, (0.2, 0.3, 0.25), (0.75, 0.55, 0.3, 1)),
)

_texture_file = None
_solid_file = None
GROUND_RGB = (104, 128, 92)


def field_texture_path():
    """The field's texture as a PNG (written once per process): grid and checker."""
    global _texture_file
    if _texture_file is not None and os.path.exists(_texture_file):
        return _texture_file
    from PIL import Image, ImageDraw
    n = TEXTURE_PX
    px_per_m = n / (2 * FIELD_HALF)
    u = (np.arange(n) + 0.5) / px_per_m            # metres from the field's edge
    checker = ((np.floor(u * 2)[None, :] + np.floor(u * 2)[:, None]) % 2).astype(bool)
    img = np.empty((n, n, 3), np.uint8)
    img[...] = (112, 150, 96)
    img[checker] = (128, 166, 110)
    pic = Image.fromarray(img)
    draw = ImageDraw.Draw(pic)
    for k in range(int(2 * FIELD_HALF) + 1):
        x = int(round(k * px_per_m))
        width, colour = (5, (245, 245, 235)) if k % 5 == 0 else (2, (215, 225, 205))
        draw.line([(x, 0), (x, n)], fill=colour, width=width)
        draw.line([(0, x), (n, x)], fill=colour, width=width)
    # Landing pad at the field's centre (the start): a disc and an arrow along +x.
    c, r = n / 2.0, 0.6 * px_per_m
    draw.ellipse([c - r, c - r, c + r, c + r], fill=(60, 60, 70), outline=(250, 250, 250),
                 width=4)
    a = 0.45 * px_per_m
    # Texture rows run along -y of the world (image v grows with -y), columns along +x.
    draw.polygon([(c + a, c), (c - a * 0.5, c - a * 0.6), (c - a * 0.2, c),
                  (c - a * 0.5, c + a * 0.6)], fill=(250, 200, 40))
    fd, path = tempfile.mkstemp(prefix='leap_teleop_field_', suffix='.png')
    os.close(fd)
    pic.save(path)
    atexit.register(_remove, path)
    _texture_file = path
    return path


def _remove(path):
    try:
        os.unlink(path)
    except OSError:
        pass


def _quad(client, half, z, uv_repeat):
    """A horizontal square, texture u along +x and v along -y (image rows run south)."""
    verts = [(-half, half, z), (half, half, z), (half, -half, z), (-half, -half, z)]
    uvs = [(0, 0), (uv_repeat, 0), (uv_repeat, uv_repeat), (0, uv_repeat)]
    vis = pb.createVisualShape(pb.GEOM_MESH, vertices=verts, indices=[0, 2, 1, 0, 3, 2],
                               uvs=uvs, normals=[(0, 0, 1)] * 4, physicsClientId=client)
    return pb.createMultiBody(0, -1, vis, (0, 0, 0), physicsClientId=client)


def _solid_texture_path():
    global _solid_file
    if _solid_file is None or not os.path.exists(_solid_file):
        from PIL import Image
        fd, _solid_file = tempfile.mkstemp(prefix='leap_teleop_ground_', suffix='.png')
        os.close(fd)
        Image.new('RGB', (64, 64), GROUND_RGB).save(_solid_file)
        atexit.register(_remove, _solid_file)
    return _solid_file


def add_bodies(client):
    """Add the scene's visual bodies to a PyBullet client; returns their ids."""
    ids = []

    def visual(shape, xyz, **kw):
        vis = pb.createVisualShape(shape, physicsClientId=client, **kw)
        ids.append(pb.createMultiBody(0, -1, vis, xyz, physicsClientId=client))
        return ids[-1]

    # Flat quads with explicit texture coordinates (a box's are not one texture per face).
    ground = _quad(client, GROUND_HALF, -0.01, uv_repeat=1.0)
    field = _quad(client, FIELD_HALF, 0.0, uv_repeat=1.0)
    ids += [ground, field]
    pb.changeVisualShape(ground, -1, textureUniqueId=pb.loadTexture(
        _solid_texture_path(), physicsClientId=client), physicsClientId=client)
    pb.changeVisualShape(field, -1, textureUniqueId=pb.loadTexture(
        field_texture_path(), physicsClientId=client), physicsClientId=client)
    for x, y, radius, height, rgba in PILLARS:
        visual(pb.GEOM_CYLINDER, (x, y, height / 2), radius=radius, length=height,
               rgbaColor=rgba)
        visual(pb.GEOM_SPHERE, (x, y, height), radius=radius * 1.2, rgbaColor=(1, 1, 1, 1))
    for x, y, half, rgba in CRATES:
        visual(pb.GEOM_BOX, (x, y, half[2]), halfExtents=half, rgbaColor=rgba)
    return ids


def body_visual(client, arm):
    """The drone's look in `client`: body, four rotor discs at `arm` m from the centre and a
    red nose marker, as one visual shape array (also drawn by the snapshot renderer)."""
    a = arm / math.sqrt(2.0)
    return pb.createVisualShapeArray(
        shapeTypes=[pb.GEOM_BOX] + [pb.GEOM_CYLINDER] * 4 + [pb.GEOM_BOX],
        halfExtents=[(0.09, 0.04, 0.03)] + [(0, 0, 0)] * 4 + [(0.03, 0.02, 0.02)],
        radii=[0] + [0.1] * 4 + [0], lengths=[0] + [0.01] * 4 + [0],
        rgbaColors=[(0.15, 0.15, 0.15, 1)] + [(0.9, 0.9, 0.9, 0.8)] * 4 + [(0.9, 0.1, 0.1, 1)],
        visualFramePositions=[(0, 0, 0), (a, a, 0.02), (a, -a, 0.02), (-a, -a, 0.02),
                              (-a, a, 0.02), (0.12, 0, 0.02)],
        physicsClientId=client)
