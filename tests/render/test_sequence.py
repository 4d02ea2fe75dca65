"""The sequence driver: frames equal still renders, the style protocol across frames, restart
(skip, mismatch, kill mid-run and resume: identical bytes), EXR and video."""

import hashlib
import json
import os
import signal
import subprocess
import sys
import textwrap
import time
from pathlib import Path

import imageio.v3 as iio
import numpy as np
import pytest

from refnpr.render import RenderContext, render
from refnpr.scenes import load_scene
from refnpr.sequence import frame_range, is_stateful, render_sequence, write_video
from refnpr.styles import get_style
from refnpr.styles.toon import ToonStyle

SCENE_TOML = """
name = "spin"
background = [0.2, 0.3, 0.4, 1.0]
[camera]
eye = [0.0, 0.5, 4.0]
target = [0.0, 0.0, 0.0]
fov_y = 40.0
[style]
name = "toon"
n = 3
[[light]]
direction = [0.5, 1.0, 0.8]
[[object]]
name = "ball"
mesh = "uv_sphere"
n_u = 24
n_v = 12
transform = {{ scale = [1.0, 0.6, 1.0] }}
[animation]
frames = {frames}
fps = 12
[[animation.track]]
target = 'object "ball".rotation'
keys = [{{ frame = 0, axis = [0, 0, 1], angle_deg = 0 }}, {{ frame = {last}, axis = [0, 0, 1], angle_deg = 170 }}]
[[animation.track]]
target = "camera.eye"
interpolation = "catmull_rom"
keys = [{{ frame = 0, value = [0.0, 0.5, 4.0] }}, {{ frame = {mid}, value = [1.0, 1.0, 3.5] }}, {{ frame = {last}, value = [0.0, 1.5, 4.0] }}]
[[animation.track]]
target = "style.n"
keys = [{{ frame = 0, value = 2 }}, {{ frame = {last}, value = 5 }}]
"""

W, H = 40, 30


def write_scene(tmp_path, frames=6):
    path = tmp_path / "spin.toml"
    path.write_text(SCENE_TOML.format(frames=frames, last=frames - 1, mid=(frames - 1) / 2))
    return path


def pixels(path):
    return iio.imread(path)


def test_frames_equal_still_renders_of_scene_at(tmp_path):
    path = write_scene(tmp_path)
    out = tmp_path / "frames"
    result = render_sequence(path, None, W, H, 1, out_dir=out)
    assert result.rendered == list(range(6)) and not result.skipped and not result.stateful
    scene = load_scene(path)
    for f in range(6):
        still = scene.at(f)
        # oracle: the one-frame renderer on the still scene, with the style track's n applied
        want = render(still, {"name": "toon", "n": still.style["n"]}, W, H, 1).to_srgb8()
        np.testing.assert_array_equal(pixels(out / f"frame_{f:05d}.png"), want)
        record = json.loads((out / f"frame_{f:05d}.json").read_text())
        assert record["frame"] == f and record["size"] == [W, H]
        assert (
            record["png_sha256"]
            == hashlib.sha256((out / f"frame_{f:05d}.png").read_bytes()).hexdigest()
        )
    assert [scene.at(f).style["n"] for f in range(6)] == [2, 3, 3, 4, 4, 5]


def test_a_second_run_skips_and_a_changed_setting_rerenders(tmp_path):
    path = write_scene(tmp_path)
    out = tmp_path / "frames"
    render_sequence(path, None, W, H, 1, out_dir=out)
    before = {p.name: p.read_bytes() for p in out.iterdir()}
    again = render_sequence(path, None, W, H, 1, out_dir=out)
    assert again.rendered == [] and again.skipped == list(range(6))
    assert {p.name: p.read_bytes() for p in out.iterdir()} == before
    # a damaged frame and a missing record are re-rendered, nothing else
    (out / "frame_00002.png").write_bytes(b"not a png")
    (out / "frame_00004.json").unlink()
    fixed = render_sequence(path, None, W, H, 1, out_dir=out)
    assert fixed.rendered == [2, 4]
    assert {p.name: p.read_bytes() for p in out.iterdir()} == before
    # another spp is another hash: every frame again
    assert render_sequence(path, None, W, H, 4, out_dir=out).rendered == list(range(6))


