"""Can an arm put its hand where the task's expert needs it? The one feasibility test of
the cross-embodiment matrix, applied to every (task, embodiment) cell alike.

Experts think in palm poses; the mount only realises them (`experts/adapter.py` solves
the mount's IK every step). On the floating mount (a free 6-DoF wrist) the hand goes
where the plan asks, so the palm trajectories of the floating hand over the first
evaluation episodes (the very reset samples the matrix evaluates) are the plan's pose
demand for that hand. For an arm carrying the same hand, every recorded palm pose is
solved with the arm's damped least-squares IK (the adapter's solver, joint limits
enforced), warm-started along the trajectory from the arm's home pose as the adapter
does, and retried from home when it misses. Each pose gets two residuals: the full
pose's (position m, orientation rad), and the reach: the position residual with the
orientation left free (solved from the full pose's solution, then from home). Reach,
joint limits and the bimanual arms' placement count (each arm placed for the task's
`workspace`, as its scene places it); collisions of arm links do not (the test is
kinematic).

Only the probe episodes the floating expert solves count: a failed episode's path
(retries, a dropped object chased) is not what the plan needs. The verdict (`verdict`)
is on reach alone: an episode is reachable when the 95th percentile of its poses' reach
residuals is <= `POS_TOL` (the percentile ignores a few transient poses, e.g. a
contact's jolt, not a grasp or a carry, which last far longer); the cell is infeasible
when fewer than `MIN_REACHABLE` of those episodes are reachable: then over most of the
reset region the arm cannot bring the palm where the hand must act, in any orientation,
and no script could reach the matrix's bar of 0.5 success. A pose the arm reaches but
cannot orient as the plan does (wrist limits: a full-pose residual beyond `POS_TOL` or
`ROT_TOL`) leaves the cell feasible, since the expert may take another orientation (a fix
for the plan kinds), and marks it pose-limited (`pose_limited`), a diagnostic for those
fixes. Floating cells are the reference, feasible by construction; a cell whose
reference solved no probe episode is not measured (feasible: the failure is then the
expert's). Reachable and unreachable positions differ by orders of magnitude (~1e-4 m
against tens of cm), so the verdict does not hang on the tolerance's exact value. The
measurements are stored per cell (`feasibility.json`), so the thresholds can change
without measuring again.
"""

from __future__ import annotations

import functools
from dataclasses import dataclass
from typing import Any

import mujoco
import numpy as np

from dexbench.embodiments.builder import DEFAULT_WORKSPACE, parse_embodiment, robot_at_home
from dexbench.embodiments.ik import POS_TOL, ROT_TOL, pose_residual, solve_site_pose
from dexbench.envs.dex_env import DexEnv
from dexbench.eval.plan import TaskPlan
from dexbench.eval.records import EpisodeRecord
from dexbench.eval.runner import run_episodes
from dexbench.eval.session import EvalSpec, build_env, build_policy

QUANTILE = 95.0  # percentile of an episode's residuals that decides it
MIN_REACHABLE = 0.5  # fraction of probe episodes that must be reachable
IK_ITERATIONS = 100  # per pose, warm-started from the previous pose's solution
IK_RETRY_ITERATIONS = 300  # from home for a missed pose, and for its reach
STRIDE = 2  # every STRIDE-th control step's pose is solved (consecutive ones are close)
RESIDUALS = ("pos", "rot", "reach")  # full pose (m, rad), reach with orientation free (m)


def reference_embodiment(embodiment: str) -> str:
    """The floating embodiment with `embodiment`'s hand and arity: whose palm paths are
    the plan's demand."""
    name = parse_embodiment(embodiment)
    return f"{'bimanual_' if name.bimanual else ''}floating_{name.hand}"


