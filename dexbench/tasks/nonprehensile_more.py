"""More non-prehensile tasks: a ball up a wide slope, a board pivoted up against a wall,
a book tipped out of its shelf."""

from __future__ import annotations

import math
from typing import ClassVar

import mujoco
import numpy as np
import torch

from dexbench.assets import objects, ramps, shelves
from dexbench.assets.objects import ObjectInfo
from dexbench.embodiments.builder import TABLE_TOP_Z
from dexbench.envs.dex_env import DexEnv
from dexbench.envs.task_api import SceneView
from dexbench.tasks.catalog import register
from dexbench.tasks.nonprehensile import BALL_FRICTION
from dexbench.tasks.plans import GraspPlan, PathPushPlan, PivotPlan, PourPlan
from dexbench.tasks.predicates import dist, tilt_deg
from dexbench.tasks.templates import SPEED_NOTE, LiftTask, Placement, TabletopTask, yaw_quat

SLOPE_HALF_WIDTH = 0.20  # m: the goal's 0.30 m spread fits between the rails with the ball
GOAL_SPREAD = 0.15  # m either side of the slope's centre line (the paper's ~0.30 m)
GOAL_PAST_CREST = 0.04  # m onto the plateau: "near the top", where a ball stays (ours)
BALL_RADIUS = 0.03  # m
BALL_START = (0.12, 0.18)  # m before the slope's foot: room to steer in line with the goal
BALL_SPREAD = 0.10  # m either side of the centre line at the start (ours)
ONTO = 0.05  # m before and after the slope's foot: the ball is pushed straight uphill


def _slope_path(env: DexEnv) -> np.ndarray:
    """(N, 4, 3) from where the ball started across the table to `ONTO` before the
    slope's foot in line with the goal, then straight up the slope past the goal: a ball
    pushed at a slant up a slope (or onto it) runs off sideways."""
    task, view = env.task, env.view
    uphill = view.axis(*task.objects["ramp"].axes["uphill"]).cpu().numpy()
    foot = task.point(view, "ramp", "foot").cpu().numpy()
    start = view.initial_body_pos["sphere"].cpu().numpy()
    goal = view.goal[:, :3].cpu().numpy()
    below = goal - ((goal - foot)[:, :2] * uphill[:, :2]).sum(1, keepdims=True) * uphill
    below[:, 2] = start[:, 2]
    before = below - ONTO * uphill
    d = before - start
    d /= np.linalg.norm(d, axis=1, keepdims=True)
    return np.stack([start - 0.1 * d, before, below + ONTO * uphill, goal + 0.05 * uphill],
                    axis=1)


def _at_goal(env: DexEnv) -> np.ndarray:
    return env.task.success(env.view).cpu().numpy()


