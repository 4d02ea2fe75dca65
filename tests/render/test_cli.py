"""The refnpr command, called in-process through main(argv)."""

import imageio.v3 as iio
import pytest

from refnpr.cli import main


def test_render_default_scene(tmp_path, capsys):
    out = tmp_path / "o.png"
    assert main(["render", "--size", "64x48", "-o", str(out)]) == 0
    assert iio.imread(out).shape == (48, 64, 4)
    assert "wrote" in capsys.readouterr().out


def test_render_with_style_params(tmp_path):
    out = tmp_path / "o.png"
    rc = main(
        [
            "render",
            "--scene",
            "sphere",
            "--style",
            "toon",
            "--param",
            "n=4",
            "--param",
            "mode=lake",
            "--size",
            "32x32",
            "--spp",
            "4",
            "-o",
            str(out),
            "-q",
        ]
    )
    assert rc == 0 and out.exists()


def test_bad_spp_is_a_clear_error(tmp_path, capsys):
    rc = main(["render", "--size", "8x8", "--spp", "3", "-o", str(tmp_path / "x.png")])
    assert rc == 2
    assert "spp: expected a square number of samples per pixel" in capsys.readouterr().err
    assert not (tmp_path / "x.png").exists()


def test_bad_size_rejected_by_parser(capsys):
    with pytest.raises(SystemExit):
        main(["render", "--size", "0x5"])
    assert "width and height must be positive" in capsys.readouterr().err


def test_scenes_styles_info(capsys):
    assert main(["scenes"]) == 0
    assert "teapot" in capsys.readouterr().out
    assert main(["styles"]) == 0
    assert "toon" in capsys.readouterr().out
    assert main(["info"]) == 0
    assert "numba threads" in capsys.readouterr().out
    assert main(["styles", "threshold", "--markdown"]) == 0
    assert capsys.readouterr().out.startswith("| parameter |")
    assert main(["styles", "--markdown"]) == 2  # one style's table: which one?
    assert (
        "--markdown: prints one style's parameter table; name the style" in capsys.readouterr().err
    )


def test_compare_command(tmp_path, capsys):
    ref, cand = tmp_path / "ref", tmp_path / "cand"
    main(["render", "--scene", "sphere", "--size", "32x24", "-o", str(ref / "s.png"), "-q"])
    main(["render", "--scene", "sphere", "--size", "32x24", "-o", str(cand / "s.png"), "-q"])
    assert main(["compare", str(ref), str(cand), "--out", str(tmp_path / "d")]) == 0
    assert "1 passed, 0 failed" in capsys.readouterr().out
    main(
        [
            "render",
            "--scene",
            "sphere",
            "--style",
            "smooth",
            "--size",
            "32x24",
            "-o",
            str(cand / "s.png"),
            "-q",
        ]
    )
    assert main(["compare", str(ref), str(cand)]) == 1


def test_golden_check_on_a_suite(tmp_path, capsys):
    suite = tmp_path / "suite.toml"
    suite.write_text("[[case]]\nname = 'a'\nscene = 'sphere'\nwidth = 16\nheight = 12\n")
    assert main(["golden", "--check", "--suite", str(suite)]) == 1
    assert "0 passed, 1 failed" in capsys.readouterr().out
    assert main(["golden", "--update", "--suite", str(suite)]) == 0
    assert main(["golden", "--suite", str(suite)]) == 0


def test_output_path_checked_before_rendering(tmp_path, capsys):
    (tmp_path / "d.png").mkdir()
    assert main(["render", "--size", "8x8", "-o", str(tmp_path / "d.png")]) == 2
    assert "is a directory" in capsys.readouterr().err
    assert main(["render", "--size", "8x8", "-o", str(tmp_path / "x.jpg")]) == 2
    assert "error: -o/--output: expected a .png file name" in capsys.readouterr().err
    assert main(["render", "--size", "8x8", "-o", ""]) == 2  # not "'' is a directory"
    assert "error: -o/--output: expected a file name ending in .png, got ''" in (
        capsys.readouterr().err
    )


def test_missing_scene_file_is_a_clear_error(tmp_path, capsys):
    assert (
        main(["render", "--scene", str(tmp_path / "nope.toml"), "-o", str(tmp_path / "a.png")]) == 2
    )
    assert "nope.toml" in capsys.readouterr().err


def test_written_png_has_the_usual_file_mode(tmp_path):
    import os

    out = tmp_path / "m.png"
    assert main(["render", "--size", "8x8", "-o", str(out), "-q"]) == 0
    umask = os.umask(0)
    os.umask(umask)
    assert (out.stat().st_mode & 0o777) == (0o666 & ~umask)


def test_compare_rejects_nan_tolerance(tmp_path, capsys):
    with pytest.raises(SystemExit):
        main(["compare", str(tmp_path), str(tmp_path), "--tolerance", "nan"])
    assert "--tolerance: expected a value in [0, 1]" in capsys.readouterr().err


def test_compare_json_is_valid_json_with_missing_images(tmp_path):
    import json

    ref, cand = tmp_path / "ref", tmp_path / "cand"
    main(["render", "--scene", "sphere", "--size", "16x12", "-o", str(ref / "s.png"), "-q"])
    cand.mkdir()
    assert main(["compare", str(ref), str(cand), "--json", str(tmp_path / "r.json")]) == 1
    rows = json.loads((tmp_path / "r.json").read_text())  # strict JSON: no Infinity
    assert rows[0]["status"] == "missing" and rows[0]["max_abs"] is None


# --- the default render: what `refnpr render -o out.png` shows a newcomer ------------------


