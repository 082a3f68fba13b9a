"""LeRobot feature keys and specs of dexbench observation groups: the one mapping.

`proprio` is LeRobot's `observation.state` and the task state its
`observation.environment_state`; cameras become `observation.images.<camera>` (RGB) and
`observation.depth.<camera>` (metres, a depth image). The simulator state is `sim_state`,
outside `observation.*`, so LeRobot policies never take it as an input.
"""

from __future__ import annotations

import numpy as np

ACTION = "action"
SIM_STATE = "sim_state"
GROUP_KEYS = {
    "proprio": "observation.state",
    "state": "observation.environment_state",
    "policy": "observation.prev_action",
    "contact": "observation.contact",
    "goal": "observation.goal",
    "privileged": "observation.privileged",
    "pointcloud": "observation.pointcloud",
}
GROUP_OF = {key: group for group, key in GROUP_KEYS.items()}
_IMAGE_NAMES = ["height", "width", "channels"]


def feature_key(group: str) -> str:
    """The feature key of an observation group (`rgb/<camera>`, `depth/<camera>` too)."""
    kind, _, camera = group.partition("/")
    if kind in ("rgb", "depth") and camera:
        prefix = "observation.images" if kind == "rgb" else "observation.depth"
        return f"{prefix}.{camera.replace('/', '_')}"
    return GROUP_KEYS[group]


def feature_spec(group: str, shape: tuple[int, ...], names: list[str] | None = None) -> dict:
    """LeRobot feature of a group whose per-frame shape is `shape`."""
    if group.startswith("rgb/"):
        return {"dtype": "image", "shape": tuple(shape), "names": _IMAGE_NAMES}
    if group.startswith("depth/"):
        return {"dtype": "image", "shape": (*shape, 1), "names": _IMAGE_NAMES,
                "info": {"is_depth_map": True}}
    return {"dtype": "float32", "shape": tuple(shape), "names": names}


def frame_value(group: str, value: np.ndarray) -> np.ndarray:
    """One frame of a group as LeRobot's `add_frame` takes it (depth gets a channel)."""
    return value[..., None] if group.startswith("depth/") else value


def dataset_features(shapes: dict[str, tuple[int, ...]], actuators: list[str],
                     state_size: int, proprio_joints: list[str]) -> dict:
    """Every feature of a dexbench dataset: action, simulator state, observation groups.

    `shapes` maps observation groups to their per-frame shapes (no history axis).
    """
    features = {ACTION: {"dtype": "float32", "shape": (len(actuators),), "names": actuators},
                SIM_STATE: {"dtype": "float64", "shape": (state_size,), "names": None}}
    for group, shape in shapes.items():
        names = proprio_joints if group == "proprio" else None
        features[feature_key(group)] = feature_spec(group, shape, names)
    return features
