"""OpenEXR passes: one single-part EXR with the linear RGBA result and the G-buffer channels,
read back with the OpenEXR package and checked layer by layer against the G-buffer."""

from __future__ import annotations

import contextlib
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest

OpenEXR = pytest.importorskip("OpenEXR")

from refnpr.cli import main  # noqa: E402
from refnpr.exr import channel_names, pixel_passes, write_exr_channels  # noqa: E402
from refnpr.image import Image  # noqa: E402
from refnpr.render import render  # noqa: E402
from refnpr.sequence import render_sequence  # noqa: E402

W, H = 20, 14


def read_exr(path) -> dict[str, np.ndarray]:
    with OpenEXR.File(str(path), separate_channels=True) as f:
        assert len(f.parts) == 1
        return {name: np.array(c.pixels) for name, c in f.channels().items()}


def expected_layers(gb, k: int) -> dict[str, tuple[str, np.ndarray]]:
    """Independent of refnpr.exr: EXR channel -> (pixel type, values) from the sample grid."""
    n = gb.n
    want: dict[str, tuple[str, np.ndarray]] = {}
    names = {"depth": ["depth.Z"], "uv": ["uv.U", "uv.V"], "duv_dx": ["duv_dx.U", "duv_dx.V"]}
    names["duv_dy"] = ["duv_dy.U", "duv_dy.V"]
    for ch in gb.channels:
        a = gb[ch]
        pix = a if a.shape[:2] == (gb.height, gb.width) else a[k::n, k::n]
        if pix.ndim == 2:
            want[names.get(ch, [ch])[0]] = (
                ("uint", pix) if pix.dtype.kind in "iu" else ("float", pix)
            )
        else:
            comps = names.get(ch) or [f"{ch}.{c}" for c in "XYZW"[: pix.shape[2]]]
            for i, c in enumerate(comps):
                want[c] = ("float", pix[..., i])
    return want


