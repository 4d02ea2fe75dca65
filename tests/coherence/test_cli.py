"""``refnpr coherence``: the command's parser and run(), on a scene file written here."""

from __future__ import annotations

import json

import pytest

from refnpr.cli import build_parser
from refnpr.coherence.cli import parse_frames, run

SCENE = """
name = "coherence_cli"
[camera]
eye = [0.0, 1.5, 5.0]
target = [0.0, 0.5, 0.0]
fov_y = 45.0
[style]
name = "toon"
n = 3
[[light]]
direction = [0.5, 1.0, 0.3]
[[object]]
name = "floor"
mesh = "plane"
width = 20.0
depth = 20.0
[[object]]
name = "ball"
mesh = "icosphere"
transform = { translate = [-0.5, 0.8, 0.0] }
[animation]
frames = 4
fps = 24
[[animation.track]]
target = 'object "ball".translation'
keys = [
    { frame = 0, value = [-0.5, 0.8, 0.0] },
    { frame = 3, value = [0.5, 0.8, 0.0] },
]
"""

STILL = """
name = "coherence_still"
[camera]
eye = [0.0, 1.5, 5.0]
target = [0.0, 0.5, 0.0]
[[object]]
mesh = "icosphere"
"""


def parse(argv):
    return build_parser().parse_args(["coherence", *argv])


@pytest.fixture
def scene_file(tmp_path):
    path = tmp_path / "anim.toml"
    path.write_text(SCENE)
    return path


def test_cli_writes_json_and_plot(scene_file, tmp_path, capsys):
    out_json, out_png = tmp_path / "c.json", tmp_path / "c.png"
    args = parse(
        [str(scene_file), "--size", "48x36", "--frames", "1:4", "--json", str(out_json),
         "--plot", str(out_png)]
    )  # fmt: skip
    assert args.func(args) == 0
    data = json.loads(out_json.read_text())
    assert [p["frame"] for p in data["pairs"]] == [2, 3]
    assert data["meta"]["style"] == "toon" and data["meta"]["size"] == [48, 36]
    assert all(p["n_valid"] > 0 for p in data["pairs"])
    assert out_png.read_bytes()[:4] == b"\x89PNG"
    text = capsys.readouterr().out
    assert "coherence_cli: frames 1..3" in text and "median" in text


def test_cli_param_and_style(scene_file, tmp_path):
    out = tmp_path / "c.json"
    assert run(parse([str(scene_file), "--size", "32x24", "--param", "n=2", "-q",
                      "--json", str(out)])) == 0  # fmt: skip
    assert json.loads(out.read_text())["meta"]["style_params"]["n"] == "2"
    assert run(parse([str(scene_file), "--size", "32x24", "--style", "smooth", "-q",
                      "--json", str(out)])) == 0  # fmt: skip
    assert json.loads(out.read_text())["meta"]["style"] == "smooth"


def test_cli_refuses_a_still_scene(tmp_path):
    path = tmp_path / "still.toml"
    path.write_text(STILL)
    with pytest.raises(ValueError, match=r"is a still \(no \[animation\] table"):
        run(parse([str(path)]))


def test_cli_refuses_a_bad_plot_path_before_rendering(scene_file, tmp_path):
    with pytest.raises(ValueError, match=r"png"):
        run(parse([str(scene_file), "--plot", str(tmp_path / "c.jpg")]))


@pytest.mark.parametrize(
    "text, count, expected",
    [(None, 5, range(0, 5)), ("1:3", 5, range(1, 3)), ("2:", 5, range(2, 5)),
     (":-1", 5, range(0, 4))],
)  # fmt: skip
def test_parse_frames(text, count, expected):
    assert parse_frames(text, count) == expected


@pytest.mark.parametrize("text", ["3", "a:b", "1:2", "4:2", "0:9"])
def test_parse_frames_errors(text):
    with pytest.raises(ValueError, match=r"--frames"):
        parse_frames(text, 5)


def test_cli_strokes_for_a_stroke_style(scene_file, tmp_path, capsys):
    out = tmp_path / "s.json"
    args = parse([str(scene_file), "--size", "64x48", "--frames", "0:3", "--style", "tamiss",
                  "--strokes", "--json", str(out)])  # fmt: skip
    assert run(args) == 0
    data = json.loads(out.read_text())
    assert [r["frame"] for r in data["strokes"]] == [1, 2]
    assert all(r["n_strokes"] > 0 for r in data["strokes"])
    assert "jitter_mean" in data["summary"]
    assert "appeared" in capsys.readouterr().out


def test_cli_strokes_refused_for_a_style_without_strokes(scene_file):
    with pytest.raises(TypeError, match=r"strokes: style 'toon' draws no strokes by id"):
        run(parse([str(scene_file), "--size", "32x24", "--strokes"]))