def test_frame_ranges_and_their_errors():
    assert frame_range(None, 5) == range(5)
    assert frame_range("1:3", 5) == range(1, 3)
    assert frame_range("3:", 5) == range(3, 5)
    assert frame_range(":2", 5) == range(0, 2)
    assert frame_range("-2:", 5) == range(3, 5)
    assert frame_range((0, 1), 1) == range(1)
    for bad in ("3:3", "0:6", "a:b", "1", "4:2"):
        with pytest.raises(ValueError, match="frames: "):
            frame_range(bad, 5)


class RecordingToon(ToonStyle):
    """Records the (frame scene, previous scene) pairs for_frame receives."""

    calls: list = []

    def for_frame(self, scene, prev_scene):
        RecordingToon.calls.append((scene, prev_scene))
        return self


def test_for_frame_gets_the_previous_still_even_when_frames_are_skipped(tmp_path):
    path = write_scene(tmp_path)
    scene = load_scene(path)
    out = tmp_path / "frames"
    style = RecordingToon(n=2)
    with pytest.raises(TypeError, match="animates style parameters .* not a Style instance"):
        render_sequence(scene, style, W, H, 1, out_dir=out)
    plain = load_scene(path)
    anim = plain.animation.__class__(
        plain.animation.frames, plain.animation.fps, plain.animation.tracks[:2]
    )  # without the style track
    scene = plain.__class__(**{**plain.__dict__, "animation": anim})
    RecordingToon.calls = []
    render_sequence(scene, style, W, H, 1, out_dir=out, frames="0:2")
    render_sequence(scene, style, W, H, 1, out_dir=out, frames="0:5")  # 0, 1 skipped
    got = [
        (s.camera.eye.tolist(), None if p is None else p.camera.eye.tolist())
        for s, p in RecordingToon.calls
    ]
    want = [
        (scene.at(f).camera.eye.tolist(), None if f == 0 else scene.at(f - 1).camera.eye.tolist())
        for f in (0, 1, 2, 3, 4)
    ]
    assert got == want
    assert [s.animation for s, _ in RecordingToon.calls] == [None] * 5


class CountingToon(ToonStyle):
    """A stateful style: the state counts shaded frames; the image is darkened by it, so a
    frame shows whether its state was rebuilt from frame 0."""

    def initial_state(self):
        return 0

    def shade_frame(self, ctx, state):
        rgba = np.asarray(self.shade(ctx), dtype=np.float32).copy()
        rgba[..., :3] *= np.float32(1.0 / (1 + state))
        return rgba, state + 1


def camera_only_scene(tmp_path):
    """The test scene with only its first two tracks (no style track)."""
    plain = load_scene(write_scene(tmp_path))
    anim = plain.animation.__class__(
        plain.animation.frames, plain.animation.fps, plain.animation.tracks[:2]
    )
    return plain.__class__(**{**plain.__dict__, "animation": anim})


def test_a_stateful_style_runs_from_frame_zero(tmp_path):
    scene = camera_only_scene(tmp_path)
    style = CountingToon(n=2)
    assert is_stateful(style) and not is_stateful(get_style("toon"))
    out = tmp_path / "frames"
    part = render_sequence(scene, style, W, H, 1, out_dir=out, frames="3:5")
    assert part.stateful and part.rendered == [3, 4]
    for f in (3, 4):  # oracle: one frame shaded from the state f (f frames shaded before it)
        ctx = RenderContext(scene.at(f), ToonStyle(n=2), W, H, 1)
        img, state = ctx.render_frame(scene.at(f), style, f)
        assert state == f + 1
        np.testing.assert_array_equal(pixels(out / f"frame_{f:05d}.png"), img.to_srgb8())
        plain_img = render(scene.at(f), ToonStyle(n=2), W, H, 1).to_srgb8()
        assert not np.array_equal(img.to_srgb8(), plain_img)  # the state shows in the pixels
    full = render_sequence(scene, style, W, H, 1, out_dir=out)
    assert full.rendered == [0, 1, 2, 5] and full.skipped == [3, 4]
    (out / "frame_00001.json").unlink()
    calls = []
    again = render_sequence(scene, style, W, H, 1, out_dir=out, progress=lambda *a: calls.append(a))
    assert again.rendered == [1] and again.skipped == [0, 2, 3, 4, 5]
    # shaded: 0 (state) and 1; 2..5 are done and after the last frame to render: not shaded
    assert [c[2:] for c in calls] == [(0, "skipped"), (1, "rendered")] + [
        (f, "skipped") for f in (2, 3, 4, 5)
    ]