@register
class PushSphereUpSlope(TabletopTask):
    """The ramp of PushSmallSphereObstacleSlope, wider and without posts; the goal is on
    its plateau just past the crest, anywhere across it."""

    name = "PushSphereUpSlope"
    category = "nonprehensile"
    instruction = "Push the ball up the slope to the target near its top."
    description = ("Push a sphere up a sloped ramp and guide it to the commanded goal "
                   "region.")
    success_text = ("The sphere comes within 0.08 m of a goal near the top of the 15 deg "
                    "slope, sampled within about 0.30 m across the slope's width.")
    deviations = ("The ramp's pose (x 0.05..0.10, y -0.10..0.10, yaw -0.2..0.2), the ball's "
                  "start (12-18 cm before the foot, within 10 cm of the centre line) and the "
                  f"goal's place ({GOAL_PAST_CREST} m past the crest, on the plateau, where "
                  "a ball stays) are ours.",
                  f"The ball is hard plastic (friction {BALL_FRICTION}), as in "
                  "PushSmallSphereObstacleSlope.")
    episode_seconds = 20.0
    goal_marker = 0.02
    tolerance: ClassVar[float] = 0.08
    placements: ClassVar = {"ramp": Placement((0.05, 0.10), (-0.10, 0.10), (-0.2, 0.2))}
    expert = PathPushPlan("sphere", _slope_path, _at_goal)

    def make_objects(self, spec: mujoco.MjSpec) -> dict[str, ObjectInfo]:
        built = {"sphere": objects.add_sphere(spec, "sphere", radius=BALL_RADIUS,
                                              friction=(BALL_FRICTION, 0.005, 0.0001)),
                 "ramp": ramps.add_ramp(spec, "ramp", half_width=SLOPE_HALF_WIDTH)}
        spec.geom("sphere/geom").priority = 1  # its friction, not the larger one, holds
        return built

    def _ramp_world(self, ramp: np.ndarray, local: np.ndarray) -> np.ndarray:
        """(N, 3) world points of points `local` (N, 3) in the ramps' frames `ramp` (N, 7)."""
        yaw = 2 * np.arctan2(ramp[:, 6], ramp[:, 3])
        c, s = np.cos(yaw), np.sin(yaw)
        out = ramp[:, :3].copy()
        out[:, 0] += c * local[:, 0] - s * local[:, 1]
        out[:, 1] += s * local[:, 0] + c * local[:, 1]
        out[:, 2] += local[:, 2]
        return out

    def sample_reset(self, rngs: list[np.random.Generator]):
        sample = super().sample_reset(rngs)
        ramp = sample.mocap_poses["ramp"]
        points = self.objects["ramp"].points
        foot, crest = np.array(points["foot"][1]), np.array(points["target"][1])
        ball = np.array([foot - [r.uniform(*BALL_START), r.uniform(-BALL_SPREAD, BALL_SPREAD),
                                 0.0] for r in rngs])
        ball = self._ramp_world(ramp, ball)
        ball[:, 2] = TABLE_TOP_Z + BALL_RADIUS
        sample.free_poses["sphere/free"] = np.concatenate(
            [ball, np.tile([1.0, 0.0, 0.0, 0.0], (len(rngs), 1))], 1)
        goal = np.array([crest + [GOAL_PAST_CREST, r.uniform(-GOAL_SPREAD, GOAL_SPREAD),
                                  BALL_RADIUS] for r in rngs])
        sample.goal = self._ramp_world(ramp, goal)
        marker = np.zeros((len(rngs), 7))
        marker[:, :3], marker[:, 3] = sample.goal, 1.0
        sample.mocap_poses[self.markers["goal"].root] = marker
        return sample

    def success(self, view: SceneView) -> torch.Tensor:
        return dist(view.body_pos("sphere"), view.goal[:, :3]) <= self.tolerance

    def progress(self, view: SceneView) -> torch.Tensor:
        miss = dist(view.body_pos("sphere"), view.goal[:, :3])
        return (1.0 - (miss - self.tolerance) / 0.5).clamp(0.0, 1.0)


BOARD_GAP = (0.005, 0.04)  # m between the board's far end and the wall at reset (ours)
BOARD_SIDE = 0.05  # m either side of the wall's middle (ours)
BOARD_YAW = 0.1  # rad either way from square to the wall (ours)


def _board_up(env: DexEnv) -> np.ndarray:
    return env.task.success(env.view).cpu().numpy()