class _PalmRecorder:
    """`env` for `run_episodes`, recording every side's palm pose after each reset and
    step, per evaluation episode (the key's last entry)."""

    def __init__(self, env: DexEnv) -> None:
        self._env = env
        model = env.scene.model
        self._sites = [model.site(s.palm_site).id for s in env.embodiment.sides.values()]
        self._slot_episode: dict[int, int] = {}
        self.paths: dict[int, list[tuple[np.ndarray, np.ndarray]]] = {}

    def __getattr__(self, name: str) -> Any:
        return getattr(self._env, name)

    def _poses(self) -> tuple[np.ndarray, np.ndarray]:
        sim = self._env.sim
        pos = sim.field("site_xpos")[:, self._sites].cpu().numpy()
        rot = sim.field("site_xmat")[:, self._sites].cpu().numpy()
        return pos, rot.reshape(*rot.shape[:2], 3, 3)

    def _record(self) -> None:
        pos, rot = self._poses()
        for slot, episode in self._slot_episode.items():
            self.paths[episode].append((pos[slot].copy(), rot[slot].copy()))

    def reset_to(self, env_ids, keys) -> Any:
        obs = self._env.reset_to(env_ids, keys)
        for slot, key in zip(np.asarray(env_ids), np.asarray(keys), strict=True):
            self._slot_episode[int(slot)] = int(key[2])
            self.paths[int(key[2])] = []
        pos, rot = self._poses()
        for slot in np.asarray(env_ids):
            self.paths[self._slot_episode[int(slot)]].append((pos[slot].copy(),
                                                              rot[slot].copy()))
        return obs

    def step(self, actions, observe=None) -> Any:
        out = self._env.step(actions, observe=observe)
        self._record()
        return out


@dataclass(frozen=True)
class PalmPath:
    """One probe episode of the reference: every side's palm pose from reset to end."""

    pos: np.ndarray  # (T, sides, 3)
    rot: np.ndarray  # (T, sides, 3, 3)
    success: bool


def record_palm_paths(spec: EvalSpec, plan: TaskPlan, episodes: int) -> list[PalmPath]:
    """The palm paths of `plan` (a floating embodiment) over evaluation episodes
    0..episodes-1, each up to its end."""
    env = build_env(spec, plan, episodes)
    policy = build_policy(spec, plan, env)
    recorder = _PalmRecorder(env)
    ends: dict[int, EpisodeRecord] = {}
    run_episodes(recorder, policy, range(episodes), spec.seed,  # type: ignore[arg-type]
                 lambda rec: ends.__setitem__(rec.episode, rec))
    out = []
    for episode in range(episodes):
        path = recorder.paths[episode][:ends[episode].steps + 1]
        out.append(PalmPath(np.stack([p for p, _ in path]), np.stack([r for _, r in path]),
                            ends[episode].success))
    return out


@dataclass(frozen=True)
class _Robot:
    """A robot-only model of an embodiment at home, for IK."""

    model: mujoco.MjModel
    home: np.ndarray  # qpos
    sides: tuple[tuple[str, tuple[str, ...]], ...]  # (palm site, mount joints) per side


@functools.cache
def _robot(embodiment: str, workspace: tuple[float, float, float]) -> _Robot:
    """Placed for the task's workspace, as the task's scene places it."""
    model, data, plan = robot_at_home(embodiment, workspace)
    sides = tuple((s.palm_site, s.mount_joints) for s in plan.sides.values())
    return _Robot(model, data.qpos.copy(), sides)


def ik_residuals(embodiment: str, positions: np.ndarray, rotations: np.ndarray,
                 workspace: tuple[float, float, float] = DEFAULT_WORKSPACE) -> np.ndarray:
    """(T, sides, 3) residuals of `embodiment`'s mounts (placed for a task's `workspace`)
    reaching palm poses `positions` (T, sides, 3) and `rotations` (T, sides, 3, 3), solved
    along them from home: the full pose's position (m) and orientation (rad), and the
    reach (m, orientation free)."""
    robot = _robot(embodiment, tuple(workspace))
    model = robot.model
    data = mujoco.MjData(model)
    out = np.zeros((len(positions), len(robot.sides), 3))

    def cost(res: tuple[float, float]) -> float:
        return res[0] / POS_TOL + res[1] / ROT_TOL

    for s, (site, joints) in enumerate(robot.sides):
        sid = model.site(site).id
        qadr = np.array([model.joint(j).qposadr[0] for j in joints])
        warm = robot.home[qadr].copy()
        for t in range(len(positions)):
            pos, rot = positions[t, s], rotations[t, s]
            data.qpos[:] = robot.home
            data.qpos[qadr] = warm
            q, _ = solve_site_pose(model, data, site, list(joints), pos, rot,
                                   iterations=IK_ITERATIONS)
            res = pose_residual(model, data, sid, pos, rot)
            if res[0] > POS_TOL or res[1] > ROT_TOL:
                data.qpos[:] = robot.home
                q_home, _ = solve_site_pose(model, data, site, list(joints), pos, rot,
                                            iterations=IK_RETRY_ITERATIONS)
                retry = pose_residual(model, data, sid, pos, rot)
                if cost(retry) < cost(res):
                    q, res = q_home, retry
            reach = res[0]
            for start in (q, robot.home[qadr]):
                if reach <= POS_TOL:
                    break
                data.qpos[qadr] = start
                solve_site_pose(model, data, site, list(joints), pos, None,
                                iterations=IK_RETRY_ITERATIONS)
                reach = min(reach, pose_residual(model, data, sid, pos, rot)[0])
            warm = q
            out[t, s] = (*res, reach)
    return out