class WindowToon(ToonStyle):
    """A stateful style whose state is the mean red of the last two frames (unshaded by the
    state), darkening each frame by it, and which says so: ``state_frames() == 2``."""

    def initial_state(self):
        return ()

    def state_frames(self):
        return 2

    def shade_frame(self, ctx, state):
        rgba = np.asarray(self.shade(ctx), dtype=np.float32).copy()
        mean = float(np.mean(rgba[..., 0]))
        rgba[..., :3] *= np.float32(1.0 / (1.0 + 4.0 * sum(state)))
        return rgba, (*state, mean)[-2:]


def test_a_style_with_a_short_memory_resumes_that_many_frames_back(tmp_path):
    scene = camera_only_scene(tmp_path)
    style = WindowToon(n=2)
    out = tmp_path / "frames"
    render_sequence(scene, style, W, H, 1, out_dir=out)
    before = {f: (out / f"frame_{f:05d}.png").read_bytes() for f in range(6)}
    (out / "frame_00004.json").unlink()
    calls = []
    again = render_sequence(scene, style, W, H, 1, out_dir=out, progress=lambda *a: calls.append(a))
    assert again.rendered == [4] and again.skipped == [0, 1, 2, 3, 5]
    # 0 and 1 are not shaded (before the state's reach), 2 and 3 are, for their state
    assert [c[2:] for c in calls] == [(f, "skipped") for f in (0, 1, 2, 3)] + [
        (4, "rendered"),
        (5, "skipped"),
    ]
    assert {f: (out / f"frame_{f:05d}.png").read_bytes() for f in range(6)} == before


def test_tamiss_default_resumes_from_its_averaging_window(tmp_path):
    """The default TAMISS (4 frames averaged, exact aggregation) has state_frames() == 4: a
    resumed run re-shades the 4 frames before and writes the same bytes as a whole run."""
    scene = load_scene("tamiss_knot_orbit")
    style = get_style("tamiss", directions=["v"])
    assert is_stateful(style) and style.state_frames() == 4
    assert get_style("tamiss", aggregation="hashed").state_frames() is None
    assert get_style("tamiss", smooth=0.5, average_frames=1).state_frames() is None
    out = tmp_path / "knot"
    render_sequence(scene, style, 64, 48, 1, out_dir=out, frames="0:7")
    before = (out / "frame_00006.png").read_bytes()
    (out / "frame_00006.json").unlink()
    calls = []
    again = render_sequence(
        scene, style, 64, 48, 1, out_dir=out, frames="0:7", progress=lambda *a: calls.append(a)
    )
    assert again.rendered == [6]
    assert (out / "frame_00006.png").read_bytes() == before
    # frames 0 and 1 untouched, 2..5 shaded for the state
    assert [c[2] for c in calls] == list(range(7))


def test_a_style_track_the_chosen_style_lacks_is_an_error_naming_both(tmp_path):
    path = write_scene(tmp_path)
    with pytest.raises(
        ValueError, match=r"track 'style.n', but the chosen style 'smooth' has no parameter 'n'"
    ):
        render_sequence(path, "smooth", W, H, 1, out_dir=tmp_path / "x")
    with pytest.raises(ValueError, match="leave out --style"):
        render_sequence(path, {"name": "smooth"}, W, H, 1, out_dir=tmp_path / "x")
    # a style that has the parameter takes the track's value
    r = render_sequence(
        path, {"name": "toon", "mode": "lake"}, W, H, 1, out_dir=tmp_path / "y", frames="5:6"
    )
    want = render(load_scene(path).at(5), {"name": "toon", "mode": "lake", "n": 5}, W, H, 1)
    np.testing.assert_array_equal(pixels(r.paths[0]), want.to_srgb8())


def test_a_still_scene_is_one_frame(tmp_path):
    result = render_sequence("sphere", "toon", W, H, 1, out_dir=tmp_path / "s")
    assert result.frames == [0]
    np.testing.assert_array_equal(
        pixels(result.paths[0]), render("sphere", "toon", W, H, 1).to_srgb8()
    )
    with pytest.raises(ValueError, match="selects no frames of 0..0"):
        render_sequence("sphere", "toon", W, H, 1, out_dir=tmp_path / "s", frames="0:2")


