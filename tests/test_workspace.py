"""Arm mounts follow the task's workspace (`Task.workspace`); floating wrists and tasks on
the default workspace are placed as before.

Built from the offline robot models (MENAGERIE_ROOT / DEXBENCH_HANDS_ROOT); skipped when
those are unset.
"""

from __future__ import annotations

import os

import mujoco
import numpy as np
import pytest

from dexbench.embodiments.builder import DEFAULT_WORKSPACE, add_embodiment, robot_at_home
from dexbench.envs.arena import PhysicsOptions, build_arena
from dexbench.envs.scene import compose_scene
from dexbench.eval.feasibility import ik_residuals
from dexbench.tasks.registry import TASKS

pytestmark = pytest.mark.skipif(
    not (os.environ.get("MENAGERIE_ROOT") and os.environ.get("DEXBENCH_HANDS_ROOT")),
    reason='offline robot models unset: run eval "$(bash <shared>/assets/unpack.sh)"',
)

OFFSET = (0.4, 0.1, 0.2)


def _robot(name: str, workspace: tuple[float, float, float] = DEFAULT_WORKSPACE
           ) -> tuple[mujoco.MjModel, mujoco.MjData, dict]:
    """A robot-only model at home, and its sides' layouts."""
    model, data, plan = robot_at_home(name, workspace)
    return model, data, plan.sides


@pytest.mark.parametrize("name", ["fr3_shadow", "bimanual_ur10e_allegro"])
def test_arm_moves_with_workspace(name: str) -> None:
    """Base and home palm shift by the workspace's offset; the arm's posture is the same."""
    m0, d0, sides0 = _robot(name)
    m1, d1, sides1 = _robot(name, OFFSET)
    shift = np.array(OFFSET)
    for side, layout in sides1.items():
        base, palm = layout.base_body, layout.palm_site
        np.testing.assert_allclose(d1.xpos[m1.body(base).id] - d0.xpos[m0.body(base).id],
                                   shift, atol=1e-9)
        np.testing.assert_allclose(d1.site_xpos[m1.site(palm).id], layout.home_palm_pos,
                                   atol=1e-3)
        np.testing.assert_allclose(np.subtract(layout.home_palm_pos,
                                               sides0[side].home_palm_pos), shift)
        assert layout.home_qpos == sides0[side].home_qpos


def test_floating_ignores_workspace() -> None:
    _, d0, sides0 = _robot("floating_shadow")
    _, d1, sides1 = _robot("floating_shadow", OFFSET)
    assert sides1 == sides0
    np.testing.assert_array_equal(d1.xpos, d0.xpos)


def test_feasibility_places_arm_as_scene() -> None:
    """The reach test's arm sits where the task's scene puts it: the home palm is reached."""
    _, _, sides = _robot("fr3_shadow", OFFSET)
    home = np.array([[sides["right"].home_palm_pos]])
    rot = np.diag([1.0, -1.0, -1.0])[None, None]
    assert ik_residuals("fr3_shadow", home, rot, OFFSET)[0, 0, 2] < 1e-3


def _bodies(task: str, embodiment: str) -> np.ndarray:
    """Body positions of the task's scene, as `compose_scene` builds it."""
    return compose_scene(TASKS[task](), embodiment, PhysicsOptions()).model.body_pos


def test_default_task_scene_unchanged() -> None:
    """A task on the default workspace gets the arm exactly where it always stood."""
    task = TASKS["PickCube"]()
    assert task.workspace == DEFAULT_WORKSPACE
    spec = build_arena(PhysicsOptions())
    add_embodiment(spec, "fr3_shadow")
    task.build(spec)
    np.testing.assert_array_equal(_bodies("PickCube", "fr3_shadow"), spec.compile().body_pos)


def test_faucet_arm_moves_floating_stays() -> None:
    """OpenFaucet works beyond the table centre, at the lever's height: the arm moves up
    to it (its pedestal then stands on the table), the floating hand does not."""
    faucet = TASKS["OpenFaucet"]
    assert faucet.workspace != DEFAULT_WORKSPACE
    for name, expected in (("fr3_shadow", faucet.workspace), ("floating_shadow", (0, 0, 0))):
        model = compose_scene(faucet(), name, PhysicsOptions()).model
        default = compose_scene(TASKS["PickCube"](), name, PhysicsOptions()).model
        base = "right/base"
        np.testing.assert_allclose(model.body(base).pos - default.body(base).pos, expected,
                                   atol=1e-9)
    pedestal = compose_scene(faucet(), "fr3_shadow", PhysicsOptions()).model.geom(
        "right/pedestal")
    np.testing.assert_allclose(2 * pedestal.size[1], faucet.workspace[2], atol=1e-9)


def test_pan_workspace_between_pan_and_stove() -> None:
    """GraspPan's hand carries the pan from its place to the stove: the declared workspace
    lies between their reset regions, on the table."""
    task = TASKS["GraspPan"]
    pan, stove = task.placements["pan"], task.placements["stove"]
    x, y, z = task.workspace
    assert pan.x[1] < x < stove.x[0]
    assert max(pan.y[0], stove.y[0]) <= y <= min(pan.y[1], stove.y[1])
    assert z == 0.0