def measure(embodiment: str, paths: list[PalmPath],
            workspace: tuple[float, float, float] = DEFAULT_WORKSPACE) -> dict:
    """`embodiment`'s reach of the reference palm paths on a task working around
    `workspace` (`Task.workspace`), as `feasibility.json` stores it: per probe episode
    whether the reference solved it, and the `QUANTILE` percentile and maximum of each
    residual (over both hands for a bimanual embodiment)."""
    episodes = []
    for path in paths:
        res = ik_residuals(embodiment, path.pos[::STRIDE], path.rot[::STRIDE],
                           workspace).reshape(-1, 3)
        q, top = np.percentile(res, QUANTILE, axis=0), res.max(axis=0)
        episodes.append({"reference_success": path.success, "poses": len(res),
                         **{f"{name}_q": round(float(v), 5)
                            for name, v in zip(RESIDUALS, q, strict=True)},
                         **{f"{name}_max": round(float(v), 5)
                            for name, v in zip(RESIDUALS, top, strict=True)}})
    return {"embodiment": embodiment, "reference": reference_embodiment(embodiment),
            "quantile": QUANTILE, "episodes": episodes}


def reference_measurement(embodiment: str) -> dict:
    """A floating cell's record: the reference itself, nothing to measure."""
    return {"embodiment": embodiment, "reference": embodiment, "quantile": QUANTILE,
            "episodes": []}


def _solved(measurement: dict) -> list[dict]:
    """The probe episodes that count: those the reference solved."""
    return [e for e in measurement["episodes"] if e["reference_success"]]


def verdict(measurement: dict | None) -> tuple[bool, str]:
    """(feasible, reason) of a cell from its stored measurement; a cell not measured
    (None) counts as feasible."""
    if measurement is None:
        return True, "not measured"
    if measurement["reference"] == measurement["embodiment"]:
        return True, "reference mount"
    episodes = _solved(measurement)
    if not episodes:
        return True, (f"not measured: the reference {measurement['reference']} solved none "
                      f"of {len(measurement['episodes'])} probe episodes")
    reachable = [e["reach_q"] <= POS_TOL for e in episodes]
    median = {k: float(np.median([e[f"{k}_q"] for e in episodes])) for k in RESIDUALS}
    why = (f"{sum(reachable)}/{len(reachable)} solved probe episodes within reach "
           f"(median p{QUANTILE:.0f} reach residual {100 * median['reach']:.1f} cm, "
           f"tolerance {100 * POS_TOL:.0f} cm; full pose {100 * median['pos']:.1f} cm / "
           f"{median['rot']:.2f} rad)")
    return sum(reachable) >= MIN_REACHABLE * len(reachable), why


def pose_limited(measurement: dict | None) -> bool:
    """Whether the arm misses the plan's exact poses (beyond `POS_TOL` or `ROT_TOL` at
    the percentile) in at least half of the solved probe episodes: the diagnostic for
    plan and mount fixes, not a verdict."""
    if measurement is None or measurement["reference"] == measurement["embodiment"]:
        return False
    episodes = _solved(measurement)
    missed = [e["pos_q"] > POS_TOL or e["rot_q"] > ROT_TOL for e in episodes]
    return bool(episodes) and 2 * sum(missed) >= len(missed)
