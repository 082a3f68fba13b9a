"""Cross-embodiment transfer as a measurement: one hand's expert motion as human input.

The scripted expert runs on a source embodiment (floating Shadow); each successful
episode's commanded hand (palm pose and fingertip sites of the robot posed at the
expert's targets, `commanded_pose`), step by step, becomes a keypoint take
(`robot_as_human`: the hand as a human's, `RetargetSpec.scale` times smaller). Each take
is then retargeted to every target hand and played open loop in the same episode (same
reset): per hand, the retargeting error (fingertip sites against their targets, in the
palm frame, every frame) and the share of takes that still solve the task.
"""

from __future__ import annotations

import pathlib
from dataclasses import dataclass

import mujoco
import numpy as np
import torch

from dexbench.envs.dex_env import DexEnv
from dexbench.experts import make_expert
from dexbench.tasks.registry import make_env
from dexbench.teleop.player import TeleopPlayer
from dexbench.teleop.retarget import Retargeter, robot_as_human
from dexbench.teleop.sources import FileSource, write_keypoints

POST_SUCCESS_STEPS = 10  # control steps a take goes on after success first holds


def commanded_pose(retargeter: Retargeter, action: np.ndarray) -> mujoco.MjData:
    """The robot-only model posed at the action's targets (what the expert commands, as
    a human's hand pose is what they intend: fingers closing into a held object, not
    stopped at its surface). A tendon actuator's target (the Shadow hand's coupled
    distal joints) is shared evenly by its joints."""
    model, data = retargeter.model, retargeter.data
    for i, target in enumerate(action):
        if model.actuator_trntype[i] == mujoco.mjtTrn.mjTRN_JOINT:
            data.qpos[model.jnt_qposadr[model.actuator_trnid[i, 0]]] = target
        elif model.actuator_trntype[i] == mujoco.mjtTrn.mjTRN_TENDON:
            tendon = model.actuator_trnid[i, 0]
            adr, num = model.tendon_adr[tendon], model.tendon_num[tendon]
            coef = model.wrap_prm[adr:adr + num]
            for w in range(adr, adr + num):
                data.qpos[model.jnt_qposadr[model.wrap_objid[w]]] = target / coef.sum()
    mujoco.mj_kinematics(model, data)
    return data


def _hand_frames(env: DexEnv, retargeter: Retargeter,
                 action: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(S, 21, 3) keypoints and (S, 4, 4) wrist poses of the commanded hands, as human
    input."""
    model = retargeter.model
    data = commanded_pose(retargeter, action)
    keypoints, wrists = [], []
    for side, layout in retargeter.embodiment.sides.items():
        palm = model.site(layout.palm_site).id
        tips = np.array([data.site_xpos[model.site(s).id] for s in layout.fingertip_sites])
        frame = robot_as_human(data.site_xpos[palm], data.site_xmat[palm].reshape(3, 3), tips,
                               retargeter.wrist[side], env.embodiment.hand.retarget)
        keypoints.append(frame.keypoints)
        wrists.append(frame.wrist)
    return np.array(keypoints), np.array(wrists)


def record_takes(task: str, embodiment: str, episodes: int, seed: int,
                 out: pathlib.Path) -> list[tuple[tuple[int, int, int], pathlib.Path]]:
    """Run the expert on episodes (seed, 0, 0..episodes-1); keep each successful one as a
    keypoint file `out/take<j>.npz`; returns (episode key, file) per kept take."""
    env = make_env(task, embodiment, num_envs=1, seed=seed, obs="state", nthread=1)
    expert, retargeter = make_expert(env), Retargeter(embodiment)
    out.mkdir(parents=True, exist_ok=True)
    takes = []
    for j in range(episodes):
        key = (seed, 0, j)
        env.reset_to(np.array([0]), [key])
        expert.reset(torch.tensor([0]))
        kps, wrists, success_at, step = [], [], -1, 0
        while True:
            action = expert.act().float()
            kp, wrist = _hand_frames(env, retargeter, action[0].cpu().numpy())
            kps.append(kp)
            wrists.append(wrist)
            _, _, success, truncated, info = env.step(action)
            step += 1
            if bool(success[0]) and success_at < 0:
                success_at = step
            if (success_at >= 0 and step - success_at >= POST_SUCCESS_STEPS) or bool(
                    truncated[0]) or int(info["sim_warnings"][0]) > 0:
                break
        if success_at >= 0:
            path = write_keypoints(out / f"take{j:03d}.npz", np.array(kps), np.array(wrists),
                                   fps=1.0 / env.control_dt,
                                   handedness=tuple(env.embodiment.sides))
            takes.append((key, path))
    return takes


@dataclass
class Transfer:
    """One target embodiment's result over the takes."""

    embodiment: str
    takes: int
    successes: int
    tip_error_mm_mean: float
    tip_error_mm_p95: float


def replay_takes(task: str, embodiment: str, takes: list[tuple[tuple[int, int, int],
                                                               pathlib.Path]],
                 seed: int) -> Transfer:
    """Each take retargeted to `embodiment` and played open loop from its own reset."""
    env = make_env(task, embodiment, num_envs=1, seed=seed, obs="state", nthread=1)
    errors, successes = [], 0
    for key, path in takes:
        take = FileSource(path)
        player = TeleopPlayer(env, [take])
        env.reset_to(np.array([0]), [key])
        player.reset(torch.tensor([0]))
        solved = False
        for t in range(len(take)):
            action = player.act()
            frame = take.frame(t)
            errors.extend(np.concatenate(list(player.retargeter.fingertip_error(
                {s: f for s, f in frame.items() if s in env.embodiment.sides}).values())))
            _, _, success, truncated, _ = env.step(action)
            solved |= bool(success[0])
            if solved or bool(truncated[0]):
                break
        while not solved and not player.ended()[0]:
            _, _, success, truncated, _ = env.step(player.act())
            solved |= bool(success[0])
            if bool(truncated[0]):
                break
        successes += int(solved)
    err_mm = 1000.0 * np.array(errors)
    return Transfer(embodiment, len(takes), successes, float(err_mm.mean()),
                    float(np.percentile(err_mm, 95)))
