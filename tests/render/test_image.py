"""Image: sRGB encoding, atomic PNG writes, invalid pixels."""

import numpy as np
import pytest

import refnpr.image as image_mod
from refnpr.image import Image, linear_to_srgb, srgb_to_linear


def test_srgb_round_trip_and_known_values():
    x = np.linspace(0, 1, 1001)
    np.testing.assert_allclose(srgb_to_linear(linear_to_srgb(x)), x, atol=1e-12)
    # IEC 61966-2-1 reference points: linear 0.5 -> 0.7354, 0.0031308 -> 0.04045
    np.testing.assert_allclose(linear_to_srgb([0.5, 0.0031308]), [0.735357, 0.04045], atol=1e-5)


def test_save_round_trip(tmp_path):
    import imageio.v3 as iio

    rgba = np.zeros((3, 4, 4), np.float32)
    rgba[..., 3] = 1
    rgba[1, 2] = [1.0, 0.5, 0.0, 1.0]
    path = Image(rgba).save(tmp_path / "a.png")
    back = iio.imread(path)
    assert back.shape == (3, 4, 4)
    assert back[1, 2].tolist() == [255, 188, 0, 255]


def test_failed_write_leaves_no_file(tmp_path, monkeypatch):
    import imageio.v3 as iio

    def boom(*args, **kwargs):
        raise OSError("disk full")

    monkeypatch.setattr(iio, "imwrite", boom)
    with pytest.raises(OSError, match="disk full"):
        image_mod.write_png_atomic(tmp_path / "x.png", np.zeros((2, 2, 4), np.uint8))
    assert list(tmp_path.iterdir()) == []


def test_nan_image_rejected():
    rgba = np.zeros((2, 2, 4), np.float32)
    rgba[0, 0, 0] = np.nan
    with pytest.raises(ValueError, match="NaN or inf"):
        Image(rgba)


def test_png_suffix_required(tmp_path):
    with pytest.raises(ValueError, match=r"path: expected a .png file name"):
        Image(np.zeros((2, 2, 4), np.float32)).save(tmp_path / "x.jpg")
