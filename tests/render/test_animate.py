"""`refnpr animate` and `refnpr scenes`' frame counts, called in-process through main(argv)."""

import json
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


@pytest.mark.parametrize(
    ("option", "frames", "kept"),
    [("--frames", "-2:", [2, 3]), ("--frames", "-3:-1", [1, 2]), ("--fram", "-2:", [2, 3])],
)
def test_animate_takes_a_slice_counted_from_the_end_after_a_space(
    tmp_path, scene_file, option, frames, kept
):
    out = tmp_path / "frames"
    assert animate(scene_file, "--size", "8x8", "--spp", "1", "-o", out, option, frames) == 0
    assert sorted(p.name for p in out.glob("*.png")) == [f"frame_{f:05d}.png" for f in kept]


def test_only_frames_starts_with_f_so_its_abbreviations_are_safe_to_rewrite():
    """The CLI writes an abbreviation of ``--frames`` followed by a negative slice out in full
    (``cli._slices_attached``); that is right only while no other option starts with --f."""
    import argparse

    from refnpr.cli import build_parser

    seen, todo = set(), [build_parser()]
    while todo:
        parser = todo.pop()
        for action in parser._actions:
            seen.update(o for o in action.option_strings if o.startswith("--f"))
            if isinstance(action, argparse._SubParsersAction):
                todo.extend(action.choices.values())
    assert seen == {"--frames"}


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


def test_animate_param_replaces_the_scenes_track_of_that_parameter(tmp_path, capsys):
    path = tmp_path / "n.toml"
    path.write_text(
        SCENE
        + '[[animation.track]]\ntarget = "style.n"\n'
        + "keys = [{ frame = 0, value = 2 }, { frame = 3, value = 6 }]\n"
    )
    out = tmp_path / "o"
    assert animate(path, "--size", "16x12", "--spp", "1", "-o", out, "--param", "n=4") == 0
    err = capsys.readouterr().err
    assert err == (
        "refnpr animate: warning: --param n=4 replaces the scene's track 'style.n': every "
        "frame uses that value\n"
    )
    scene = load_scene(path)
    for f in (0, 3):
        want = render(scene.at(f), {"name": "toon", "n": 4}, 16, 12, 1).to_srgb8()
        np.testing.assert_array_equal(iio.imread(out / f"frame_{f:05d}.png"), want)
        assert '"n": 4' in (out / f"frame_{f:05d}.json").read_text()
    # the track still animates n where --param does not set it
    assert animate(path, "--size", "16x12", "--spp", "1", "-o", tmp_path / "t", "-q") == 0
    want = render(scene.at(3), {"name": "toon", "n": 6}, 16, 12, 1).to_srgb8()
    np.testing.assert_array_equal(iio.imread(tmp_path / "t" / "frame_00003.png"), want)


def test_a_failed_run_removes_only_the_empty_directories_it_made(tmp_path, scene_file, monkeypatch):
    from refnpr import sequence

    calls = []

    def shade(self, f):
        calls.append(f)
        if f == 1:
            raise ValueError("shading failed")
        return shade.original(self, f)

    shade.original = sequence._Shader.shade
    monkeypatch.setattr(sequence._Shader, "shade", shade)
    out = tmp_path / "a" / "b" / "frames"
    with pytest.raises(ValueError, match="shading failed"):
        sequence.render_sequence(scene_file, None, 8, 8, 1, out_dir=out, frames="1:3")
    assert not (tmp_path / "a").exists()  # nothing written: every directory it made is gone
    existing = tmp_path / "kept"
    existing.mkdir()
    with pytest.raises(ValueError, match="shading failed"):
        sequence.render_sequence(scene_file, None, 8, 8, 1, out_dir=existing / "f", frames="1:3")
    assert existing.is_dir() and not (existing / "f").exists()
    with pytest.raises(ValueError, match="shading failed"):  # frame 0 written, then a failure
        sequence.render_sequence(scene_file, None, 8, 8, 1, out_dir=out, frames="0:3")
    assert sorted(p.name for p in out.iterdir()) == ["frame_00000.json", "frame_00000.png"]


def test_warnings_are_one_line_without_a_source_location(tmp_path, capsys):
    args = ["--scene", "sphere", "--size", "8x8", "--spp", "1", "-o", tmp_path / "x.png", "-q"]
    rc = main(["render", "--style", "toon", "--param", "mode=lake", "--param", "specular=false"]
              + list(map(str, args)))  # fmt: skip
    assert rc == 0
    assert capsys.readouterr().err == (
        "refnpr render: warning: specular: False is ignored with mode='lake'; remove specular "
        "or use mode='step'\n"
    )


def test_a_run_refused_by_the_lock_leaves_the_holders_new_directory(tmp_path):
    """Two runs that both made ``out`` (they started together): the one the lock refuses must
    not remove the directory the other is writing into."""
    from refnpr import sequence

    out = tmp_path / "new"
    out.mkdir()
    with sequence.claim(out, (out,)):
        with pytest.raises(ValueError, match="is being written by another `refnpr animate` run"):
            with sequence.claim(out, (out,)):
                pass
        assert out.is_dir()
    assert out.is_dir()  # the holder finished without an error: nothing removed


def test_a_frame_record_lists_the_values_the_style_tracks_set(tmp_path):
    from refnpr.sequence import render_sequence

    path = tmp_path / "n.toml"
    path.write_text(
        SCENE
        + '[[animation.track]]\ntarget = "style.n"\ninteger = true\n'
        + "keys = [{ frame = 0, value = 2 }, { frame = 3, value = 5 }]\n"
    )
    out = tmp_path / "o"
    render_sequence(path, {"name": "toon", "n": 4}, 8, 8, 1, out_dir=out)
    records = [json.loads((out / f"frame_{f:05d}.json").read_text()) for f in range(4)]
    assert [r["style_tracks"] for r in records] == [{"n": n} for n in (2, 3, 4, 5)]
    assert all(r["style"] == {"name": "toon", "n": 4} for r in records)
    want = render(load_scene(path).at(3), {"name": "toon", "n": 5}, 8, 8, 1).to_srgb8()
    np.testing.assert_array_equal(iio.imread(out / "frame_00003.png"), want)
    plain = tmp_path / "plain.toml"
    plain.write_text(SCENE)  # a camera track, no style track
    render_sequence(plain, None, 8, 8, 1, out_dir=tmp_path / "still", frames="0:1")
    assert "style_tracks" not in (tmp_path / "still" / "frame_00000.json").read_text()
