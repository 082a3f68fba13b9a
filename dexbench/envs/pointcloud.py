"""Depth images to world-frame point clouds, cropping and farthest-point sampling.

All batched torch, so the same code serves CPU and GPU renderers. Cameras follow
MuJoCo's convention: they look along their -z axis with +y up in the image, and the
vertical field of view and square pixels fix the intrinsics.
"""

from __future__ import annotations

import torch


def depth_to_world(depth: torch.Tensor, fovy_deg: torch.Tensor, cam_pos: torch.Tensor,
                   cam_mat: torch.Tensor) -> torch.Tensor:
    """(N, H*W, 3) world points of depth images (N, H, W) (distance to image plane).

    `fovy_deg` is (N,): each world may have its own field of view.
    """
    n, h, w = depth.shape
    dtype, device = cam_pos.dtype, depth.device
    f = (0.5 * h / torch.tan(torch.deg2rad(fovy_deg.to(dtype)) / 2))[:, None, None]
    u = torch.arange(w, dtype=dtype, device=device) + 0.5 - w / 2
    v = torch.arange(h, dtype=dtype, device=device) + 0.5 - h / 2
    d = depth.to(dtype)
    local = torch.stack([u[None, None, :] * d / f, -v[None, :, None] * d / f, -d], dim=-1)
    world = local.reshape(n, -1, 3) @ cam_mat.to(dtype).transpose(1, 2)
    return world + cam_pos.to(dtype)[:, None]


def crop_mask(points: torch.Tensor, lo: tuple[float, float, float],
              hi: tuple[float, float, float]) -> torch.Tensor:
    """(N, P) whether points lie inside an axis-aligned box."""
    lo_t = torch.tensor(lo, dtype=points.dtype, device=points.device)
    hi_t = torch.tensor(hi, dtype=points.dtype, device=points.device)
    return ((points >= lo_t) & (points <= hi_t)).all(dim=-1)


def farthest_point_sample(points: torch.Tensor, mask: torch.Tensor, n: int) -> torch.Tensor:
    """(N, n) indices chosen by farthest-point sampling among the masked points.

    Starts from the first valid point of each cloud (deterministic). A cloud with no
    valid point yields index 0 throughout; one with fewer than n valid points repeats
    points once all have been taken. Masked points start at distance -1 and stay there
    (distances are never negative); the coordinates are laid out one plane per axis and
    updated in place, which makes the loop several times faster on the CPU than
    per-point vectors, with the same sums in the same order.
    """
    batch, count, _ = points.shape
    rows = torch.arange(batch, device=points.device)
    planes = points.permute(2, 0, 1).contiguous()
    dist = torch.full((batch, count), float("inf"), dtype=points.dtype, device=points.device)
    dist[~mask] = -1.0
    chosen = torch.zeros(batch, n, dtype=torch.long, device=points.device)
    step, term = torch.empty_like(dist), torch.empty_like(dist)
    current = mask.to(torch.int8).argmax(dim=1)
    for k in range(n):
        chosen[:, k] = current
        centre = points[rows, current]
        torch.sub(planes[0], centre[:, 0:1], out=step).square_()
        for axis in (1, 2):
            step.add_(torch.sub(planes[axis], centre[:, axis:axis + 1], out=term).square_())
        torch.minimum(dist, step, out=dist)
        current = dist.argmax(dim=1)
    return chosen


def sample_cloud(points: torch.Tensor, mask: torch.Tensor, n: int,
                 oversample: int = 4) -> torch.Tensor:
    """(N, n, 3) points: the masked points, thinned evenly to `oversample * n`, then FPS.

    Thinning by evenly spaced indices keeps the result deterministic and bounds the cost
    of farthest-point sampling whatever the image size.
    """
    keep = oversample * n
    rows, valid = [], []
    for cloud, m in zip(points, mask, strict=True):
        idx = m.nonzero().flatten()
        if len(idx) > keep:
            idx = idx[torch.linspace(0, len(idx) - 1, keep, device=idx.device).long()]
        count = len(idx)
        padded = torch.zeros(keep, dtype=torch.long, device=idx.device)
        padded[:count] = idx
        rows.append(cloud[padded])
        valid.append(torch.arange(keep, device=idx.device) < count)
    thinned, ok = torch.stack(rows), torch.stack(valid)
    chosen = farthest_point_sample(thinned.to(torch.float32), ok, n)
    return torch.gather(thinned, 1, chosen[..., None].expand(-1, -1, 3))