def test_exr_frames_hold_the_linear_image(tmp_path):
    import OpenEXR

    path = write_scene(tmp_path, frames=2)
    out = tmp_path / "frames"
    render_sequence(path, None, W, H, 1, out_dir=out, exr=True)
    scene = load_scene(path)
    want = render(scene.at(1), {"name": "toon", "n": 5}, W, H, 1).rgba
    with OpenEXR.File(str(out / "frame_00001.exr"), separate_channels=True) as f:
        ch = f.channels()
        got = np.stack([np.asarray(ch[c].pixels) for c in "RGBA"], axis=-1)
    np.testing.assert_array_equal(got, want)
    # asking for EXR later re-renders frames that have none
    out2 = tmp_path / "frames2"
    render_sequence(path, None, W, H, 1, out_dir=out2)
    assert render_sequence(path, None, W, H, 1, out_dir=out2, exr=True).rendered == [0, 1]


def test_render_frame_reuses_buffers_and_equals_render(tmp_path):
    scene = load_scene(write_scene(tmp_path))
    style = get_style("toon", n=3)
    ctx = RenderContext(scene.at(0), style, W, H, 4)
    first, gb0, state = ctx.render_frame(scene.at(0), style, None, return_gbuffer=True, copy=True)
    second, gb1, _ = ctx.render_frame(scene.at(3), style, state, return_gbuffer=True)
    assert gb1 is gb0 and state is None
    np.testing.assert_array_equal(first.rgba, render(scene.at(0), style, W, H, 4).rgba)
    np.testing.assert_array_equal(second.rgba, render(scene.at(3), style, W, H, 4).rgba)
    # a style needing other channels gets fresh buffers
    third, gb2, _ = ctx.render_frame(scene.at(3), get_style("smooth"), None, return_gbuffer=True)
    np.testing.assert_array_equal(third.rgba, render(scene.at(3), "smooth", W, H, 4).rgba)


# ------------------------------------------------------------------------------ kill + resume
RUNNER = textwrap.dedent(
    """
    import sys
    from refnpr.sequence import render_sequence
    render_sequence(sys.argv[1], None, 64, 48, 4, out_dir=sys.argv[2])
    """
)


def run_until_frames(path, out, n, sig):
    """Start a run in a subprocess; once ``n`` frame records exist, send ``sig``."""
    proc = subprocess.Popen([sys.executable, "-c", RUNNER, str(path), str(out)])
    deadline = time.monotonic() + 300
    try:
        while time.monotonic() < deadline:
            if out.is_dir() and len(list(out.glob("frame_*.json"))) >= n:
                break
            if proc.poll() is not None:
                pytest.fail(f"the run ended (status {proc.returncode}) before it was killed")
            time.sleep(0.01)
        os.kill(proc.pid, sig)
    finally:
        proc.wait(timeout=60)
    return proc.returncode


@pytest.mark.parametrize("sig", [signal.SIGTERM, signal.SIGKILL])
def test_kill_mid_run_and_resume_gives_identical_bytes(tmp_path, sig):
    path = write_scene(tmp_path, frames=30)
    ref = tmp_path / "ref"
    render_sequence(path, None, 64, 48, 4, out_dir=ref)
    out = tmp_path / "killed"
    status = run_until_frames(path, out, 3, sig)
    assert status == -sig
    done = sorted(out.glob("frame_*.json"))
    assert 3 <= len(done) < 30, "the run was not killed mid-way; make the frames slower"
    if sig == signal.SIGTERM:  # the atomic writes remove their temporary files on SIGTERM
        assert not [p for p in out.iterdir() if p.name.startswith(".")]
    (out / ".frame_00029.0123456789.png").write_bytes(b"partial")  # what a SIGKILL can leave
    resumed = render_sequence(path, None, 64, 48, 4, out_dir=out)
    assert len(resumed.skipped) >= len(done) - 1 and resumed.rendered
    assert sorted(p.name for p in out.iterdir()) == sorted(p.name for p in ref.iterdir())
    for p in ref.iterdir():
        assert (out / p.name).read_bytes() == p.read_bytes(), p.name


# ------------------------------------------------------------------------------ video
def test_gif_and_mp4_videos(tmp_path):
    path = write_scene(tmp_path, frames=4)
    result = render_sequence(path, None, 41, 31, 1, out_dir=tmp_path / "f")
    gif = write_video(result.paths, tmp_path / "v.gif", 12)
    frames = iio.imread(gif, index=None)
    assert frames.shape[:3] == (4, 31, 41)
    mp4 = write_video(result.paths, tmp_path / "v.mp4", 12)
    video = iio.imread(mp4, plugin="FFMPEG", index=None)
    assert video.shape[0] == 4 and video.shape[1:3] == (32, 42)  # padded to even sizes
    # lossy, but close to the frames (the padding repeats the last row and column)
    first = pixels(result.paths[0])[..., :3].astype(float)
    assert np.abs(video[0, :31, :41].astype(float) - first).mean() < 12
    assert not [p for p in tmp_path.iterdir() if p.name.startswith(".v.")]


