"""The ``tiling`` option of both styles that threshold with an image: a user's image that does not
tile gets its periodic component (the texture layer's ``load_texture(tiling="periodic")``).

Oracle: a ramp image whose left and right borders differ by the whole range; the halftone
screen seen raw (``show="screen"``) across uv repeats jumps at the repeat line without the option
and not with it. The threshold style's content is checked at the pyramid level in
tests/texture/test_tiling.py; here, that the option reaches it.
"""

from __future__ import annotations

import imageio.v3 as iio
import numpy as np
import pytest

from refnpr.render import render
from refnpr.styles import style_from_spec

from .test_threshold_tone import flat_scene

SIZE = 96


def _ramp(tmp_path) -> str:
    """A 64 x 64 8-bit image: a periodic pattern (two sine periods across) on a horizontal ramp
    that goes from 0.1 at the left border to 0.9 at the right (a photograph's lighting
    gradient: the borders do not meet)."""
    y, x = np.mgrid[0:64, 0:64] / 64.0
    img = 0.5 + 0.15 * np.sin(4 * np.pi * x) * np.cos(2 * np.pi * y) + 0.5 * (x * 64 / 63 - 0.5)
    path = tmp_path / "ramp.png"
    iio.imwrite(path, np.round(255 * img).astype(np.uint8))
    return str(path)


def _seam_jump(img: np.ndarray) -> float:
    """Largest mean |difference| between neighbouring columns (the repeat line when the image
    does not tile, a smooth step otherwise)."""
    grey = img[..., 0].astype(np.float64)
    return float(np.abs(np.diff(grey, axis=1)).mean(axis=0).max())


STYLES = {
    "threshold": lambda path, tiling: {
        "name": "threshold",
        "source": "image",
        "texture": path,
        "clahe_levels": "none",
        "uv_scale": [1.0, 1.0],
        "tiling": tiling,
    },
    "halftone": lambda path, tiling: {
        "name": "halftone",
        "threshold": "binary",
        "screen": {"kind": "dither", "texture": path, "rank_equalize": False, "tiling": tiling},
        "uv_scale": [1.0, 1.0],
        "show": "screen",
    },
}


def _render(name: str, path: str, tiling: str) -> np.ndarray:
    return render(flat_scene(0.5), style_from_spec(STYLES[name](path, tiling)), SIZE, SIZE, 1).rgba


def test_halftone_screen_tiling_periodic_removes_the_seam_of_a_user_image(tmp_path):
    path = _ramp(tmp_path)
    plain, tiled = _render("halftone", path, "none"), _render("halftone", path, "periodic")
    assert _seam_jump(plain) > 0.5  # the ramp's 0 -> 1 jump at every repeat
    assert _seam_jump(plain) > 3.0 * _seam_jump(tiled), (_seam_jump(plain), _seam_jump(tiled))


def test_threshold_tiling_reaches_the_image_pyramid(tmp_path):
    path = _ramp(tmp_path)
    plain, tiled = _render("threshold", path, "none"), _render("threshold", path, "periodic")
    assert np.array_equal(plain, _render("threshold", path, "none"))
    assert (plain != tiled).any(axis=-1).mean() > 0.05


def test_tiling_bad_values_name_the_parameter(tmp_path):
    path = _ramp(tmp_path)
    with pytest.raises(ValueError, match=r"tiling.*'none', 'periodic'"):
        style_from_spec(STYLES["threshold"](path, "wrap"))
    with pytest.raises(ValueError, match=r"screen.tiling: expected one of \['none', 'periodic'\]"):
        style_from_spec(STYLES["halftone"](path, "wrap"))
