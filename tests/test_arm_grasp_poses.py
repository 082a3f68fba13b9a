"""A round vessel's grasp turns about its axis to where the arm can pour it.

GraspCup's plan holds the cup in a handshake grasp (fingers along +x, thumb up) and tips
it 115 deg over the fingertips at the goal, 0.3 m over the table: the Shadow forearm then
points up, out of the xArm7's reach (the pour's palm poses missed by 10-30 cm), and the
arm scored 0.00 where the floating hand scores 1.00. The cup is round: it may be held
from any side.
"""

from __future__ import annotations

import numpy as np
import torch

from dexbench.eval.seeds import eval_keys
from dexbench.experts import make_expert
from dexbench.tasks.registry import make_env


def _planned_fingers(embodiment: str) -> np.ndarray:
    """The fingers' direction of GraspCup's first planned grasp on `embodiment`."""
    env = make_env("GraspCup", embodiment, num_envs=1, seed=0, nthread=1)
    env.reset_to(np.arange(1), eval_keys(0, [0]))
    expert = make_expert(env)
    expert.reset(torch.arange(1))
    for _ in range(2):
        env.step(expert.act())
    return expert._held_rot[0][:, 0]


def test_round_vessel_grasp_turns_to_where_the_arm_pours():
    """The floating hand keeps the plan's grasp; the xArm7 turns it about the vertical."""
    np.testing.assert_allclose(_planned_fingers("floating_shadow"), [1.0, 0.0, 0.0],
                               atol=1e-9)  # the plan's own turn
    fingers = _planned_fingers("xarm7_shadow")
    assert abs(fingers[2]) < 1e-9 and fingers[0] < 0.9, fingers