@register
class PivotLargeCuboidAgainstWall(LiftTask):
    """A 46 cm foam board lies flat on the table, its far end at a wall; standing it up
    on that end raises its centre by 21 cm."""

    name = "PivotLargeCuboidAgainstWall"
    category = "nonprehensile"
    instruction = "Stand the large board up on its end against the wall."
    description = ("Use the hand and wall support to pivot a large thin cuboid into an "
                   "upright pose.")
    success_text = ("The cuboid is lifted at least 0.20 m above its reset height and tilted "
                    "to within 20 deg of vertical.")
    deviations = (SPEED_NOTE,
                  "The board's size and mass (46 x 20 x 4 cm, 0.5 kg), the wall's pose (x "
                  "0.28..0.32, y -0.05..0.05, yaw -0.15..0.15) and the board's (its far end "
                  "0.5-4 cm from the wall, within 5 cm of its middle, within 0.1 rad of "
                  "square to it) are ours; \"vertical\" is the board's long axis, either end "
                  "up.")
    episode_seconds = 20.0
    lifted = "board"
    lift_threshold = 0.20
    max_tilt = 20.0
    placements: ClassVar = {"wall": Placement((0.28, 0.32), (-0.05, 0.05), (-0.15, 0.15))}
    expert = PivotPlan("board", "near_edge", "far_edge", _board_up)

    def make_objects(self, spec: mujoco.MjSpec) -> dict[str, ObjectInfo]:
        return {"board": shelves.add_board(spec, "board"), "wall": shelves.add_wall(spec, "wall")}

    def _upright(self, view: SceneView) -> torch.Tensor:
        """The board's long axis within `max_tilt` of vertical, whichever end is up: it
        is the same board either way."""
        tilt = tilt_deg(view.axis(*self.objects["board"].axes["up"]))
        return torch.minimum(tilt, 180.0 - tilt) <= self.max_tilt

    def sample_reset(self, rngs: list[np.random.Generator]):
        sample = super().sample_reset(rngs)
        wall = sample.mocap_poses["wall"]
        face_x, _, _ = self.objects["wall"].points["face"][1]
        half_len = -self.objects["board"].points["near_edge"][1][0]
        poses = []
        for r, w in zip(rngs, wall, strict=True):
            yaw = 2 * math.atan2(w[6], w[3])
            along = face_x - r.uniform(*BOARD_GAP) - half_len
            side = r.uniform(-BOARD_SIDE, BOARD_SIDE)
            turn = yaw + r.uniform(-BOARD_YAW, BOARD_YAW)
            # The board's far end is `along` from the wall's centre, square to its face.
            x = w[0] + math.cos(yaw) * along - math.sin(yaw) * side
            y = w[1] + math.sin(yaw) * along + math.cos(yaw) * side
            poses.append([x, y, TABLE_TOP_Z + self.objects["board"].rest_height,
                          *yaw_quat(turn)])
        sample.free_poses["board/free"] = np.array(poses)
        return sample


BOOK_OUT, BOOK_UP = 0.18, 0.05  # m: the goal from the slot, out of the shelf and up
BOOK_TILT = math.radians(65.0)  # its top tipped out of the shelf, downwards
BOOK_GAP = 0.004  # m between neighbouring books, and between them and the shelf's sides
NEIGHBOUR_HALF = (0.075, 0.015, 0.08)  # m: the books either side, 6 cm lower (ours)


def _book_goal(env: DexEnv) -> np.ndarray:
    return env.view.goal[:, :3].cpu().numpy().copy()  # the carry edits what it is given


