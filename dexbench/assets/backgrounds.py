"""Background images for the arena backdrop: procedural ones, and users' own files.

Radiance `.hdr` panoramas (the common free HDRI format) are decoded here and tone-mapped
to 8 bits, since MuJoCo textures are 8-bit; `.png` and `.jpg` files are read with
Pillow. Images are downsampled to at most `MAX_SIDE` pixels per side so a folder of 4k
panoramas does not bloat every compiled model.
"""

from __future__ import annotations

import pathlib
import re

import mujoco
import numpy as np

IMAGE_SUFFIXES = (".hdr", ".png", ".jpg", ".jpeg")
MAX_SIDE = 512


class BackgroundImageError(ValueError):
    """A background file that cannot be read."""


def _rle_scanline(data: bytes, pos: int, width: int) -> tuple[np.ndarray, int]:
    """One new-style run-length-encoded RGBE scanline: four channel planes in turn."""
    line = np.empty((4, width), np.uint8)
    for channel in range(4):
        x = 0
        while x < width:
            count = data[pos]
            pos += 1
            if count > 128:  # a run of one value
                count -= 128
                line[channel, x:x + count] = data[pos]
                pos += 1
            else:
                line[channel, x:x + count] = np.frombuffer(data, np.uint8, count, pos)
                pos += count
            x += count
        if x != width:
            raise BackgroundImageError("corrupt run-length data")
    return line.T, pos


def read_hdr(path: pathlib.Path) -> np.ndarray:
    """Decode a Radiance RGBE file into linear float32 RGB, (H, W, 3)."""
    data = path.read_bytes()
    header_end = data.find(b"\n\n")
    if not data.startswith((b"#?RADIANCE", b"#?RGBE")) or header_end < 0:
        raise BackgroundImageError(f"{path} is not a Radiance .hdr file")
    size_end = data.index(b"\n", header_end + 2)
    match = re.fullmatch(rb"-Y (\d+) \+X (\d+)", data[header_end + 2:size_end].strip())
    if match is None:
        raise BackgroundImageError(f"{path}: only the standard -Y H +X W orientation is read")
    height, width = int(match[1]), int(match[2])
    pos = size_end + 1
    rgbe = np.empty((height, width, 4), np.uint8)
    try:
        for y in range(height):
            if 8 <= width < 32768 and data[pos:pos + 2] == b"\x02\x02":
                rgbe[y], pos = _rle_scanline(data, pos + 4, width)
            else:  # flat scanline
                rgbe[y] = np.frombuffer(data, np.uint8, width * 4, pos).reshape(width, 4)
                pos += width * 4
    except (IndexError, ValueError) as err:
        raise BackgroundImageError(f"{path} is truncated or corrupt ({err})") from None
    scale = np.ldexp(1.0, rgbe[..., 3].astype(np.int32) - 136)
    rgb = rgbe[..., :3] * scale[..., None]
    rgb[rgbe[..., 3] == 0] = 0.0
    return rgb.astype(np.float32)


def tone_map(linear: np.ndarray) -> np.ndarray:
    """Linear radiance to 8-bit sRGB-like values: exposure to the median, Reinhard, gamma."""
    lum = linear @ np.array([0.2126, 0.7152, 0.0722], np.float32)
    exposed = linear * (0.18 / max(float(np.median(lum)), 1e-6))
    mapped = exposed / (1.0 + exposed)
    return (np.clip(mapped, 0, 1) ** (1 / 2.2) * 255 + 0.5).astype(np.uint8)


def _downsample(image: np.ndarray) -> np.ndarray:
    step = int(np.ceil(max(image.shape[:2]) / MAX_SIDE))
    return np.ascontiguousarray(image[::step, ::step]) if step > 1 else image


