"""Camera frames to the square uint8 images VLA servers expect."""

from __future__ import annotations

import torch
import torch.nn.functional as F


def resize_with_pad(frames: torch.Tensor, size: int) -> torch.Tensor:
    """(N, H, W, 3) uint8 -> (N, size, size, 3) uint8: scaled to fit, centred, black bars.

    The aspect ratio is kept (as openpi's clients do before sending), so a non-square
    camera is letterboxed rather than stretched; area-averaging when shrinking keeps
    thin edges from aliasing.
    """
    n, h, w, _ = frames.shape
    scale = size / max(h, w)
    new_h, new_w = max(1, round(h * scale)), max(1, round(w * scale))
    x = frames.permute(0, 3, 1, 2).float()
    if (new_h, new_w) != (h, w):
        x = F.interpolate(x, size=(new_h, new_w), mode="bilinear", antialias=True,
                          align_corners=False)
    top, left = (size - new_h) // 2, (size - new_w) // 2
    out = torch.zeros(n, 3, size, size, dtype=x.dtype, device=x.device)
    out[:, :, top:top + new_h, left:left + new_w] = x
    return out.round().clamp(0, 255).to(torch.uint8).permute(0, 2, 3, 1).contiguous()
