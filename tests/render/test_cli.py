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
    assert "expected a .png file name" in capsys.readouterr().err


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