def load_image(path: pathlib.Path) -> np.ndarray:
    """An image file as uint8 RGB (H, W, 3), at most MAX_SIDE pixels per side."""
    if path.suffix.lower() == ".hdr":
        return _downsample(tone_map(_downsample(read_hdr(path))))
    from PIL import Image, UnidentifiedImageError

    try:
        with Image.open(path) as image:
            image.thumbnail((MAX_SIDE, MAX_SIDE))
            return np.asarray(image.convert("RGB"))
    except (OSError, UnidentifiedImageError) as err:
        raise BackgroundImageError(f"cannot read background image {path}: {err}") from None


def list_images(folder: str | pathlib.Path) -> list[pathlib.Path]:
    """The background files of a folder, sorted by name, or a clear error."""
    root = pathlib.Path(folder).expanduser()
    if not root.is_dir():
        raise BackgroundImageError(
            f"background folder {root} does not exist: point visual.background_dir at a "
            f"folder of {', '.join(IMAGE_SUFFIXES)} images")
    files = sorted(p for p in root.iterdir() if p.suffix.lower() in IMAGE_SUFFIXES)
    if not files:
        raise BackgroundImageError(f"no {', '.join(IMAGE_SUFFIXES)} images in {root}")
    return files


NUM_PROCEDURAL = 8
DEFAULT = "bg/default"


def add_background_library(spec: mujoco.MjSpec, images: list[pathlib.Path] = ()) -> list[str]:
    """Add the backdrop materials: `bg/default` (the sky-like gradient every scene shows
    without variation), NUM_PROCEDURAL procedural ones (`bg/proc<i>`: gradients, flat
    colours, speckle) and one per image file (`bg/img<i>`); return the varied ones."""
    sky = spec.add_texture(name="bg/default", type=mujoco.mjtTexture.mjTEXTURE_2D,
                           builtin=mujoco.mjtBuiltin.mjBUILTIN_GRADIENT, width=256, height=256,
                           rgb1=[0.55, 0.65, 0.8], rgb2=[0.1, 0.1, 0.15])
    names = [_material(spec, DEFAULT, sky.name)]
    rng = np.random.default_rng(7)
    for i in range(NUM_PROCEDURAL):
        top, bottom = rng.uniform(0.05, 0.95, size=(2, 3))
        tex = spec.add_texture(name=f"bg/proc{i}", type=mujoco.mjtTexture.mjTEXTURE_2D,
                               width=128, height=128, rgb1=list(top), rgb2=list(bottom))
        tex.builtin = (mujoco.mjtBuiltin.mjBUILTIN_GRADIENT if i % 3 != 1
                       else mujoco.mjtBuiltin.mjBUILTIN_FLAT)
        if i % 3 == 2:
            tex.mark = mujoco.mjtMark.mjMARK_RANDOM
            tex.random = 0.05
            tex.markrgb = list(rng.uniform(0, 1, size=3))
        names.append(_material(spec, tex.name, tex.name))
    for i, path in enumerate(images):
        pixels = load_image(path)
        tex = spec.add_texture(name=f"bg/img{i}", type=mujoco.mjtTexture.mjTEXTURE_2D,
                               width=pixels.shape[1], height=pixels.shape[0], nchannel=3)
        tex.data = np.ascontiguousarray(pixels).tobytes()
        names.append(_material(spec, tex.name, tex.name))
    return names[1:]


def _material(spec: mujoco.MjSpec, name: str, texture: str) -> str:
    mat = spec.add_material(name=name, texrepeat=[1.0, 1.0], emission=0.6)
    mat.textures[mujoco.mjtTextureRole.mjTEXROLE_RGB] = texture
    return mat.name


def background_pool(names: list[str], split: str) -> list[str]:
    """The `train` (even) or `test` (odd) half of the procedural backgrounds and, likewise,
    of the user's images, so evaluation can use backgrounds never seen in training."""
    first = 0 if split == "train" else 1
    procedural = [n for n in names if n.startswith("bg/proc")]
    images = [n for n in names if n.startswith("bg/img")]
    return procedural[first::2] + images[first::2]
