"""`refnpr animate` and `refnpr scenes`' frame counts, called in-process through main(argv)."""

import re

import imageio.v3 as iio
import numpy as np
import pytest

from refnpr.cli import main
from refnpr.render import render
from refnpr.scenes import load_scene

SCENE = """
[camera]
eye = [0.0, 0.5, 4.0]
target = [0.0, 0.0, 0.0]
[style]
name = "toon"
n = 3
[[object]]
name = "ball"
mesh = "uv_sphere"
n_u = 16
n_v = 8
[animation]
frames = 4
fps = 8
[[animation.track]]
target = "camera.eye"
keys = [{ frame = 0, value = [0.0, 0.5, 4.0] }, { frame = 3, value = [2.0, 0.5, 3.0] }]
"""


@pytest.fixture
def scene_file(tmp_path):
    path = tmp_path / "move.toml"
    path.write_text(SCENE)
    return path


def animate(*args):
    return main(["animate", *map(str, args)])


def test_animate_writes_frames_and_resumes(tmp_path, scene_file, capsys):
    out = tmp_path / "frames"
    assert animate(scene_file, "--size", "32x24", "--spp", "1", "-o", out, "--frames", "1:3") == 0
    assert "wrote 2 of 2 frame(s)" in capsys.readouterr().out
    assert sorted(p.name for p in out.glob("*.png")) == ["frame_00001.png", "frame_00002.png"]
    want = render(load_scene(scene_file).at(2), None, 32, 24, 1).to_srgb8()
    np.testing.assert_array_equal(iio.imread(out / "frame_00002.png"), want)
    assert animate(scene_file, "--size", "32x24", "--spp", "1", "-o", out) == 0
    assert "wrote 2 of 4 frame(s)" in capsys.readouterr().out  # 1 and 2 were done


def test_animate_style_params_video_and_progress(tmp_path, scene_file, capsys):
    out = tmp_path / "frames"
    video = tmp_path / "clip.gif"
    rc = animate(
        scene_file, "--style", "toon", "--param", "n=2", "--size", "24x16", "--spp", "1",
        "-o", out, "--video", video, "--progress",
    )  # fmt: skip
    assert rc == 0
    captured = capsys.readouterr()
    assert "frame 4/4" in captured.err and "frame/s" in captured.err and "ETA" in captured.err
    assert "wrote " + str(video) in captured.out
    assert iio.imread(video, index=None).shape[:3] == (4, 16, 24)
    want = render(load_scene(scene_file).at(3), {"name": "toon", "n": 2}, 24, 16, 1).to_srgb8()
    np.testing.assert_array_equal(iio.imread(out / "frame_00003.png"), want)
    # quiet and not a tty: no progress bar
    animate(scene_file, "--size", "24x16", "--spp", "1", "-o", tmp_path / "q", "-q")
    assert capsys.readouterr().err == ""


@pytest.mark.parametrize(
    "args, message",
    [
        (["--frames", "2:9"], r"--frames: frames: '2:9' selects no frames of 0..3"),
        (["--frames", "x"], r"--frames: frames: expected A:B"),
        (["--video", "clip.avi"], r"--video: expected a file name ending in .mp4 or .gif"),
        (["--style", " "], r"--style: expected a style name"),
        (["--param", "name=toon"], r"--param: 'name' is not a style parameter"),
    ],
)
def test_animate_errors(tmp_path, scene_file, capsys, args, message):
    rc = animate(scene_file, "--size", "8x8", "--spp", "1", "-o", tmp_path / "o", *args)
    assert rc == 2
    err = capsys.readouterr().err
    assert err.startswith("refnpr animate: error: ")
    assert re.search(message, err), err
    assert not (tmp_path / "o").exists()  # refused before any frame


def test_animate_param_without_style_uses_the_scenes_style(tmp_path, scene_file):
    out = tmp_path / "o"
    assert animate(scene_file, "--size", "8x8", "--spp", "1", "-o", out, "--param", "n=2") == 0
    want = render(load_scene(scene_file).at(0), {"name": "toon", "n": 2}, 8, 8, 1).to_srgb8()
    np.testing.assert_array_equal(iio.imread(out / "frame_00000.png"), want)


def test_animate_style_track_conflict_names_both(tmp_path, capsys):
    path = tmp_path / "n.toml"
    path.write_text(
        SCENE
        + '[[animation.track]]\ntarget = "style.n"\n'
        + "keys = [{ frame = 0, value = 2 }, { frame = 3, value = 4 }]\n"
    )
    assert animate(path, "--style", "smooth", "--size", "8x8", "-o", tmp_path / "o") == 2
    err = capsys.readouterr().err
    assert "track 'style.n', but the chosen style 'smooth' has no parameter 'n'" in err


def test_animate_output_must_be_a_directory(tmp_path, scene_file, capsys):
    f = tmp_path / "file"
    f.write_text("x")
    assert animate(scene_file, "-o", f) == 2
    assert "-o/--output: " in capsys.readouterr().err


def test_scenes_marks_animated_scenes(capsys):
    assert main(["scenes"]) == 0
    lines = {line.split()[0]: line for line in capsys.readouterr().out.splitlines()}
    assert "[49 frames]" in lines["veryovka_dolly"]
    assert "[36 frames]" in lines["xtoon_flow"]
    assert "frames]" not in lines["teapot"]
