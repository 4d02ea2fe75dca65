"""Jupyter display: ``Image`` and ``GBuffer`` show themselves (``_repr_png_``).

Oracles: the PNG decoder (imageio) and the G-buffer's own arrays; the labels are found by
matching the font's bitmap in the decoded picture, the layout by the documented cell origins.
"""

from __future__ import annotations

import imageio.v3 as iio
import numpy as np
import pytest

from refnpr.image import Image
from refnpr.raster import Camera, rasterize
from refnpr.raster import _display as disp
from refnpr.scenes import icosphere, load_scene

CHANNELS = (
    "depth",
    "tri_id",
    "mesh_id",
    "coverage",
    "normal",
    "uv",
    "duv_dx",
    "duv_dy",
    "dyadic_scale",
)


@pytest.fixture(scope="module")
def gbuffer():
    scene = load_scene("teapot")
    return rasterize(scene, scene.camera, 160, 120, CHANNELS, spp=4, line_period=4.0)


def test_image_png_round_trips_to_srgb8():
    rng = np.random.default_rng(3)
    rgba = rng.random((17, 23, 4)).astype(np.float32)
    image = Image(rgba)
    png = image._repr_png_()
    assert png[:8] == b"\x89PNG\r\n\x1a\n"
    decoded = iio.imread(png)
    assert decoded.shape == (17, 23, 4) and decoded.dtype == np.uint8
    np.testing.assert_array_equal(decoded, image.to_srgb8())
    assert image.to_png_bytes() == png


