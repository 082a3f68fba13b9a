"""GPU backend: mujoco_warp, `num_envs` worlds of one model in one set of device arrays.

Fields are zero-copy torch views of mujoco_warp's arrays (float32), so observation
terms, rewards and success predicates run on them unchanged and on the GPU. A control
step is one CUDA graph (captured on first use per substep count), so stepping costs
one graph launch from Python; on warp's CPU device (no GPU, e.g. CI) the same functions
run as plain launches.

The step keeps the CPU backend's meaning of derived fields: after `step` they describe
the new state (positions, velocities and their sensors; with `acceleration` also the
acceleration stage: contact forces), not the start of the last substep. It does so at
no extra physics cost: the position and velocity stages computed after a step are
exactly those the next step begins with (`mjw.step1`), so a control step of k substeps
is `step2`, k-1 full steps and `step1`, the work of k raw steps, plus the acceleration
stage when asked for.

Contact and constraint capacity is sized from the model (`capacity`); mujoco_warp flags
overflows per world, and each control step with a capacity overflow or a non-finite
state counts as one warning of that world (`warning_counts`), like MuJoCo's warnings
on the CPU backend. Like MuJoCo on the CPU (its auto-reset), a world whose state went
non-finite or beyond `MAX_STATE_VALUE` is reset to the model's defaults in the same step,
so a diverged world never hands NaN to observations or policies.
"""

from __future__ import annotations

import dataclasses

import mujoco
import numpy as np
import torch

from dexbench.sim.backend import DERIVED_FIELDS, INTEGRATION, STATE_FIELDS, lookup_field
from dexbench.sim.warp_render import _import_warp, default_warp_device

wp, mjw = _import_warp()
from mujoco_warp._src import types as mjw_types  # noqa: E402  (after warp is configured)

# Overflows that lose contacts or constraints. Solver and line-search iteration limits
# are not errors (MuJoCo does not warn about them either) and are neither printed nor
# counted.
_CAPACITY_OVERFLOWS = int(mjw.OverflowType.ALL & ~(mjw.OverflowType.ITERATIONS
                                                    | mjw.OverflowType.LS_ITERATIONS))
# Constants `mjw.set_const` derives from mass and inertia: per world once those are.
_DERIVED_CONSTANTS = ("body_subtreemass", "body_invweight0", "dof_invweight0",
                      "tendon_invweight0", "actuator_acc0")
CAPACITY_MARGIN = 2.0
MAX_STATE_VALUE = 1e10  # MuJoCo's mjMAXVAL: larger positions or velocities are divergence


@wp.kernel
def _count_warnings(mask: int, max_value: float, qpos: wp.array2d(dtype=wp.float32),
                    qvel: wp.array2d(dtype=wp.float32), overflow: wp.array(dtype=wp.int32),
                    counts: wp.array(dtype=wp.int32), diverged: wp.array(dtype=bool)):
    """Count a world's control step as a warning if it overflowed or diverged (a
    non-finite or huge state, which also marks the world for MuJoCo's auto-reset)."""
    world = wp.tid()
    bad = wp.int32(0)  # a dynamic variable: warp forbids mutating a constant in a loop
    for i in range(qpos.shape[1]):
        if not (wp.abs(qpos[world, i]) <= max_value):  # NaN fails every comparison
            bad = 1
    for i in range(qvel.shape[1]):
        if not (wp.abs(qvel[world, i]) <= max_value):
            bad = 1
    diverged[world] = bad != 0
    if bad != 0 or (overflow[world] & mask) != 0:
        counts[world] = counts[world] + 1
    overflow[world] = overflow[world] & ~mask


def capacity(model: mujoco.MjModel, margin: float = CAPACITY_MARGIN) -> tuple[int, int]:
    """Per-world contacts (`nconmax`) and constraint rows (`njmax`) to allocate.

    Contacts: one per collision geom of a moving body (a finger link touching the object
    or the table) plus 8 per free object (a box resting on a box touches at up to 8
    points). Rows: each contact takes `condim` rows (elliptic cones; 2(condim-1)
    pyramidal), plus joint limits, dof friction and equality rows. Both times `margin`
    (a Shadow hand grasping a cube measured 19 contacts and 90 rows at most, against 94
    and 484 allocated); running out is still detected and counted (`warning_counts`).
    """
    solid = (model.geom_contype != 0) | (model.geom_conaffinity != 0)
    moving = model.body_weldid[model.geom_bodyid] != 0
    free = int((model.jnt_type == mujoco.mjtJoint.mjJNT_FREE).sum())
    contacts = int((solid & moving).sum()) + 8 * free
    condim = int(model.geom_condim[solid].max()) if solid.any() else 1
    elliptic = model.opt.cone == mujoco.mjtCone.mjCONE_ELLIPTIC
    per_contact = condim if elliptic else max(1, 2 * (condim - 1))
    other = (int(model.jnt_limited.sum()) + int((model.dof_frictionloss > 0).sum())
             + 6 * model.neq)
    return (max(1, int(np.ceil(margin * contacts))),
            max(1, int(np.ceil(margin * (contacts * per_contact + other)))))


