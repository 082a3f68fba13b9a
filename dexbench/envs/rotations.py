"""Batched quaternion helpers on torch tensors (MuJoCo's w, x, y, z convention)."""

from __future__ import annotations

import torch


def quat_apply(quat: torch.Tensor, vec: torch.Tensor) -> torch.Tensor:
    """Rotate vectors (..., 3) by unit quaternions (..., 4)."""
    w, xyz = quat[..., :1], quat[..., 1:]
    t = 2.0 * torch.cross(xyz, vec, dim=-1)
    return vec + w * t + torch.cross(xyz, t, dim=-1)


def quat_apply_inverse(quat: torch.Tensor, vec: torch.Tensor) -> torch.Tensor:
    """Rotate vectors (..., 3) by the inverse of unit quaternions (..., 4)."""
    conj = torch.cat([quat[..., :1], -quat[..., 1:]], dim=-1)
    return quat_apply(conj, vec)
