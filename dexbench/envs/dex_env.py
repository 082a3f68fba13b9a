"""The batched environment: N copies of one task on one embodiment and backend.

Actions are absolute joint-position targets for every actuator, (N, action_dim), held
for one control period (`control_dt`, 60 Hz by default). Observations are a dict of
group -> float32 tensor on the backend's device; groups a task does not populate are
absent. `terminated` is success, `truncated` the time limit.

Every episode has a key (seed, env, episode) that fixes its reset sample, goal and
variation; `reset_to` replays a key in any environment and `restore` puts a recorded
`sim_state` back, so recorded demonstrations regenerate their observations exactly.
"""

from __future__ import annotations

import mujoco
import numpy as np
import torch

from dexbench.assets.materials import NUM_MATERIALS
from dexbench.envs.arena import PhysicsOptions
from dexbench.envs.camera_obs import CameraObservations, default_cameras
from dexbench.envs.observations import CAMERA_GROUPS, ObservationTerms, resolve_preset
from dexbench.envs.scene import compose_scene
from dexbench.envs.task_api import SceneView, Task
from dexbench.envs.variation import PhysicalVariation, Variation, VisualVariation
from dexbench.sim.backend import DERIVED_FIELDS, STATE_FIELDS
from dexbench.sim.factory import make_backend, make_renderer

Obs = dict[str, torch.Tensor]

_S = mujoco.mjtState
# What `restore` needs to reproduce a frame and continue its physics exactly: MuJoCo's
# full physics state plus the solver warm start (contact forces depend on it), the
# controls in force, mocap poses (fixed objects) and userdata (task memory, e.g. stages).
# Applied forces and equality switches are left out: the env never writes them.
STATE_SPEC = (int(_S.mjSTATE_FULLPHYSICS) | int(_S.mjSTATE_WARMSTART) | int(_S.mjSTATE_CTRL)
              | int(_S.mjSTATE_MOCAP_POS) | int(_S.mjSTATE_MOCAP_QUAT)
              | int(_S.mjSTATE_USERDATA))


# An episode terminates as a success once the task's condition has held this many
# consecutive control steps (1/6 s at 60 Hz), the authors' rule for recording a demo: a
# condition met for an instant (an object bouncing through a threshold) is not success.
SUCCESS_HOLD_STEPS = 10


def time_limit_steps(episode_seconds: float, physics: PhysicsOptions | None = None) -> int:
    """Control steps in a time limit of `episode_seconds`: `DexEnv` truncates on this step,
    and Gymnasium registers it as `max_episode_steps` (one source of truth)."""
    physics = physics or PhysicsOptions()
    return round(episode_seconds / (physics.decimation * physics.timestep))


class InvalidActionError(ValueError):
    """An action batch with the wrong shape or non-finite values."""


