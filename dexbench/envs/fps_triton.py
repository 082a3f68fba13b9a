"""Farthest-point sampling as one Triton kernel per batch of clouds (CUDA).

The torch loop in `pointcloud.farthest_point_sample` launches about ten small kernels per
chosen point, 5,000 per batch for 512 points: on a GPU its time is launch overhead, and it
was most of the time of replaying demonstrations to point clouds. Here one program per
cloud keeps the cloud's coordinates and distances in registers and runs the whole loop.
Same rule as the torch loop (first valid point first, masked points at distance -1, ties
to the lowest index); the sums may differ from it in the last bit (fused multiply-adds),
hence the choice in rare near-ties.
"""

from __future__ import annotations

import torch
import triton
import triton.language as tl

MAX_POINTS = 8192
"""Clouds up to this many candidate points run in registers; larger ones use the torch loop."""


@triton.jit
def _fps_kernel(planes_ptr, valid_ptr, out_ptr, batch, count, n, BLOCK: tl.constexpr):
    cloud = tl.program_id(0)
    offs = tl.arange(0, BLOCK)
    inside = offs < count
    row = cloud * count
    x = tl.load(planes_ptr + row + offs, mask=inside, other=0.0)
    y = tl.load(planes_ptr + batch * count + row + offs, mask=inside, other=0.0)
    z = tl.load(planes_ptr + 2 * batch * count + row + offs, mask=inside, other=0.0)
    valid = tl.load(valid_ptr + row + offs, mask=inside, other=0) != 0
    dist = tl.where(valid, float("inf"), -1.0)
    dist = tl.where(inside, dist, -2.0)
    current = tl.argmax(tl.where(valid, 1, 0), axis=0)
    for k in range(n):
        tl.store(out_ptr + cloud * n + k, current)
        cx = tl.load(planes_ptr + row + current)
        cy = tl.load(planes_ptr + batch * count + row + current)
        cz = tl.load(planes_ptr + 2 * batch * count + row + current)
        dx = x - cx
        dy = y - cy
        dz = z - cz
        step = dx * dx + dy * dy + dz * dz
        dist = tl.minimum(dist, step)
        current = tl.argmax(dist, axis=0)


def farthest_point_sample_triton(points: torch.Tensor, mask: torch.Tensor,
                                 n: int) -> torch.Tensor:
    """(N, n) int64 indices, as `pointcloud.farthest_point_sample`, for float32 CUDA
    clouds of at most `MAX_POINTS` points."""
    batch, count, _ = points.shape
    planes = points.permute(2, 0, 1).contiguous()
    valid = mask.to(torch.int8).contiguous()
    out = torch.empty(batch, n, dtype=torch.int32, device=points.device)
    block = max(triton.next_power_of_2(count), 16)
    _fps_kernel[(batch,)](planes, valid, out, batch, count, n, BLOCK=block,
                          num_warps=8 if block >= 2048 else 4)
    return out.to(torch.int64)
