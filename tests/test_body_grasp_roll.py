"""A body grasp on an arm rolls the palm down where the links behind it would meet the table."""

import numpy as np
import torch

from dexbench.eval.seeds import eval_keys
from dexbench.experts import make_expert
from dexbench.experts.surface import mount_part
from dexbench.tasks.registry import make_env


def _planned_palm_normal(embodiment: str) -> np.ndarray:
    """The palm normal (world) of the can's planned grasp, episode 0."""
    env = make_env("FunctionalPourCan", embodiment, num_envs=1, nthread=1)
    expert = make_expert(env)
    env.reset_to(torch.arange(1), eval_keys(0, [0]))
    expert.reset(torch.arange(1))
    start = expert._held_rot.copy()
    for _ in range(20):
        env.step(expert.act())
        if not np.allclose(expert._held_rot, start):
            break
    return expert._held_rot[0][:, 2]


def test_only_a_hand_without_a_wrist_on_an_arm_has_links_moving_with_its_palm():
    def part(embodiment: str) -> np.ndarray:
        return mount_part(make_env("FunctionalPourCan", embodiment, num_envs=1), "right")

    fr3, ur10e = part("fr3_wuji"), part("ur10e_wuji")
    assert len(fr3) and len(ur10e)
    assert not len(part("floating_wuji")) and not len(part("fr3_shadow"))
    # the FR3's flat mount carries link 7 behind the palm, further out than the UR10e's wrist
    assert fr3[:, 1].max() > ur10e[:, 1].max() + 0.02


def test_the_fr3_rolls_its_palm_down_over_the_can_and_the_ur10e_does_not():
    assert _planned_palm_normal("fr3_wuji")[2] < -0.3
    assert abs(_planned_palm_normal("ur10e_wuji")[2]) < 0.05
