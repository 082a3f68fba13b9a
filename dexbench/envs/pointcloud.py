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
    dtype, device = torch.float32, depth.device  # as the depth images: float32 is enough
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


def farthest_point_sample(points: torch.Tensor, mask: torch.Tensor, n: int,
                          kernel: bool = True) -> torch.Tensor:
    """(N, n) indices chosen by farthest-point sampling among the masked points.

    Starts from the first valid point of each cloud (deterministic). A cloud with no
    valid point yields index 0 throughout; one with fewer than n valid points repeats
    points once all have been taken. Masked points start at distance -1 and stay there
    (distances are never negative); the coordinates are laid out one plane per axis and
    updated in place, which makes the loop several times faster on the CPU than
    per-point vectors, with the same sums in the same order. On CUDA (float32, with
    `kernel`) the loop runs as one Triton kernel (`fps_triton`): same rule, a fraction of
    the time.
    """
    batch, count, _ = points.shape
    if kernel and points.is_cuda and points.dtype == torch.float32 and count > 0:
        from dexbench.envs import fps_triton

        if count <= fps_triton.MAX_POINTS:
            return fps_triton.farthest_point_sample_triton(points, mask, n)
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


def thin_evenly(mask: torch.Tensor, keep: int) -> tuple[torch.Tensor, torch.Tensor]:
    """(N, keep) indices of masked points, evenly spaced among them when more than `keep`
    are masked, and (N, keep) whether each slot holds one.

    Ranks from a cumulative sum and a sorted search select the points of every cloud at
    once, without reading the counts back to the host: one GPU sync per cloud was the
    cost of replaying datasets to point clouds.
    """
    count = mask.sum(dim=1, keepdim=True)
    rank = mask.to(torch.int64).cumsum(dim=1)
    slot = torch.arange(keep, device=mask.device)[None]
    want = torch.where(count > keep, slot * (count - 1) // max(keep - 1, 1), slot)
    idx = torch.searchsorted(rank, want + 1).clamp_(max=mask.shape[1] - 1)
    return idx, slot < count


def sample_cloud(points: torch.Tensor, mask: torch.Tensor, n: int,
                 oversample: int = 4) -> torch.Tensor:
    """(N, n, 3) points: the masked points, thinned evenly to `oversample * n`, then FPS.

    Thinning by evenly spaced indices keeps the result deterministic and bounds the cost
    of farthest-point sampling whatever the image size.
    """
    idx, ok = thin_evenly(mask, oversample * n)
    thinned = torch.gather(points, 1, idx[..., None].expand(-1, -1, 3))
    chosen = farthest_point_sample(thinned.to(torch.float32), ok, n)
    return torch.gather(thinned, 1, chosen[..., None].expand(-1, -1, 3))