def test_video_errors(tmp_path, monkeypatch):
    with pytest.raises(ValueError, match=r"video: expected a file name ending in .mp4 or .gif"):
        write_video([Path("a.png")], tmp_path / "v.avi", 12)
    with pytest.raises(ValueError, match="no frames"):
        write_video([], tmp_path / "v.gif", 12)
    monkeypatch.setitem(sys.modules, "imageio_ffmpeg", None)  # as if not installed
    with pytest.raises(
        ValueError, match=r"needs ffmpeg from the imageio-ffmpeg package; .*refnpr\[video\]"
    ):
        write_video([Path("a.png")], tmp_path / "v.mp4", 12)


# ------------------------------------------------------------------------------ shared directories
def test_a_second_run_on_a_directory_in_use_is_refused(tmp_path):
    from refnpr.sequence import claim

    path = write_scene(tmp_path, frames=2)
    out = tmp_path / "frames"
    out.mkdir()
    with claim(out):  # as a first run holds it, in any process (flock on the directory)
        with pytest.raises(ValueError, match=r"out_dir: .*frames.* another `refnpr animate` run"):
            render_sequence(path, None, W, H, 1, out_dir=out)
        assert not list(out.iterdir())  # refused before any file was written or removed
    assert render_sequence(path, None, W, H, 1, out_dir=out).rendered == [0, 1]
    assert sorted(p.name for p in out.iterdir())[0] == "frame_00000.json"  # no lock file left


def test_a_second_process_is_refused_while_a_run_holds_the_directory(tmp_path):
    out = tmp_path / "frames"
    out.mkdir()
    holder = subprocess.Popen(
        [
            sys.executable,
            "-c",
            "import sys, time\nfrom pathlib import Path\nfrom refnpr.sequence import claim\n"
            "with claim(Path(sys.argv[1])):\n    print('held', flush=True)\n    time.sleep(60)\n",
            str(out),
        ],
        stdout=subprocess.PIPE,
        text=True,
    )
    try:
        assert holder.stdout.readline().strip() == "held"
        from refnpr.cli import main

        path = write_scene(tmp_path, frames=2)
        assert main(["animate", str(path), "-o", str(out), "--size", "8x6", "--spp", "1"]) == 2
    finally:
        holder.kill()
        holder.wait(timeout=30)


def test_temporaries_of_frames_past_99999_are_removed(tmp_path):
    path = write_scene(tmp_path, frames=2)
    out = tmp_path / "frames"
    out.mkdir()
    stray = [".frame_00001.0123456789.png", ".frame_123456.0123456789.exr"]
    kept = [".frame_1.0123456789.png", "notes.frame_123456.0123456789.png"]  # not ours
    for name in stray + kept:
        (out / name).write_bytes(b"partial")
    render_sequence(path, None, W, H, 1, out_dir=out, frames="0:1")
    names = {p.name for p in out.iterdir()}
    assert not names & set(stray)
    assert set(kept) <= names


def test_frame_counts_past_the_maximum_are_refused_up_front(tmp_path):
    from refnpr.scenes.animation import MAX_FRAMES, Animation

    path = write_scene(tmp_path, frames=2)
    text = path.read_text().replace("frames = 2", "frames = 1000000000")
    path.write_text(text)
    with pytest.raises(ValueError, match=rf"frames: expected an integer <= {MAX_FRAMES}"):
        render_sequence(path, None, W, H, 1, out_dir=tmp_path / "out")
    assert not (tmp_path / "out").exists()
    assert Animation(MAX_FRAMES).frames == MAX_FRAMES


def test_a_full_disk_while_writing_an_exr_frame_is_a_clear_error(tmp_path, monkeypatch):
    import contextlib

    import refnpr.sequence as sequence

    @contextlib.contextmanager
    def onto_a_full_disk(path, *, suffix=""):  # every write fails with ENOSPC
        yield Path("/dev/full")

    monkeypatch.setattr(sequence, "atomic_file", onto_a_full_disk)
    rng = np.random.default_rng(1)
    for rgba in (rng.random((30, 40, 4)), np.zeros((30, 40, 4))):  # large and tiny writes
        with pytest.raises(ValueError, match=r"exr: writing '.*frame_00000\.exr' failed: "):
            sequence._write_exr(tmp_path / "frame_00000.exr", rgba)