def test_render_exr_holds_rgba_and_every_gbuffer_layer(tmp_path, capsys):
    spp, k = 4, 0  # n = 2: sample (0, 0) of each pixel, the upper-left of the central four
    exr = tmp_path / "out.exr"
    args = ["render", "--scene", "sphere", "--style", "toon", "--size", f"{W}x{H}"]
    assert main([*args, "--spp", str(spp), "-o", str(tmp_path / "o.png"), "--exr", str(exr)]) == 0
    assert "o.png and " in capsys.readouterr().out
    image, gb = render("sphere", "toon", W, H, spp, passes=True, return_gbuffer=True)
    plain = render("sphere", "toon", W, H, spp)
    np.testing.assert_array_equal(image.rgba, plain.rgba)  # the passes change no pixel
    assert {"depth", "position", "tri_id", "mesh_id", "normal", "uv"} <= set(gb.channels)

    got = read_exr(exr)
    rgba = image.rgba
    for i, c in enumerate("RGB"):
        np.testing.assert_array_equal(got[c], rgba[..., i] * rgba[..., 3])  # premultiplied
    np.testing.assert_array_equal(got["A"], rgba[..., 3])
    want = expected_layers(gb, k)
    kept = {"tone", "toon_tone"}  # the toon style's intermediates (test_exr_intermediates.py)
    assert set(got) == set(want) | set("RGBA") | kept
    for name in kept:
        np.testing.assert_array_equal(got[name], image.passes[name], err_msg=name)
    for name, (kind, values) in want.items():
        if kind == "uint":
            assert got[name].dtype == np.uint32, name
            np.testing.assert_array_equal(got[name].view(np.int32), values, err_msg=name)
        else:
            assert got[name].dtype == np.float32, name
            np.testing.assert_array_equal(got[name], values.astype(np.float32), err_msg=name)
    # the sphere covers the middle and leaves the corner empty: ids there are int32 -1
    assert got["tri_id"][0, 0] == 0xFFFFFFFF and got["tri_id"][H // 2, W // 2] < 0xFFFFFFFF
    assert np.isinf(got["depth.Z"][0, 0]) and np.isfinite(got["depth.Z"][H // 2, W // 2])


def test_pixel_passes_take_the_centre_sample_for_odd_n_and_keep_per_pixel_channels():
    n, h, w = 3, 2, 4
    grid = np.arange(n * h * n * w, dtype=np.float32).reshape(n * h, n * w)

    class Grid(SimpleNamespace):  # what pixel_passes reads of a GBuffer
        def __getitem__(self, name):
            return self.channels[name]

    channels = {"depth": grid, "normal": np.stack([grid] * 3, -1), "coverage": np.ones((h, w))}
    gb = Grid(n=n, width=w, height=h, channels=channels)
    got = pixel_passes(gb)
    for y in range(h):
        for x in range(w):  # sample (1, 1) of each 3 x 3 block: at the pixel centre
            assert got["depth"][y, x] == grid[n * y + 1, n * x + 1]
    assert got["normal"].shape == (h, w, 3) and got["coverage"].shape == (h, w)
    assert got["depth"].base is None or not np.shares_memory(got["depth"], grid)


def test_channel_names_follow_compositing_conventions():
    assert channel_names("depth", 0) == ("depth.Z",)
    assert channel_names("uv", 2) == ("uv.U", "uv.V")
    assert channel_names("normal", 3) == ("normal.X", "normal.Y", "normal.Z")
    assert channel_names("tri_id", 0) == ("tri_id",)
    assert channel_names("weights", 6)[-1] == "weights.5"


def test_an_image_without_passes_saves_rgba_only(tmp_path):
    rgba = np.random.default_rng(0).random((5, 7, 4)).astype(np.float32)
    Image(rgba).save(tmp_path / "a.exr")
    got = read_exr(tmp_path / "a.exr")
    assert sorted(got) == ["A", "B", "G", "R"]
    np.testing.assert_array_equal(got["G"], rgba[..., 1] * rgba[..., 3])


def test_bad_exr_targets_and_channels_are_clear_errors(tmp_path, capsys):
    image = Image(np.zeros((4, 4, 4), np.float32))
    with pytest.raises(ValueError, match=r"expected a \.png file name .* or a \.exr one"):
        image.save(tmp_path / "a.tif")
    with pytest.raises(ValueError, match=r"passes: 'depth' has shape \(3, 4\)"):
        Image(np.zeros((4, 4, 4), np.float32), passes={"depth": np.zeros((3, 4))})
    assert main(["render", "--size", "8x8", "--exr", str(tmp_path / "x.png")]) == 2
    assert "--exr: expected a .exr file name" in capsys.readouterr().err
    assert main(["render", "--size", "8x8", "-o", str(tmp_path / "o.png"), "--exr", ""]) == 2
    assert "--exr: expected a file name ending in .exr, got ''" in capsys.readouterr().err
    assert main(["render", "--size", "8x8", "--exr", str(tmp_path) + "/"]) == 2
    assert "names a directory (it ends with a slash)" in capsys.readouterr().err
    target = tmp_path / "c.exr"
    with pytest.raises(ValueError, match="every channel needs one shape"):
        write_exr_channels(target, {"R": np.zeros((2, 2)), "G": np.zeros((2, 3))})
    with pytest.raises(ValueError, match="dtype int64; expected float"):
        write_exr_channels(target, {"R": np.zeros((2, 2), np.int64)})
    assert not target.exists()


def test_a_full_disk_names_the_file_and_the_free_space(tmp_path):
    @contextlib.contextmanager
    def onto_a_full_disk(path, *, suffix=""):
        yield Path("/dev/full")

    # /dev/full takes no byte: OpenEXR may raise or leave an unreadable file; either is named
    with pytest.raises(ValueError, match=r"exr: writing '.*p\.exr' failed: .*(full|read back)"):
        write_exr_channels(
            tmp_path / "p.exr", {"R": np.ones((64, 64), np.float32)}, opener=onto_a_full_disk
        )


def test_animate_exr_frames_carry_the_passes(tmp_path):
    out = tmp_path / "frames"
    render_sequence("sphere", "toon", W, H, 1, out_dir=out, exr=True)
    got = read_exr(out / "frame_00000.exr")
    image, gb = render("sphere", "toon", W, H, 1, return_gbuffer=True, passes=True)
    np.testing.assert_array_equal(got["depth.Z"], gb["depth"])
    np.testing.assert_array_equal(got["mesh_id"].view(np.int32), gb["mesh_id"])
    np.testing.assert_array_equal(got["R"], image.rgba[..., 0] * image.rgba[..., 3])


def test_integer_passes_beyond_32_bits_are_split_or_refused(tmp_path):
    rgba = np.zeros((2, 3, 4), np.float32)
    ids = np.array([[-1, 5, 1 << 40], [7, (1 << 62) + 3, 0]], dtype=np.int64)
    Image(rgba, passes={"stroke_id": ids}).save(tmp_path / "s.exr")
    got = read_exr(tmp_path / "s.exr")
    back = (got["stroke_id.hi"].astype(np.uint64) << np.uint64(32)) | got["stroke_id.lo"]
    np.testing.assert_array_equal(back.view(np.int64), ids)
    with pytest.raises(ValueError, match=r"channel 'ids\.X' holds integers beyond 32 bits"):
        Image(rgba, passes={"ids": np.full((2, 3, 2), 1 << 40, np.int64)}).save(tmp_path / "t.exr")
    assert not (tmp_path / "t.exr").exists()
