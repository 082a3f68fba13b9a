"""Background images: the Radiance reader, the folder contract, backdrop variation."""

import pathlib

import numpy as np
import pytest

from dexbench.assets.backgrounds import BackgroundImageError, load_image, read_hdr
from dexbench.envs.variation import VisualVariation
from dexbench.tasks.registry import make_env


def _rgbe(linear: np.ndarray) -> np.ndarray:
    peak = linear.max(axis=-1)
    exp = np.where(peak > 0, np.floor(np.log2(np.maximum(peak, 1e-30))) + 1, -128)
    mant = np.clip(linear / np.exp2(exp)[..., None] * 256, 0, 255).astype(np.uint8)
    return np.concatenate([mant, (exp + 128).clip(0, 255).astype(np.uint8)[..., None]], -1)


def _rle_channel(values: np.ndarray) -> bytes:
    """Runs of equal values as (128 + n, v), everything else as literal chunks."""
    out, i = bytearray(), 0
    while i < len(values):
        run = 1
        while i + run < len(values) and run < 127 and values[i + run] == values[i]:
            run += 1
        if run >= 3:
            out += bytes([128 + run, values[i]])
            i += run
        else:
            n = min(128, len(values) - i)
            out += bytes([n]) + values[i:i + n].tobytes()
            i += n
    return bytes(out)


def _write_hdr(path: pathlib.Path, rgbe: np.ndarray, rle: bool) -> None:
    h, w, _ = rgbe.shape
    body = bytearray()
    for row in rgbe:
        if rle:
            body += bytes([2, 2, w >> 8, w & 255])
            for c in range(4):
                body += _rle_channel(row[:, c])
        else:
            body += row.tobytes()
    path.write_bytes(b"#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n-Y %d +X %d\n" % (h, w) + body)


@pytest.mark.parametrize("rle", [False, True])
def test_hdr_reader_decodes_flat_and_run_length_files(tmp_path, rle):
    rng = np.random.default_rng(0)
    linear = rng.uniform(0, 8, size=(12, 40, 3)).astype(np.float32)
    linear[3, 5:30] = 2.0  # a long run for the encoder
    rgbe = _rgbe(linear)
    _write_hdr(tmp_path / "a.hdr", rgbe, rle)
    decoded = read_hdr(tmp_path / "a.hdr")
    expected = rgbe[..., :3] * np.exp2(rgbe[..., 3].astype(np.float64) - 136)[..., None]
    np.testing.assert_allclose(decoded, expected, rtol=1e-6)
    np.testing.assert_allclose(decoded, linear, rtol=0, atol=8 / 128)  # RGBE quantization
    image = load_image(tmp_path / "a.hdr")
    assert image.dtype == np.uint8 and image.shape == (12, 40, 3)


def test_truncated_hdr_and_missing_folder_give_clear_errors(tmp_path):
    _write_hdr(tmp_path / "a.hdr", _rgbe(np.ones((8, 16, 3), np.float32)), rle=True)
    data = (tmp_path / "a.hdr").read_bytes()
    (tmp_path / "a.hdr").write_bytes(data[: len(data) // 2])
    with pytest.raises(BackgroundImageError, match="truncated or corrupt"):
        read_hdr(tmp_path / "a.hdr")
    with pytest.raises(BackgroundImageError, match=r"visual\.background_dir"):
        make_env("PickCube", visual=VisualVariation(enabled=True,
                                                    background_dir=str(tmp_path / "nope")))


def test_background_images_show_on_the_backdrop(tmp_path):
    """A user's image (here pure green) appears behind the scene in some environments."""
    from PIL import Image

    for i in range(2):  # image 0 is in the train pool, image 1 in the test pool
        Image.fromarray(np.full((32, 32, 3), (0, 255, 0) if i == 0 else (255, 0, 0),
                                np.uint8)).save(tmp_path / f"{i}.png")
    only_backdrop = VisualVariation(enabled=True, materials=False, lighting=False,
                                    exposure=False, camera_pose=False, camera_fov=False,
                                    background_dir=str(tmp_path))
    env = make_env("PickCube", num_envs=8, seed=0, obs="rgb", image_size=(32, 32),
                   visual=only_backdrop)
    rgb = env.reset()["rgb/front"][:, -1].float()
    top = rgb[:, :4].mean(dim=(1, 2))  # the wall above the table
    green = (top[:, 1] > 1.5 * top[:, 0]) & (top[:, 1] > 1.5 * top[:, 2])
    red = (top[:, 0] > 1.5 * top[:, 1]) & (top[:, 0] > 1.5 * top[:, 2])
    assert green.any() and not green.all(), top
    assert not red.any(), "a test-pool image showed in the train pool"