TEXTURED_TOML = """
[camera]
eye = [0.0, 0.0, 4.0]
target = [0.0, 0.0, 0.0]
[style]
name = "threshold"
source = "image"
[[light]]
direction = [0.6, 0.7, 1.0]
[[object]]
mesh = "uv_sphere"
n_u = 12
n_v = 6
[object.material]
texture = "t.png"
"""


def test_an_edited_texture_file_rerenders_the_frames_that_read_it(tmp_path):
    path = tmp_path / "textured.toml"
    path.write_text(TEXTURED_TOML)
    rng = np.random.default_rng(3)
    iio.imwrite(tmp_path / "t.png", rng.integers(0, 256, (16, 16), dtype=np.uint8))
    out = tmp_path / "frames"
    assert render_sequence(path, None, 8, 8, 1, out_dir=out).rendered == [0]
    assert render_sequence(path, None, 8, 8, 1, out_dir=out).skipped == [0]
    iio.imwrite(tmp_path / "t.png", np.full((16, 16), 255, dtype=np.uint8))  # same name
    assert render_sequence(path, None, 8, 8, 1, out_dir=out).rendered == [0]
    want = render(path, None, 8, 8, 1).to_srgb8()
    np.testing.assert_array_equal(pixels(out / "frame_00000.png"), want)


def test_a_style_file_parameter_is_hashed_by_its_content(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    iio.imwrite("t.png", np.zeros((16, 16), dtype=np.uint8))
    style = {"name": "threshold", "source": "image", "texture": "t.png"}
    out = tmp_path / "frames"
    assert render_sequence("sphere", style, 8, 8, 1, out_dir=out).rendered == [0]
    iio.imwrite("t.png", np.full((16, 16), 255, dtype=np.uint8))
    assert render_sequence("sphere", style, 8, 8, 1, out_dir=out).rendered == [0]
    want = render("sphere", style, 8, 8, 1).to_srgb8()
    np.testing.assert_array_equal(pixels(out / "frame_00000.png"), want)


def toon_textures():
    """Two 2D toon textures of one shape: a ramp and its reverse."""
    ramp = np.linspace(0.0, 1.0, 32, dtype=np.float32)[None, :, None]
    a = np.broadcast_to(ramp, (16, 32, 3)).copy()
    return a, np.ascontiguousarray(a[:, ::-1])


def test_a_style_instance_is_hashed_by_its_parameter_values(tmp_path):
    a, b = toon_textures()
    out = tmp_path / "frames"
    for tex in (a, b):
        style = get_style("xtoon", texture=tex)
        assert render_sequence("sphere", style, 8, 8, 1, out_dir=out).rendered == [0]
        want = render("sphere", get_style("xtoon", texture=tex), 8, 8, 1).to_srgb8()
        np.testing.assert_array_equal(pixels(out / "frame_00000.png"), want)
    same = get_style("xtoon", texture=b.copy())  # equal values: done
    assert render_sequence("sphere", same, 8, 8, 1, out_dir=out).skipped == [0]


def test_an_array_in_a_style_table_is_hashed_with_its_shape_and_dtype(tmp_path):
    a, _ = toon_textures()
    out = tmp_path / "frames"
    for tex in (a, np.ascontiguousarray(a.reshape(32, 16, 3))):  # the same bytes
        style = {"name": "xtoon", "texture": tex}
        assert render_sequence("sphere", style, 8, 8, 1, out_dir=out).rendered == [0]
        want = render("sphere", style, 8, 8, 1).to_srgb8()
        np.testing.assert_array_equal(pixels(out / "frame_00000.png"), want)
    record = json.loads((out / "frame_00000.json").read_text())
    assert record["style"]["texture"]["shape"] == [32, 16, 3]
    assert record["style"]["texture"]["dtype"] == "<f4"


def test_a_frame_rendered_without_exr_removes_its_old_exr(tmp_path):
    out = tmp_path / "frames"
    render_sequence("sphere", "toon", 8, 8, 1, out_dir=out, exr=True)
    assert (out / "frame_00000.exr").is_file()
    again = render_sequence("sphere", "toon", 16, 12, 1, out_dir=out)
    assert again.rendered == [0]
    assert sorted(p.name for p in out.iterdir()) == ["frame_00000.json", "frame_00000.png"]
    # a done frame keeps the EXR of its own render
    render_sequence("sphere", "toon", 16, 12, 1, out_dir=out, exr=True)
    assert render_sequence("sphere", "toon", 16, 12, 1, out_dir=out).skipped == [0]
    assert (out / "frame_00000.exr").is_file()