class DexEnv:
    """Batched dexterous-manipulation environment.

    `obs` is a preset name or a list of groups; `history` overrides the preset's history
    length (k > 0 stacks the last k frames on axis 1). With `auto_reset`, environments
    that terminate or truncate are reset inside `step`. Camera groups render `cameras`
    (default: the preset's: front, or front/left/right when multiview, left/right for a
    bimanual point cloud; wrist cameras are `<side>/hand/wrist_cam`) at `image_size`
    (width, height) with `renderer` (`cpu`: OpenGL, `warp`: mujoco_warp ray tracing on the
    GPU), with the lights' shadows unless
    `shadows` is off (faster, mostly for the ray tracer); the point cloud keeps
    `num_points` points, computed on `cloud_device` (default: where the renderer leaves
    the depth images). `terminated` is success held for `SUCCESS_HOLD_STEPS` steps;
    `info["success"]` is the task's condition at this step.
    """

    def __init__(
        self,
        task: Task,
        embodiment: str,
        num_envs: int = 1,
        seed: int = 0,
        obs: str | list[str] = "state",
        backend: str = "cpu",
        nthread: int = 0,
        physics: PhysicsOptions | None = None,
        auto_reset: bool = False,
        history: int | None = None,
        cameras: tuple[str, ...] | list[str] | None = None,
        image_size: tuple[int, int] = (256, 256),
        renderer: str = "cpu",
        shadows: bool = True,
        num_points: int = 512,
        cloud_device: str | None = None,
        visual: VisualVariation | None = None,
        physical: PhysicalVariation | None = None,
    ) -> None:
        if num_envs < 1:
            raise ValueError(f"num_envs must be >= 1, got {num_envs}")
        self.task = task
        self.seed = seed
        self.num_envs = num_envs
        self.auto_reset = auto_reset
        self.physics = physics or PhysicsOptions()
        self.decimation = self.physics.decimation
        self.control_dt = self.decimation * self.physics.timestep
        self.episode_steps = time_limit_steps(task.episode_seconds, self.physics)
        visual = visual or VisualVariation()
        self.scene = compose_scene(task, embodiment, self.physics, visual.background_files())
        self.embodiment = self.scene.embodiment
        model = self.scene.model
        self.sim = make_backend(backend, model, num_envs, nthread)
        self.device = self.sim.device
        fields = {n: self.sim.field(n) for n in (*STATE_FIELDS, *DERIVED_FIELDS)}
        self._f = fields
        sites = [s for side in self.embodiment.sides.values() for s in side.fingertip_sites]
        palms = [side.palm_site for side in self.embodiment.sides.values()]
        self.view = SceneView(model, fields, sites, palms, self.scene.hand_geoms,
                              self.control_dt, self.scene.link_force_sensors)
        model_materials = [model.material(f"var/mat{i}").id for i in range(NUM_MATERIALS)]
        self.variation = Variation(self.scene, self.sim, model_materials,
                                   visual, physical or PhysicalVariation())
        self._noise = torch.Generator(device=self.device).manual_seed(seed)
        preset = resolve_preset(obs)
        self.groups = tuple(g for g in preset.groups if g not in CAMERA_GROUPS)
        self.history = preset.history if history is None else history
        # Contact forces are acceleration-stage quantities: computed at the current state
        # (not the last substep) so that a restored state observes the same forces, for
        # the `contact` group and for a success that reads per-link forces alike.
        self._acceleration = "contact" in self.groups or bool(task.link_force_bodies)
        camera_groups = tuple(g for g in preset.groups if g in CAMERA_GROUPS)
        self.cameras: CameraObservations | None = None
        if camera_groups:
            names = tuple(cameras) if cameras else default_cameras(
                preset.multiview, camera_groups, self.embodiment.arity)
            renderer = make_renderer(self.sim, *image_size, kind=renderer, shadows=shadows)
            self.cameras = CameraObservations(renderer, names, camera_groups, num_points,
                                              cloud_device)
        self._terms = ObservationTerms(self.scene, self.view, task, fields)

        emb = self.embodiment
        self.action_low = torch.tensor(emb.ctrl_range[:, 0], device=self.device)
        self.action_high = torch.tensor(emb.ctrl_range[:, 1], device=self.device)
        self.home_action = torch.tensor(emb.poses["home"], device=self.device)
        home = emb.home_qpos
        self._home_qadr = torch.tensor([model.joint(j).qposadr[0] for j in home],
                                       device=self.device)
        self._home_qval = torch.tensor(list(home.values()), dtype=torch.float64,
                                       device=self.device)
        self._episode = np.zeros(num_envs, dtype=np.int64)
        self._keys = np.zeros((num_envs, 3), dtype=np.int64)
        self.steps = torch.zeros(num_envs, dtype=torch.long, device=self.device)
        self.success_steps = torch.zeros(num_envs, dtype=torch.long, device=self.device)
        self.last_action = self.home_action.repeat(num_envs, 1).float()
        self._history: Obs = {}
        self._was_reset = False
        for body in task.tracked_bodies:
            self.view.initial_body_pos[body] = torch.zeros(num_envs, 3, dtype=fields["xpos"].dtype,
                                                           device=self.device)

    @property
    def action_dim(self) -> int:
        return self.embodiment.action_dim

    def obs_shapes(self) -> dict[str, tuple[int, ...]]:
        """Shape of each group one environment returns (no batch axis)."""
        obs = self._observe() if self._was_reset else self.reset()
        return {k: tuple(v.shape[1:]) for k, v in obs.items()}

    def reseed(self, seed: int) -> None:
        """Restart every environment's reset stream and the observation-noise stream from
        `seed` (takes effect at reset), so a seeded reset is reproducible."""
        self.seed = seed
        self._episode[:] = 0
        self._noise.manual_seed(seed)

    @property
    def episode_keys(self) -> np.ndarray:
        """(num_envs, 3) int64 key (seed, env, episode) of each environment's episode."""
        return self._keys.copy()

    @staticmethod
    def _rngs(keys: np.ndarray, stream: int = 0) -> list[np.random.Generator]:
        # One stream per (seed, env, episode, purpose): resets of some envs never shift
        # others', and switching variation on never changes the task's samples.
        return [np.random.default_rng([*map(int, key), stream]) for key in keys]

    def _env_ids(self, env_ids) -> torch.Tensor:
        ids = torch.arange(self.num_envs) if env_ids is None else torch.as_tensor(
            env_ids, dtype=torch.long).reshape(-1).cpu()
        if len(ids) and (ids.min() < 0 or ids.max() >= self.num_envs):
            raise IndexError(f"env_ids must lie in [0, {self.num_envs}), got {ids.tolist()}")
        return ids

    def reset(self, env_ids: torch.Tensor | np.ndarray | list[int] | None = None) -> Obs:
        """Reset some (default all) environments; return observations of all."""
        ids = self._env_ids(env_ids)
        if len(ids) == 0:
            return self._observe()
        n = ids.numpy()
        keys = np.stack([np.full(len(n), self.seed), n, self._episode[n]], axis=1)
        self._episode[n] += 1
        return self._reset(ids, keys)

    def reset_to(self, env_ids, keys) -> Obs:
        """Reset environments into given episodes; return observations of all.

        `keys` (n, 3) are episode keys as `episode_keys` reports them: the reset sample,
        goal and variation are exactly that episode's, whichever environment replays it.
        The environments' own episode counters do not advance.
        """
        ids = self._env_ids(env_ids)
        keys = np.asarray(keys, dtype=np.int64).reshape(-1, 3)
        if len(keys) != len(ids):
            raise ValueError(f"{len(keys)} episode keys for {len(ids)} environments")
        return self._reset(ids, keys) if len(ids) else self._observe()

    def _reset(self, ids: torch.Tensor, keys: np.ndarray) -> Obs:
        self._keys[ids.numpy()] = keys
        self.sim.reset(ids)
        qpos = self._f["qpos"]
        dev_ids = ids.to(self.device)
        qpos[dev_ids[:, None], self._home_qadr] = self._home_qval.to(qpos.dtype)
        self._f["ctrl"][dev_ids] = self.home_action.to(qpos.dtype)
        sample = self.task.sample_reset(self._rngs(keys))
        model = self.scene.model
        for joint, pose in sample.free_poses.items():
            adr = model.joint(joint).qposadr[0]
            qpos[dev_ids, adr:adr + 7] = torch.as_tensor(pose, dtype=qpos.dtype,
                                                        device=self.device)
        for body, pose in sample.mocap_poses.items():
            mocap = int(model.body(body).mocapid[0])
            pose = torch.as_tensor(pose, dtype=qpos.dtype, device=self.device)
            self._f["mocap_pos"][dev_ids, mocap] = pose[:, :3]
            self._f["mocap_quat"][dev_ids, mocap] = pose[:, 3:]
        for joint, value in sample.joint_pos.items():
            qpos[dev_ids, model.joint(joint).qposadr[0]] = torch.as_tensor(
                value, dtype=qpos.dtype, device=self.device)
        if sample.goal is not None:
            goal = torch.as_tensor(sample.goal, dtype=torch.float64, device=self.device)
            if self.view.goal is None:
                self.view.goal = torch.zeros(self.num_envs, goal.shape[1], dtype=goal.dtype,
                                             device=self.device)
            self.view.goal[dev_ids] = goal
        self.variation.apply(ids.numpy(), self._rngs(keys, stream=1))
        self.sim.forward(ids, self._acceleration)
        for body, initial in self.view.initial_body_pos.items():
            initial[dev_ids] = self.view.body_pos(body)[dev_ids]
        self._was_reset = True
        self.steps[dev_ids] = 0
        self.success_steps[dev_ids] = 0
        self.last_action[dev_ids] = self.home_action.float()
        return self._observe(reset_ids=dev_ids)

    @property
    def state_size(self) -> int:
        """Length of one environment's `sim_state`."""
        return mujoco.mj_stateSize(self.scene.model, STATE_SPEC)

    def sim_state(self) -> torch.Tensor:
        """(num_envs, state_size) float64 simulator state (`STATE_SPEC`), for `restore`."""
        return self.sim.get_state(STATE_SPEC)

    def restore(self, env_ids, states, last_action=None) -> Obs:
        """Put recorded `sim_state`s back into environments; return their observations.

        Nothing is stepped. Observations are (len(env_ids), ...) per group. The
        environments must have been reset to the recorded episodes (`reset_to`): goal,
        variation and reset poses come from there. `last_action` is the action before this
        frame (`policy` group; default: the home pose, as after a reset); history stacks of
        these environments restart from this frame.
        """
        ids = self._env_ids(env_ids)
        states = torch.as_tensor(states, dtype=torch.float64)
        if states.shape != (len(ids), self.state_size):
            raise ValueError(f"states have shape {tuple(states.shape)}; expected "
                             f"({len(ids)}, {self.state_size}) for {self.task.name} on "
                             f"{self.embodiment.name} (was it recorded for another scene?)")
        self.sim.set_state(ids, states.to(self.device), STATE_SPEC, self._acceleration)
        dev_ids = ids.to(self.device)
        self.last_action[dev_ids] = (self.home_action.float() if last_action is None else
                                     torch.as_tensor(last_action, dtype=torch.float32,
                                                     device=self.device))
        obs = self._observe(reset_ids=dev_ids)
        return {k: v[dev_ids] for k, v in obs.items()}

    def _validate(self, actions) -> torch.Tensor:
        a = torch.as_tensor(actions, device=self.device)
        if a.shape != (self.num_envs, self.action_dim):
            raise InvalidActionError(
                f"actions have shape {tuple(a.shape)}; expected (num_envs, action_dim) = "
                f"({self.num_envs}, {self.action_dim}) for {self.embodiment.name} "
                "(layout: env.embodiment.actuators)")
        if not a.is_floating_point():
            a = a.double()
        bad = ~torch.isfinite(a).all(dim=1)
        if bad.any():
            raise InvalidActionError(
                f"actions contain NaN or inf in env(s) {bad.nonzero().flatten().tolist()}; "
                "nothing was stepped")
        return torch.clamp(a.double(), self.action_low, self.action_high)

    def step(self, actions, observe: torch.Tensor | None = None
             ) -> tuple[Obs, torch.Tensor, torch.Tensor, torch.Tensor, dict]:
        """Apply one control step; return (obs, reward, terminated, truncated, info).

        `observe` (bool, (num_envs,)): the envs whose camera groups are rendered this step;
        the others' rows are zero. A chunking policy reads images only on the few steps
        before it plans (`reads_next`), and rendering is most of an image policy's
        evaluation time. Rendering changes no state, so the episodes are the same.
        """
        if not self._was_reset:
            raise RuntimeError("call reset() before the first step()")
        if observe is not None and self.history and self.cameras is not None:
            raise ValueError("observe= skips frames, which an env-side history would stack; "
                             "build the env with history=0 to use it")
        a = self._validate(actions)
        self._f["ctrl"][:] = a
        self.last_action = a.float()
        self.sim.step(self.decimation, self._acceleration)
        self.steps += 1
        self.task.update(self.view)
        success = self.task.success(self.view)
        reward = self.task.reward(self.view).float()
        self.success_steps = torch.where(success, self.success_steps + 1, 0)
        terminated = self.success_steps >= SUCCESS_HOLD_STEPS
        truncated = self.steps >= self.episode_steps
        info = {"success": success, "steps": self.steps.clone(),
                "sim_warnings": self.sim.warning_counts()}
        if self.auto_reset:  # finding the finished envs waits for the GPU: only then
            done = (terminated | truncated).nonzero().flatten()
            if len(done) > 0:
                return self.reset(done), reward, terminated, truncated, info
        return self._observe(observe=observe), reward, terminated, truncated, info

    def _observe(self, reset_ids: torch.Tensor | None = None,
                 observe: torch.Tensor | None = None) -> Obs:
        out: Obs = {}
        noise = self.variation.physical.obs_noise if self.variation.physical.enabled else 0.0
        for group in self.groups:
            value = self._terms.compute(group, self.last_action)
            if value is not None and noise > 0 and group in ("proprio", "state"):
                value = value + noise * torch.randn(value.shape, generator=self._noise,
                                                    device=self.device)
            if value is not None:
                out[group] = value
        if self.cameras is not None:
            envs = None if observe is None else torch.as_tensor(observe).nonzero().flatten()
            out.update(self.cameras.compute(envs))
        if self.history:
            out = {k: self._stack(k, v, reset_ids) for k, v in out.items()}
        return out

    def _stack(self, group: str, value: torch.Tensor, reset_ids: torch.Tensor | None):
        """Keep the last `history` frames; a reset fills an env's stack with its frame."""
        buf = self._history.get(group)
        if buf is None:
            buf = value[:, None].repeat(1, self.history, *[1] * (value.dim() - 1))
        elif reset_ids is not None:
            buf = buf.clone()  # never modify a stack already handed out
            buf[reset_ids] = value[reset_ids, None]
        else:
            buf = torch.cat([buf[:, 1:], value[:, None]], dim=1)
        self._history[group] = buf
        return buf