@pytest.fixture(scope="module")
def default_render(tmp_path_factory):
    """``refnpr render -o out.png`` with no other option: the PNG's luminance (sRGB, 0..1),
    its printed report, and the default scene's coverage at the same size (an independent
    G-buffer, spp 1)."""
    import numpy as np

    from refnpr.raster import rasterize
    from refnpr.scenes import load_scene

    out = tmp_path_factory.mktemp("default") / "out.png"
    assert main(["render", "-o", str(out), "-q"]) == 0
    png = iio.imread(out)
    lum = png[..., :3].astype(np.float64) @ np.array([0.2126, 0.7152, 0.0722]) / 255.0
    scene = load_scene("default")
    h, w = lum.shape
    gb = rasterize(scene, scene.camera, w, h, channels=("tri_id", "mesh_id", "position"))
    return png, lum, gb


def _rings(covered):
    """Covered pixels with an uncovered 4-neighbour (inner) and uncovered pixels with a covered
    4-neighbour (outer)."""
    import numpy as np

    p = np.pad(covered, 1)
    nbrs = [p[:-2, 1:-1], p[2:, 1:-1], p[1:-1, :-2], p[1:-1, 2:]]
    any_un = ~nbrs[0] | ~nbrs[1] | ~nbrs[2] | ~nbrs[3]
    any_co = nbrs[0] | nbrs[1] | nbrs[2] | nbrs[3]
    return covered & any_un, ~covered & any_co


def test_default_render_is_a_wide_frame(default_render):
    png, _, _ = default_render
    h, w = png.shape[:2]
    assert (w, h) == (768, 432) and w / h >= 16 / 9 - 1e-9


def test_default_render_draws_contours_along_the_silhouette(default_render):
    """Every silhouette pixel (against the background) has dark ink within one pixel. The
    engraving alone leaves the lit side's silhouette white on white (measured: 60% of the
    silhouette inked without the contours; 58% for the old flat toon default)."""
    import numpy as np

    _, lum, gb = default_render
    inner, _ = _rings(gb["tri_id"] >= 0)
    h, w = lum.shape
    p = np.pad(lum, 1, constant_values=1.0)
    darkest = np.min(
        [p[1 + dy : h + 1 + dy, 1 + dx : w + 1 + dx] for dy in (-1, 0, 1) for dx in (-1, 0, 1)],
        axis=0,
    )
    assert inner.sum() > 1000
    assert (darkest[inner] < 0.65).mean() >= 0.98  # measured 1.0


def test_default_render_is_anti_aliased(default_render):
    """Background pixels touching the teapot take intermediate values (partial coverage of
    samples and of the anti-aliased contour), not only the background's white: an spp-1 toon
    render has none (measured 0.0), the default 0.95."""
    _, lum, gb = default_render
    _, outer = _rings(gb["tri_id"] >= 0)
    edge = lum[outer]
    assert ((edge > 0.02) & (edge < 0.98)).mean() > 0.5


def test_default_render_lid_rim_is_a_line_not_dots(default_render):
    """Where the front of the rim meets the lid, the rim's bead turns away from the camera in a
    band thinner than a pixel; at spp 1 a toon render samples it as a dotted line (ink >= 0.5
    in 21% of the columns, measured). The default render draws it as a continuous contour:
    every column along the front rim has at least half a pixel of ink there."""
    import numpy as np

    _, lum, gb = default_render
    pos, on = gb["position"], gb["mesh_id"] == 0
    r = np.hypot(pos[..., 0], pos[..., 2])
    lid = on & (r < 1.31) & (pos[..., 1] > 2.39)  # the lid's skirt ends at r = 1.3
    rim = on & (r > 1.33) & (r < 1.52) & (pos[..., 1] > 2.39)  # the rim bead, r in [1.4, 1.5]
    ys, xs = np.nonzero(lid[:-1] & rim[1:] & (pos[1:, :, 2] > 0.3))  # lid above the front rim
    assert np.unique(xs).size > 150  # the front rim spans ~220 columns at 768x432
    ink = np.array([(1.0 - lum[y - 2 : y + 4, x]).sum() for y, x in zip(ys, xs, strict=True)])
    assert (ink >= 0.5).mean() >= 0.98  # measured 1.0 (no contours: 0.06)


def test_a_param_nested_too_deeply_is_a_usage_error(capsys):
    deep = "[" * 100_000 + "]" * 100_000
    with pytest.raises(SystemExit) as info:
        main(["render", "--param", f"n={deep}", "-o", "x.png"])
    assert info.value.code == 2
    assert "--param: the value of 'n' nests arrays or tables too deeply" in capsys.readouterr().err


def test_param_warns_for_what_the_user_gave_not_for_the_scene_table(tmp_path, capsys):
    """veryovka_dolly's [style] sets uniform = true for its lines; --param source=image reads no
    uniform, and the scene's own value drops out without a warning the user cannot act on."""
    out = str(tmp_path / "d.png")
    args = ["render", "--scene", "veryovka_dolly", "--size", "16x12", "--spp", "1", "-o", out]
    assert main([*args, "-q", "--param", "source=image"]) == 0
    assert capsys.readouterr().err == ""
    assert main([*args, "-q", "--param", "source=image", "--param", "uniform=true"]) == 0
    assert "warning: uniform: True is ignored with source='image'" in capsys.readouterr().err
    scene = tmp_path / "c.toml"  # the same with a contour layer in the table
    scene.write_text(
        '[camera]\neye = [0.0, 0.5, 4.0]\ntarget = [0.0, 0.0, 0.0]\n[style]\nname = "threshold"\n'
        'source = "lines"\nuniform = true\ncontours = { width = 1.5 }\n[[object]]\nmesh = "uv_sphere"\n'
    )
    args = ["render", "--scene", str(scene), "--size", "16x12", "--spp", "1", "-o", out, "-q"]
    assert main([*args, "--param", "source=image"]) == 0
    assert capsys.readouterr().err == ""