def _tile_origins(n_tiles: int, th: int, tw: int, columns: int = 4):
    strip = disp.GLYPH_H * 2 + 2 * disp.PAD
    ncol = min(columns, n_tiles)
    for k in range(n_tiles):
        y0 = disp.GAP + (k // ncol) * (strip + th + disp.GAP)
        x0 = disp.GAP + (k % ncol) * (tw + disp.GAP)
        yield y0, x0, strip


def test_gbuffer_png_decodes_with_one_labelled_tile_per_channel(gbuffer):
    png = gbuffer._repr_png_()
    grid = iio.imread(png)
    tiles = disp.channel_tiles(gbuffer.channels, gbuffer.height, gbuffer.width)
    labels = [label for label, _ in tiles]
    # every channel, vector derivatives split per component
    expected = ["depth", "tri_id", "mesh_id", "coverage", "normal", "uv", "duv_dx.u", "duv_dx.v"]
    expected += ["duv_dy.u", "duv_dy.v", "dyadic_scale"]
    assert labels == expected
    th, tw = tiles[0][1].shape[:2]
    assert (th, tw) == (120, 160)  # below max_tile: the pixel size, aspect kept
    strip = disp.GLYPH_H * 2 + 2 * disp.PAD
    rows = -(-len(tiles) // 4)
    assert grid.shape == (
        disp.GAP + rows * (strip + th + disp.GAP),
        disp.GAP + 4 * (tw + disp.GAP),
        3,
    )
    for (label, tile), (y0, x0, strip) in zip(
        tiles, _tile_origins(len(tiles), th, tw), strict=True
    ):
        np.testing.assert_array_equal(grid[y0 + strip : y0 + strip + th, x0 : x0 + tw], tile)
        bits = disp.label_bitmap(label, disp.label_scale(label, tw))
        ly = y0 + disp.PAD + (disp.GLYPH_H * 2 - bits.shape[0]) // 2
        region = grid[ly : ly + bits.shape[0], x0 + disp.PAD : x0 + disp.PAD + bits.shape[1]]
        ink = np.all(region == disp.INK, axis=-1)
        np.testing.assert_array_equal(ink, bits, err_msg=f"label {label!r} not drawn")


def test_labels_differ_between_channel_names():
    a, b = disp.label_bitmap("duv_dx"), disp.label_bitmap("duv_dy")
    assert a.shape == b.shape == (5, 4 * 6 - 1)
    assert (a != b).any() and a.any()
    assert disp.label_bitmap("uv", 2).shape == (10, 14)
    with pytest.raises(ValueError, match="scale: expected an integer >= 1, got 0"):
        disp.label_bitmap("uv", 0)


def test_large_buffers_are_downscaled_to_max_tile():
    scene = load_scene("sphere")
    gb = rasterize(scene, scene.camera, 1024, 512, ("depth", "tri_id"), spp=1)
    tiles = disp.channel_tiles(gb.channels, gb.height, gb.width)
    assert all(t.shape[:2] == (128, 256) for _, t in tiles)
    grid = iio.imread(gb._repr_png_())
    assert max(grid.shape[:2]) < 600
    with pytest.raises(ValueError, match="max_tile: expected an integer >= 8"):
        disp.channel_tiles(gb.channels, gb.height, gb.width, max_tile=2)


def test_ids_are_false_coloured_distinctly(gbuffer):
    tiles = dict(disp.channel_tiles(gbuffer.channels, gbuffer.height, gbuffer.width))
    tri = gbuffer["tri_id"][1::2, 1::2]  # the sample each tile pixel shows (nearest, n = 2)
    colours = tiles["tri_id"].reshape(-1, 3)
    ids = tri.reshape(-1)
    covered = ids >= 0
    # one colour per id, and neighbouring ids (id, id + 1) far apart in colour
    table = {}
    for i, c in zip(ids[covered], colours[covered], strict=True):
        table.setdefault(int(i), set()).add(tuple(c))
    assert all(len(v) == 1 for v in table.values())
    present = sorted(table)
    assert len(present) > 50
    pairs = [(i, i + 1) for i in present if i + 1 in table]
    dist = [
        np.abs(np.subtract(next(iter(table[i])), next(iter(table[j])), dtype=float)).max()
        for i, j in pairs
    ]
    assert min(dist) > 60  # no two consecutive triangles share a shade
    distinct = {c for v in table.values() for c in v}
    assert len(distinct) >= 0.95 * len(table)
    # background is marked with the checkerboard, never an id colour
    bg = colours[~covered]
    assert len(bg) and set(map(tuple, bg)) <= {
        tuple(np.rint(c * 255).astype(int)) for c in disp._CHECKER
    }


def test_hash_colours_of_consecutive_ids_are_unrelated():
    c = disp.hash_colors(np.arange(-1, 5000))
    assert c.shape == (5001, 3) and c.min() >= 0.0 and c.max() <= 1.0
    step = np.abs(np.diff(c, axis=0)).max(axis=1)
    assert step.min() > 0.25 and np.median(step) > 0.4
    # ids far apart whose golden-ratio hues nearly repeat (Fibonacci gaps) mostly differ too
    gap = np.abs(c[89:] - c[:-89]).max(axis=1)
    assert np.mean(gap > 0.05) > 0.8


def test_symmetric_map_is_symmetric_and_white_at_zero():
    v = np.linspace(-2, 2, 9)
    c = disp.symmetric_colors(v)
    np.testing.assert_allclose(c[4], [1, 1, 1])
    assert c[0, 2] > c[0, 0] and c[-1, 0] > c[-1, 2]  # blue below zero, red above
    np.testing.assert_allclose(1 - c[:4], (1 - c[5:][::-1]) * (1 - disp._NEG) / (1 - disp._POS))


def test_depth_normals_and_uv_encodings():
    sphere = icosphere(3)
    cam = Camera.look_at((0, 0, 3), (0, 0, 0), (0, 1, 0), 45, 0.1, 10)
    gb = rasterize(sphere, cam, 64, 64, ("depth", "tri_id", "normal", "uv"))
    tiles = dict(disp.channel_tiles(gb.channels, gb.height, gb.width))
    mask = gb["tri_id"] >= 0
    depth = tiles["depth"][..., 0].astype(float)
    near = np.unravel_index(np.argmin(np.where(mask, gb["depth"], np.inf)), mask.shape)
    far = np.unravel_index(np.argmax(np.where(mask, gb["depth"], -np.inf)), mask.shape)
    assert depth[near] == 255 and depth[far] == 0  # normalised, near bright
    expected_n = np.rint(np.clip(0.5 * gb["normal"] + 0.5, 0, 1) * 255)
    np.testing.assert_array_equal(tiles["normal"][mask], expected_n[mask])
    uv = gb["uv"]
    assert uv[mask].min() >= 0 and uv[mask].max() <= 1
    np.testing.assert_array_equal(tiles["uv"][mask][:, :2], np.rint(uv[mask] * 255))
    assert not tiles["uv"][mask][:, 2].any()


def test_coverage_shows_partial_pixels_and_marks_only_empty_ones():
    scene = load_scene("sphere")
    gb = rasterize(scene, scene.camera, 48, 36, ("tri_id", "coverage"), spp=4)
    tiles = dict(disp.channel_tiles(gb.channels, gb.height, gb.width))
    cov = gb["coverage"]
    partial = (cov > 0) & (cov < 1)
    assert partial.any()
    grey = tiles["coverage"][..., 0]
    np.testing.assert_array_equal(grey[cov > 0], np.rint(cov[cov > 0] * 255))
    checker = {int(np.rint(c[0] * 255)) for c in disp._CHECKER}
    assert set(np.unique(grey[cov == 0]).tolist()) <= checker
