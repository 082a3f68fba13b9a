"""The three arms: model sources, how each carries the hand, and where it stands."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

# Hand-frame axes (columns: fingers, palm y, palm normal) in an arm's flange frame.
# Inline: the fingers continue the tool axis z, the palm normal is the flange's x.
INLINE_MOUNT = np.array([[0.0, 0.0, 1.0], [0.0, -1.0, 0.0], [1.0, 0.0, 0.0]])
# Flat: the palm normal is the tool axis, the fingers run along the flange's x.
FLAT_MOUNT = np.eye(3)


@dataclass(frozen=True)
class ArmSpec:
    """An arm model with an `attachment_site` at its flange.

    The base sits on a pedestal level with the table top, `flange_reach` metres (in x)
    behind the flange at home, so every hand gets the same comfortable arm posture
    however long it is. `seed_qpos` starts the inverse kinematics that finds the home
    pose, so it picks the elbow-up branch.

    `hand_rot` is how the flange carries the hand: the mount that lets the arm hold the
    home pose (palm down, fingers forward, low over the table) and reach over the table
    with every joint clear of its limits. The UR10e and xArm7 can hold their flange
    level there, so they carry the hand inline; the FR3 cannot (joint 6's lower limit,
    ~0.54 rad, forbids a level, forward-pointing flange low down), so its hand sits flat
    under a downward flange, the usual Franka posture.

    `armature` (kg m^2) is a floor on every arm joint's rotor inertia. Without any (the
    xArm7 model), a wrist servo that hits its force limit (kv 80 on a light link) locks
    into a bang-bang chatter at the 240 Hz step, ~0.2 rad off its target for good. The
    UR10e's wrist servos (kp 5000, limit 56 Nm: saturated 0.011 rad off) did the same
    with the model's 0.1 under the Shadow hand, pinned at their limits 94-100% of the
    time and shaking the palm (wrist 3 at 1 rad/s rms holding still); 0.5, of the order
    of a harmonic-drive joint's reflected rotor inertia, settles them.

    `damping_ratio`, where set, makes each joint servo's velocity gain that fraction of
    critical damping for the joint's inertia at the home pose, hand included (the
    position gain stays the model's). The FR3 model's own kv = kp/10 is 2-5 times
    critical there: an overdamped servo lags its target by ~0.1 s, which put the palm
    2-4 cm behind a moving command (the floating wrist: <1 cm) and, pushing, made the
    experts take their plan for blocked over and over. The UR10e keeps its model's kv:
    its light wrist links (kp 5000, force limit 56 Nm) need that damping, implicit in
    the integrator, to stay out of a bang-bang chatter at the 240 Hz step.
    """

    name: str
    collection: str
    entry: str
    seed_qpos: tuple[float, ...]
    hand_rot: np.ndarray
    flange_reach: float = 0.4
    armature: float = 0.0
    damping_ratio: float | None = None


ARMS: dict[str, ArmSpec] = {
    "fr3": ArmSpec(
        name="fr3",
        collection="franka_fr3",
        entry="fr3",
        seed_qpos=(0.0, -0.2, 0.0, -2.8, 0.0, 2.7, 0.0),
        hand_rot=FLAT_MOUNT,
        flange_reach=0.37,
        damping_ratio=1.0,
    ),
    "ur10e": ArmSpec(
        name="ur10e",
        collection="universal_robots_ur10e",
        entry="ur10e",
        seed_qpos=(2.7, -1.4, 2.4, -1.0, 1.2, -1.57),
        hand_rot=INLINE_MOUNT,
        flange_reach=0.55,
        armature=0.5,
    ),
    "xarm7": ArmSpec(
        name="xarm7",
        collection="ufactory_xarm7",
        entry="xarm7_nohand",
        seed_qpos=(0.0, 0.0, 0.0, 1.2, 0.0, 1.2, 0.0),
        hand_rot=INLINE_MOUNT,
        flange_reach=0.30,
        armature=0.05,
    ),
}