@register
class TakeBookOffShelf(TabletopTask):
    """One book between two lower ones in an open-topped slot; the goal pose is the
    book's reset pose moved out and up and turned about the shelf's width axis."""

    name = "TakeBookOffShelf"
    category = "nonprehensile"
    instruction = "Take the blue book out of the shelf and hold it tipped forwards."
    description = ("Extract a target book from a shelf and move it to the commanded pose.")
    success_text = ("The book's position is within 0.05 m and its orientation within about "
                    "26 deg of a goal that sits 0.18 m out and 0.05 m up from the shelf slot, "
                    "tilted downward by 65 deg.")
    deviations = ("The shelf's pose (x 0.12..0.18, y -0.10..0.10, yaw -0.2..0.2), the books "
                  "(15 x 3 x 22 cm, 0.35 kg, between two 16 cm tall ones in a slot just "
                  "wide enough, with 12 cm walls and an open top) and \"downward\" (the "
                  "book's top towards the hand) are ours; the orientation bound is 0.45 rad "
                  "(25.8 deg).",)
    episode_seconds = 20.0
    goal_marker = 0.02
    tolerance: ClassVar[float] = 0.05
    max_angle: ClassVar[float] = 0.45
    placements: ClassVar = {"shelf": Placement((0.12, 0.18), (-0.10, 0.10), (-0.2, 0.2))}
    expert = PourPlan(GraspPlan("book", "top", shift=(0.0, 0.0, -0.02), yaw="body",
                                target=_book_goal, commanded_hand=True),
                      tilt=BOOK_TILT, clearance=0.03, turn_rate=0.8, about=(0.0, 1.0, 0.0),
                      squeeze=1.5)

    def make_objects(self, spec: mujoco.MjSpec) -> dict[str, ObjectInfo]:
        return {"book": shelves.add_book(spec, "book"),
                "shelf": shelves.add_shelf(spec, "shelf"),
                **{f"neighbour{k}": shelves.add_book(spec, f"neighbour{k}", NEIGHBOUR_HALF,
                                                     rgba=shelves.NEIGHBOUR)
                   for k in range(2)}}

    def sample_reset(self, rngs: list[np.random.Generator]):
        sample = super().sample_reset(rngs)
        shelf = sample.mocap_poses["shelf"]
        yaw = 2 * np.arctan2(shelf[:, 6], shelf[:, 3])
        across = np.stack([-np.sin(yaw), np.cos(yaw), np.zeros_like(yaw)], 1)
        out = np.stack([-np.cos(yaw), -np.sin(yaw), np.zeros_like(yaw)], 1)
        slot = shelf[:, :3].copy()  # the shelf's `slot` point is its origin
        book_half = self.objects["book"].rest_height
        step = 2 * NEIGHBOUR_HALF[1] + BOOK_GAP  # centre to centre: both 3 cm thick
        poses = {"book": slot + [0.0, 0.0, book_half],
                 "neighbour0": slot + step * across + [0.0, 0.0, NEIGHBOUR_HALF[2]],
                 "neighbour1": slot - step * across + [0.0, 0.0, NEIGHBOUR_HALF[2]]}
        for name, pos in poses.items():
            sample.free_poses[f"{name}/free"] = np.concatenate([pos, shelf[:, 3:]], 1)
        # The goal: out and up from the slot, turned about the shelf's width axis (its
        # y) so that the book's top tips out of the shelf.
        goal = np.zeros((len(rngs), 7))
        goal[:, :3] = poses["book"] + BOOK_OUT * out + [0.0, 0.0, BOOK_UP]
        tip = np.array([math.cos(-BOOK_TILT / 2), 0.0, math.sin(-BOOK_TILT / 2), 0.0])
        for i in range(len(rngs)):
            mujoco.mju_mulQuat(goal[i, 3:], shelf[i, 3:], tip)
        sample.goal = goal
        marker = np.zeros((len(rngs), 7))
        marker[:, :3], marker[:, 3] = goal[:, :3], 1.0
        sample.mocap_poses[self.markers["goal"].root] = marker
        return sample

    def angle_off(self, view: SceneView) -> torch.Tensor:
        """(N,) angle (rad) of the turn from the goal orientation to the book's."""
        dot = (view.body_quat("book") * view.goal[:, 3:7]).sum(dim=1).abs().clamp(max=1.0)
        return 2 * torch.arccos(dot)

    def success(self, view: SceneView) -> torch.Tensor:
        near = dist(view.body_pos("book"), view.goal[:, :3]) <= self.tolerance
        return near & (self.angle_off(view) <= self.max_angle)

    def progress(self, view: SceneView) -> torch.Tensor:
        miss = dist(view.body_pos("book"), view.goal[:, :3]) / 0.3
        turn = self.angle_off(view) / math.pi
        return (1.0 - (miss + turn) / 2).clamp(0.0, 1.0)
