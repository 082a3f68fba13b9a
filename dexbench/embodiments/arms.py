"""The three arms: model sources and where they stand relative to the table."""

from __future__ import annotations

from dataclasses import dataclass


@dataclass(frozen=True)
class ArmSpec:
    """An arm model with an `attachment_site` at its flange.

    The base sits on a pedestal level with the table top, `flange_reach` metres (in x)
    behind the flange at home, so every hand gets the same comfortable arm posture
    however long it is. `seed_qpos` starts the inverse kinematics that finds the home
    pose, so it picks the elbow-up branch.
    """

    name: str
    collection: str
    entry: str
    seed_qpos: tuple[float, ...]
    flange_reach: float = 0.4


ARMS: dict[str, ArmSpec] = {
    "fr3": ArmSpec(
        name="fr3",
        collection="franka_fr3",
        entry="fr3",
        seed_qpos=(0.0, -0.3, 0.0, -2.2, 0.0, 2.0, 0.785),
        flange_reach=0.4,
    ),
    "ur10e": ArmSpec(
        name="ur10e",
        collection="universal_robots_ur10e",
        entry="ur10e",
        seed_qpos=(2.7, -1.4, 2.4, -1.0, 1.2, -1.57),
        flange_reach=0.55,
    ),
    "xarm7": ArmSpec(
        name="xarm7",
        collection="ufactory_xarm7",
        entry="xarm7_nohand",
        seed_qpos=(0.0, 0.0, 0.0, 1.2, 0.0, 1.2, 0.0),
        flange_reach=0.35,
    ),
}
