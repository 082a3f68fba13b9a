"""An embodiment resolved against a compiled model: the action layout and its poses."""

from __future__ import annotations

from dataclasses import dataclass

import mujoco
import numpy as np

from dexbench.embodiments.builder import EmbodimentPlan, SideLayout
from dexbench.embodiments.hands import SYNERGIES, HandSpec


@dataclass(frozen=True)
class Embodiment:
    """Action layout, proprio joints and named poses, in the compiled model's order.

    `poses` holds full action vectors: `home` (mounts at home, hand open) and one per
    hand synergy (mounts at home, hand in that synergy). `mount`, `hand` and `arity` are
    what the name says, so no caller needs to parse the name.
    """

    name: str
    mount: str
    hand: HandSpec
    arity: int
    sides: dict[str, SideLayout]
    actuators: tuple[str, ...]
    ctrl_range: np.ndarray  # (nu, 2)
    proprio_joints: tuple[str, ...]
    poses: dict[str, np.ndarray]
    home_qpos: dict[str, float]  # every robot joint

    @property
    def bimanual(self) -> bool:
        return self.arity == 2

    @property
    def action_dim(self) -> int:
        return len(self.actuators)

    def side_actuators(self, side: str) -> np.ndarray:
        """Indices into `actuators` of one side's actuators (mount and hand), in action
        order."""
        return np.array([i for i, a in enumerate(self.actuators) if a.startswith(f"{side}/")],
                        dtype=np.int64)

    def hand_actuators(self, side: str) -> np.ndarray:
        """Indices into `actuators` of one side's hand actuators, in action order."""
        return np.array([i for i, a in enumerate(self.actuators)
                         if a.startswith(f"{side}/hand/")], dtype=np.int64)

    @classmethod
    def resolve(cls, plan: EmbodimentPlan, model: mujoco.MjModel) -> Embodiment:
        """Read indices and ranges from `model`; every actuator must be the robot's."""
        actuators = tuple(model.actuator(i).name for i in range(model.nu))
        stray = [a for a in actuators if a.split("/", 1)[0] not in plan.sides]
        if stray:
            raise ValueError(f"actuators outside the embodiment: {stray}; task objects "
                             "must not add actuators")
        mount_home = {j: q for s in plan.sides.values() for j, q in s.home_qpos.items()}
        home_qpos = {**mount_home, **plan.hand_qpos}
        poses = {}
        for pose in ("home", *SYNERGIES):
            targets = plan.hand_targets["open" if pose == "home" else pose]
            vec = np.zeros(model.nu)
            for i, act in enumerate(actuators):
                if act in targets:
                    vec[i] = targets[act]
                else:
                    joint = model.joint(model.actuator_trnid[i, 0]).name
                    vec[i] = mount_home[joint]
            poses[pose] = vec
        proprio = tuple(j for s in plan.sides.values() for j in (*s.mount_joints,
                                                                   *s.hand_joints))
        return cls(
            name=str(plan.name),
            mount=plan.name.mount,
            hand=plan.name.hand_spec,
            arity=plan.name.arity,
            sides=plan.sides,
            actuators=actuators,
            ctrl_range=model.actuator_ctrlrange.copy(),
            proprio_joints=proprio,
            poses=poses,
            home_qpos=home_qpos,
        )
