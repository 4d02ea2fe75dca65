"""Bad input to animated scenes, ``refnpr animate`` and ``refnpr coherence``: each is one
``error:`` line naming the file, track and key (or the option), exit status 2, and no output
directory left behind. Cases run the command in a child process (``catalogue.cli``)."""

from __future__ import annotations

from pathlib import Path

from .catalogue import Case, Exits, cli, parametrize

_HEAD = """
[camera]
eye = [0.0, 0.0, 5.0]
target = [0.0, 0.0, 0.0]
[[object]]
name = "ball"
mesh = "uv_sphere"
[style]
name = "toon"
n = 3
[animation]
frames = 4
[[animation.track]]
"""


def _animate(track: str, *args: str):
    """``refnpr animate spin.toml ARGS -o out`` with ``track`` as the scene's one track."""

    def run(tmp: Path):
        (tmp / "spin.toml").write_text(_HEAD + track)
        proc = cli("animate", "spin.toml", "--size", "8x8", *args, "-o", "out", cwd=tmp)
        if proc.returncode != 0 and (tmp / "out").exists():
            proc.stderr += "\n(stray output: out/ was created)"
            proc.returncode = 0  # counted as "wrong" by the harness
        return proc

    return run


_FOV = 'target = "camera.fov_y"\n'
_KEY = _FOV + "keys = [{ frame = 0, value = 30 }]\n"


def _with(path: str, *args: str, directory: bool = False):
    """:func:`_animate` of a one-key track after creating ``path`` (a file, or a directory)
    in the case's directory."""

    def run(tmp: Path):
        target = tmp / path
        target.mkdir() if directory else target.write_text("x")
        return _animate(_KEY, *args)(tmp)

    return run


def _output_under_file(tmp: Path):
    (tmp / "spin.toml").write_text(_HEAD + _KEY)
    (tmp / "afile").write_text("x")
    return cli("animate", "spin.toml", "--size", "8x8", "-o", "afile/out", cwd=tmp)


def _coherence_json_into_a_directory(tmp: Path):
    (tmp / "d").mkdir()
    return cli(
        "coherence", "xtoon_flow", "--size", "8x6", "--frames", "0:3", "--json", "d", cwd=tmp
    )


CASES = [
    Case(
        "animation-bad-quaternion",
        "nonsense",
        "a rotation key with a quaternion of length sqrt(2)",
        _animate(
            "target = 'object \"ball\".rotation'\nkeys = [{ frame = 0, quaternion = [0, 0, 1, 1] }]\n"
        ),
        Exits(
            2, r"spin\.toml: \[\[animation\.track\]\] #1 .*keys\[0\].*unit quaternion.*normalize"
        ),
    ),
    Case(
        "animation-keys-out-of-order",
        "nonsense",
        "keys at frames 2 then 1",
        _animate(_FOV + "keys = [{ frame = 2, value = 30 }, { frame = 1, value = 40 }]\n"),
        Exits(2, r"spin\.toml: .*'camera\.fov_y': keys\[1\]: frame 1 is not after .* increasing"),
    ),
    Case(
        "animation-unknown-target",
        "nonsense",
        'target = "camera.zoom"',
        _animate('target = "camera.zoom"\nkeys = [{ frame = 0, value = 3 }]\n'),
        Exits(2, r"spin\.toml: .*unknown track target 'camera\.zoom'; valid targets: camera\.eye"),
    ),
    Case(
        "animation-key-after-last-frame",
        "nonsense",
        "a key at frame 7 of a 4-frame animation",
        _animate(_FOV + "keys = [{ frame = 0, value = 30 }, { frame = 7, value = 40 }]\n"),
        Exits(2, r"keys\[1\]: frame 7 .* lies after the last frame 3 .*frames = 8"),
    ),
    Case(
        "animate-style-track-missing-param",
        "nonsense",
        "a style.n track rendered with --style smooth",
        _animate(
            'target = "style.n"\nkeys = [{ frame = 0, value = 2 }, { frame = 3, value = 5 }]\n',
            "--style",
            "smooth",
        ),
        Exits(2, r"track 'style\.n', but the chosen style 'smooth' has no parameter 'n'"),
    ),
    Case(
        "animate-frames-bad-range",
        "nonsense",
        "refnpr animate --frames 3:9 of 4 frames",
        _animate(_FOV + "keys = [{ frame = 0, value = 30 }]\n", "--frames", "3:9"),
        Exits(2, r"--frames: .*'3:9' selects no frames of 0\.\.3 .*0 <= A < B <= 4"),
    ),
    Case(
        "animate-video-suffix",
        "nonsense",
        "refnpr animate --video out.avi",
        _animate(_FOV + "keys = [{ frame = 0, value = 30 }]\n", "--video", "out.avi"),
        Exits(2, r"--video: expected a file name ending in \.mp4 or \.gif, got 'out\.avi'"),
    ),
    Case(
        "animate-video-is-a-directory",
        "nonsense",
        "refnpr animate --video clip.gif where clip.gif is a directory",
        _with("clip.gif", "--video", "clip.gif", directory=True),
        Exits(2, r"--video: 'clip\.gif' is a directory; give a file name ending in \.gif"),
        notes="every frame was rendered before the video failed with an OSError",
    ),
    Case(
        "animate-video-under-a-file",
        "nonsense",
        "refnpr animate --video afile/clip.gif where afile is a file",
        _with("afile", "--video", "afile/clip.gif"),
        Exits(2, r"--video: cannot write 'afile/clip\.gif': 'afile' is a file, not a directory"),
    ),
    Case(
        "animate-output-under-a-file",
        "nonsense",
        "refnpr animate -o afile/out where afile is a file",
        _output_under_file,
        Exits(2, r"-o/--output: cannot write 'afile/out': 'afile' is a file, not a directory"),
    ),
    Case(
        "animate-workers-zero",
        "nonsense",
        "refnpr animate --workers 0",
        _animate(_FOV + "keys = [{ frame = 0, value = 30 }]\n", "--workers", "0"),
        Exits(2, r"--workers: expected a whole number >= 1, got 0"),
    ),
    Case(
        "coherence-json-directory",
        "nonsense",
        "refnpr coherence xtoon_flow --json d where d is a directory",
        _coherence_json_into_a_directory,
        Exits(2, r"--json: 'd' is a directory; give a file name ending in \.json"),
        notes="it failed after rendering every frame, naming a hidden temporary file",
    ),
    Case(
        "coherence-still-scene",
        "nonsense",
        "refnpr coherence sphere (a still scene)",
        lambda tmp: cli("coherence", "sphere", "--size", "8x8", cwd=tmp),
        Exits(2, r"scene: 'sphere' is a still .*consecutive frames of an animated scene"),
    ),
]

test_case = parametrize(CASES)
