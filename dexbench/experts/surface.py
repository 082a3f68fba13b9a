"""Points on a body's collision geoms among which its farthest point in any direction
lies: where a finger actually ends, rather than its fingertip site (the distal link's
centre of mass, 1.5-3 cm short of its end, by hand)."""

from __future__ import annotations

import itertools

import mujoco
import numpy as np

from dexbench.embodiments.builder import set_joints
from dexbench.envs.dex_env import DexEnv
from dexbench.experts.adapter import collidable, site_pose, subtree

_G = mujoco.mjtGeom


def _sphere_directions(count: int = 128) -> np.ndarray:
    """(count, 3) unit vectors spread evenly over the sphere (a Fibonacci lattice): for
    128, the farthest of them along any direction is within 14 degrees of it (a round
    geom's extent is at most 3% of its radius short: 0.3 mm on a 1 cm fingertip)."""
    k = np.arange(count) + 0.5
    z = 1.0 - 2.0 * k / count
    ring = np.sqrt(1.0 - z**2)
    angle = np.pi * (1.0 + 5**0.5) * k
    return np.column_stack([ring * np.cos(angle), ring * np.sin(angle), z])


def geom_extremes(model: mujoco.MjModel, geom: int) -> np.ndarray:
    """(K, 3) points in the geom's frame whose convex hull is the geom (meshes: their
    vertices, boxes: corners; round shapes: a dense sample of their surface)."""
    kind, size = model.geom_type[geom], model.geom_size[geom]
    unit = _sphere_directions()
    if kind == _G.mjGEOM_MESH:
        mesh = model.geom_dataid[geom]
        start = model.mesh_vertadr[mesh]
        return model.mesh_vert[start:start + model.mesh_vertnum[mesh]].astype(float)
    if kind == _G.mjGEOM_BOX:
        signs = np.array([[x, y, z] for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)])
        return signs * size
    if kind == _G.mjGEOM_SPHERE:
        return size[0] * unit
    if kind == _G.mjGEOM_CAPSULE:
        return size[0] * unit + np.sign(unit[:, 2:]) * [0.0, 0.0, size[1]]
    if kind == _G.mjGEOM_ELLIPSOID:
        return unit * size
    if kind == _G.mjGEOM_CYLINDER:
        ring = unit[:, :2] / np.linalg.norm(unit[:, :2], axis=1, keepdims=True)
        rim = np.column_stack([size[0] * ring, np.zeros(len(ring))])
        return np.concatenate([rim + [0, 0, size[1]], rim - [0, 0, size[1]]])
    raise ValueError(f"geom {model.geom(geom).name}: type {kind} has no extreme points here")


def body_surface(model: mujoco.MjModel, body: int) -> np.ndarray:
    """(K, 3) extreme points of a body's collision geoms, in the body's frame."""
    points = []
    for g in collidable(model, body):
        rot = np.zeros(9)
        mujoco.mju_quat2Mat(rot, model.geom_quat[g])
        points.append(model.geom_pos[g] + geom_extremes(model, g) @ rot.reshape(3, 3).T)
    return np.concatenate(points)


class FingerEnds:
    """The extreme points of the bodies carrying `sites` (fingertips), measured once in
    their bodies' frames; called, they are given in the palm site's frame of every env
    (N, K, 3): where the fingers end, whatever the palm's pose."""

    def __init__(self, env: DexEnv, palm: int, sites: list[int]) -> None:
        model = env.scene.model
        self.env, self.palm = env, palm
        self.bodies = [int(model.site_bodyid[s]) for s in sites]
        self.local = [body_surface(model, b) for b in self.bodies]
        self.count = sum(len(points) for points in self.local)
        rows = np.cumsum([0] + [len(points) for points in self.local])
        self.rows = list(itertools.pairwise(rows))  # each body's rows in what a call gives

    def __call__(self) -> np.ndarray:
        pos, rot = site_pose(self.env, self.palm)
        xpos = self.env.sim.field("xpos").cpu().numpy()[:, self.bodies]
        xquat = self.env.sim.field("xquat").cpu().numpy()[:, self.bodies]
        out = []
        for k, points in enumerate(self.local):
            mats = np.zeros((len(pos), 9))
            for i in range(len(pos)):
                mujoco.mju_quat2Mat(mats[i], xquat[i, k])
            world = xpos[:, k, None] + np.einsum("nij,kj->nki", mats.reshape(-1, 3, 3), points)
            out.append(np.einsum("nji,nkj->nki", rot, world - pos[:, None]))
        return np.concatenate(out, axis=1)


def front_aim(site: np.ndarray, points: np.ndarray, level: np.ndarray, push: np.ndarray,
              radius: float) -> np.ndarray:
    """(3,) the point a pushing finger steers: at its tip `site`'s height, but along and
    across the horizontal `push` where its front (the farthest of its extreme `points`
    along it, among those at `level`, a mask) is, `radius` back; `site` where no point is
    at level. A tip site is its link's centre of mass, not where the finger touches (LEAP's
    lies 2-3 cm behind its front). All in one frame with z up."""
    if not level.any():
        return site
    front = points[level][np.argmax(points[level] @ push)]
    aim = site.copy()
    aim[:2] = (front - radius * push)[:2]
    return aim


def mount_part(env: DexEnv, side: str) -> np.ndarray:
    """(K, 3) extreme points of the arm's links that move as one with the hand (the
    FR3's link 7 and flange, behind the palm of its flat-mounted hand), in the palm
    site's frame at home; (0, 3) on a floating mount and for a hand with a wrist of its
    own (the Shadow hand's: those links then stand off the palm as the wrist bends). A
    grasp planned from the hand's own geometry alone may put them into the table."""
    model, layout = env.scene.model, env.embodiment.sides[side]
    root = model.body(layout.hand_root).id
    site = model.site(layout.palm_site).id
    wrist = model.body_weldid[model.site_bodyid[site]] != model.body_weldid[root]
    if env.embodiment.mount == "floating" or wrist:
        return np.zeros((0, 3))
    data = mujoco.MjData(model)
    set_joints(model, data, layout.home_qpos)
    mujoco.mj_kinematics(model, data)
    hand = subtree(model, root)
    pos, rot = data.site_xpos[site], data.site_xmat[site].reshape(3, 3)
    out = [np.zeros((0, 3))]
    for b in range(model.nbody):
        if b in hand or model.body_weldid[b] != model.body_weldid[root] or not collidable(model, b):
            continue
        world = data.xpos[b] + body_surface(model, b) @ data.xmat[b].reshape(3, 3).T
        out.append((world - pos) @ rot)
    return np.concatenate(out)