def _torch_device(wp_device: str) -> torch.device:
    return torch.device("cpu") if wp_device == "cpu" else torch.device(wp_device)


class WarpBackend:
    """N worlds of one model on one warp device (CUDA when there is a GPU)."""

    def __init__(self, model: mujoco.MjModel, num_envs: int, device: str | None = None,
                 nconmax: int | None = None, njmax: int | None = None) -> None:
        self.model = model
        self.num_envs = num_envs
        self.wp_device = device or default_warp_device()
        self.device = _torch_device(self.wp_device)
        self.graphs_enabled = self.wp_device != "cpu"
        sized_con, sized_j = capacity(model)
        self.nconmax, self.njmax = nconmax or sized_con, njmax or sized_j
        with wp.ScopedDevice(self.wp_device):
            self.m = mjw.put_model(model)
            self.m.opt.warn_overflow = _CAPACITY_OVERFLOWS
            self.d = mjw.make_data(model, nworld=num_envs, nconmax=self.nconmax,
                                   njmax=self.njmax)
            self._reset_mask = wp.zeros(num_envs, dtype=bool)
            self._warnings = wp.zeros(num_envs, dtype=wp.int32)
            self._stream = wp.get_stream() if self.graphs_enabled else None
        self._fields = {name: self._view(name) for name in (*STATE_FIELDS, *DERIVED_FIELDS)}
        self._mask_t = wp.to_torch(self._reset_mask)
        self._warnings_t = wp.to_torch(self._warnings)
        self._graphs: dict[tuple, object] = {}
        self._batchable = {f.name for f in dataclasses.fields(mjw_types.Model)
                           if getattr(f.type, "shape", ())[:1] == ("*",)}
        self.per_world_model = False
        self._run(("forward", False), lambda: self._forward(False))

    def _view(self, name: str) -> torch.Tensor:
        """A zero-copy (num_envs, ...) torch view of a Data field, shaped as on the CPU."""
        array = getattr(self.d, name)
        if array.size == 0:  # torch cannot alias an empty warp array; nothing to share
            inner = getattr(array.dtype, "_shape_", ())
            return torch.zeros((self.num_envs, *array.shape[1:], *inner),
                               dtype=torch.float32, device=self.device)
        tensor = wp.to_torch(array)
        if name == "site_xmat":
            tensor = tensor.view(self.num_envs, -1, 9)
        return tensor

    def field(self, name: str) -> torch.Tensor:
        return lookup_field(self._fields, name)

    def model_field(self, name: str) -> torch.Tensor:
        """A writable (num_envs, ...) view of per-world values of a model field.

        The field is expanded from one shared row to one row per world on first use
        (captured graphs are re-captured, as they hold the old array).
        """
        if name not in self._batchable:
            raise ValueError(f"model field {name!r} cannot vary per world in mujoco_warp")
        self._expand(name)
        self.per_world_model = True
        return wp.to_torch(getattr(self.m, name))

    def _expand(self, name: str) -> None:
        old = getattr(self.m, name)
        if old.shape[0] == self.num_envs:
            return
        tiled = np.repeat(old.numpy(), self.num_envs, axis=0)
        new = wp.array(tiled, dtype=old.dtype, device=self.wp_device)
        new._is_batched = True
        setattr(self.m, name, new)
        self._graphs.clear()

    def set_const(self, env_ids) -> None:
        """Recompute derived constants (subtree masses, inverse weights) of every world
        after per-world edits (the other worlds' values come out unchanged)."""
        for name in _DERIVED_CONSTANTS:
            if getattr(self.m, name).size:
                self._expand(name)
        self._run(None, lambda: mjw.set_const(self.m, self.d))

    def warning_counts(self) -> torch.Tensor:
        """(num_envs,) control steps with a contact/constraint overflow or a non-finite
        state since each world's reset."""
        return self._warnings_t.long()

    def _run(self, key: tuple | None, fn) -> None:
        """Run `fn`'s warp work ordered after the torch work queued so far and before the
        torch work that follows; with a `key`, as a CUDA graph captured on first use.
        On the CPU device: plain launches."""
        if not self.graphs_enabled:
            with wp.ScopedDevice(self.wp_device):
                fn()
            return
        torch_stream = wp.stream_from_torch(torch.cuda.current_stream(self.device))
        with wp.ScopedDevice(self.wp_device), wp.ScopedStream(self._stream):
            self._stream.wait_stream(torch_stream)
            if key is None:
                fn()
            else:
                if key not in self._graphs:
                    with wp.ScopedCapture() as capture:
                        fn()
                    self._graphs[key] = capture.graph
                wp.capture_launch(self._graphs[key])
            torch_stream.wait_stream(self._stream)

    def _forward(self, acceleration: bool) -> None:
        """Position and velocity stages (+ acceleration stage) at the current state."""
        mjw.step1(self.m, self.d)
        if acceleration:
            mjw.fwd_actuation(self.m, self.d)
            mjw.fwd_acceleration(self.m, self.d)
            mjw.solve(self.m, self.d)
            mjw.sensor_acc(self.m, self.d)

    def _control_step(self, nsubsteps: int, acceleration: bool) -> None:
        mjw.step2(self.m, self.d)  # the position/velocity stages are current already
        for _ in range(nsubsteps - 1):
            mjw.step(self.m, self.d)
        wp.launch(_count_warnings, dim=self.num_envs,
                  inputs=[_CAPACITY_OVERFLOWS, MAX_STATE_VALUE, self.d.qpos, self.d.qvel,
                          self.d.overflow, self._warnings, self._reset_mask])
        mjw.reset_data(self.m, self.d, self._reset_mask)  # the diverged worlds only
        self._forward(acceleration)

    def step(self, nsubsteps: int, acceleration: bool = False) -> None:
        if nsubsteps < 1:
            raise ValueError(f"nsubsteps must be >= 1, got {nsubsteps}")
        self._run(("step", nsubsteps, acceleration),
                  lambda: self._control_step(nsubsteps, acceleration))

    def raw_step(self, nsubsteps: int) -> None:
        """`nsubsteps` plain `mjw.step`s of every world (the raw-physics benchmark)."""
        def fn():
            for _ in range(nsubsteps):
                mjw.step(self.m, self.d)
        self._run(("raw", nsubsteps), fn)

    def reset(self, env_ids: torch.Tensor) -> None:
        ids = torch.as_tensor(env_ids, dtype=torch.long, device=self.device).reshape(-1)
        self._mask_t.zero_()
        self._mask_t[ids] = True
        self._run(("reset",), lambda: mjw.reset_data(self.m, self.d, self._reset_mask))
        self._warnings_t[ids] = 0

    def forward(self, env_ids: torch.Tensor, acceleration: bool = False) -> None:
        """Recompute derived fields (every world's: the others' come out unchanged)."""
        self._run(("forward", acceleration), lambda: self._forward(acceleration))

    def get_state(self, spec: int = INTEGRATION) -> torch.Tensor:
        size = mujoco.mj_stateSize(self.model, spec)
        state = torch.zeros(self.num_envs, size, dtype=torch.float32, device=self.device)
        self._run(None, lambda: mjw.get_state(self.m, self.d, wp.from_torch(state), spec))
        return state.double()

    def set_state(self, env_ids: torch.Tensor, state: torch.Tensor, spec: int = INTEGRATION,
                  acceleration: bool = False) -> None:
        rows = torch.as_tensor(env_ids, dtype=torch.long, device=self.device).reshape(-1)
        size = mujoco.mj_stateSize(self.model, spec)
        full = torch.zeros(self.num_envs, size, dtype=torch.float32, device=self.device)
        full[rows] = torch.as_tensor(state, device=self.device).float().reshape(len(rows), size)
        active = torch.zeros(self.num_envs, dtype=torch.bool, device=self.device)
        active[rows] = True
        self._run(None, lambda: mjw.set_state(self.m, self.d, wp.from_torch(full), spec,
                                              wp.from_torch(active)))
        self.forward(rows, acceleration)
