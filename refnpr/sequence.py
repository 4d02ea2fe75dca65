"""Render frames of an animated scene to a directory, restartably (``refnpr animate``).

:func:`render_sequence` renders frames ``A .. B - 1`` of a scene (a still scene is frame 0 of a
one-frame sequence) with the style protocol of :class:`refnpr.styles.Style`: for each frame the
still ``scene.at(f)`` and the previous frame's still (``None`` at frame 0) go to
``style.for_frame``, and ``style.shade_frame(ctx, state)`` carries the style's state from frame
to frame, so nothing is kept in globals. Buffers are reused across frames
(:meth:`refnpr.render.RenderContext.render_frame`).

Files, per frame ``f`` (the animation's frame number): ``DIR/frame_00000.png`` (8-bit sRGB RGBA),
optionally ``DIR/frame_00000.exr`` (linear float32 RGBA), and ``DIR/frame_00000.json``, the
restart record, written last. Every file is written through a temporary file and an atomic
rename, so a killed run leaves complete files only; the temporaries of a run killed by SIGKILL
(which no process can clean up) are removed by the next run in that directory.

Restart rules. A frame's record holds a hash of everything the pixels depend on: the scene (its
meshes, transforms, materials, camera, lights, style table and animation), the style
specification, the size, spp and frame number, and the refnpr version; and the SHA-256 of the
PNG (and EXR) it describes. A frame whose record matches, and whose files match the record, is
done:

* a **stateless** style (``initial_state()`` is None and ``shade_frame`` is the default; the
  contour layer counts as its base style) skips it: a killed run loses nothing but the frame it
  was on;
* a **stateful** style (TAMISS hash tables, aggregate history) re-runs from frame 0 of the
  animation up to the last frame still to render, since the state of frame f depends on all
  frames before it; frames before ``A`` are shaded for their state only, and frames already
  done are not rewritten (a range that is all done is not shaded at all). A style whose state
  reaches only K frames back (``Style.state_frames()``, e.g. TAMISS averaging k frames with
  exact aggregation: K = k) re-runs from K frames before the first frame still to render.

Either way the frames on disk after any number of kills and restarts are byte-identical to an
uninterrupted run. One run per directory at a time. :mod:`refnpr.distributed` renders the same
frames on a Dask cluster with these files and rules (the client writes them).
"""

from __future__ import annotations

import hashlib
import json
import os
import re
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from . import __version__
from .image import atomic_file
from .render import DEFAULT_STYLE, RenderContext, as_scene
from .scenes._params import check_int
from .styles import Style, style_from_spec

__all__ = [
    "SequenceResult",
    "frame_range",
    "is_stateful",
    "render_sequence",
    "scene_digest",
    "write_video",
]

#: Frame file names: ``frame_00042.png`` / ``.exr`` / ``.json``.
FRAME_NAME = "frame_{:05d}"
#: The temporary files of :func:`refnpr.image.atomic_file` for frame files (``.frame_00042.<10
#: hex digits>.png``): removed when a run starts (left only by a SIGKILL).
_TEMP_RE = re.compile(r"^\.frame_\d{5}\.[0-9a-f]{10}\.(png|exr|json)$")

#: progress(done, total, frame, status): status is "rendered", "skipped" or "state" (a frame
#: shaded only to rebuild a stateful style's state).
SequenceProgress = Callable[[int, int, int, str], None]


@dataclass
class SequenceResult:
    """What :func:`render_sequence` did.

    Attributes
    ----------
    out_dir : Path
    frames : list of int
        The frames of the range, in order.
    rendered, skipped : list of int
        Frames written by this run / found done on disk (not rewritten).
    paths : list of Path
        The PNG of every frame of the range, in order.
    stateful : bool
        Whether the style carried state (and so ran from frame 0).
    seconds : float
        Wall time of the run.
    """

    out_dir: Path
    frames: list[int]
    rendered: list[int] = field(default_factory=list)
    skipped: list[int] = field(default_factory=list)
    paths: list[Path] = field(default_factory=list)
    stateful: bool = False
    seconds: float = 0.0


def frame_range(frames: Any, count: int) -> range:
    """Frames ``A .. B - 1`` from ``None`` (all), a ``range``, ``(A, B)`` or ``"A:B"``.

    As a Python slice: ``B`` is excluded and either end may be left out (``"10:"``, ``":20"``)
    or be None; negative numbers count from the end. The result must hold at least one frame.

    Raises
    ------
    ValueError
        A malformed text, or a range outside ``[0, count)`` or empty, naming the frame count.
    """
    if frames is None:
        return range(count)
    if isinstance(frames, range):
        a, b = frames.start, frames.stop
        if frames.step != 1:
            raise ValueError(f"frames: expected consecutive frames (step 1), got {frames!r}")
    elif isinstance(frames, str):
        parts = frames.split(":")
        if len(parts) != 2:
            raise ValueError(
                f"frames: expected A:B (frames A to B - 1, like a Python slice, e.g. 0:24 or "
                f"10:), got {frames!r}"
            )
        try:
            a, b = (int(p) if p.strip() else None for p in parts)
        except ValueError:
            raise ValueError(f"frames: expected whole numbers in A:B, got {frames!r}") from None
    elif isinstance(frames, (tuple, list)) and len(frames) == 2:
        a, b = frames
    else:
        raise TypeError(f"frames: expected None, a range, (A, B) or 'A:B', got {frames!r}")
    a = 0 if a is None else check_int("frames start", a)
    b = count if b is None else check_int("frames stop", b)
    if a < 0:
        a += count
    if b < 0:
        b += count
    if not 0 <= a < b <= count:
        raise ValueError(
            f"frames: {frames!r} selects no frames of 0..{count - 1} ({count} frames); give "
            f"A:B with 0 <= A < B <= {count}"
        )
    return range(a, b)


def is_stateful(style: Style) -> bool:
    """Whether ``style`` carries state from frame to frame (see the module docstring).

    The protocol's contract (:meth:`refnpr.styles.Style.initial_state`): a style is stateful
    exactly when its initial state is not None. Overriding ``shade_frame`` alone says nothing
    (the contour layer passes it through to its base; TAMISS's default configuration has no
    state and is rendered frame by frame like any stateless style).
    """
    return style.initial_state() is not None


def _hash_arrays(h: Any, *arrays: Any) -> None:
    for a in arrays:
        if a is None:
            h.update(b"none")
            continue
        a = np.ascontiguousarray(a)
        h.update(f"{a.dtype.str}{a.shape}".encode())
        h.update(a.tobytes())


def _jsonable(value: Any) -> Any:
    if isinstance(value, dict):
        return {str(k): _jsonable(v) for k, v in sorted(value.items(), key=lambda kv: str(kv[0]))}
    if isinstance(value, (list, tuple)):
        return [_jsonable(v) for v in value]
    if isinstance(value, np.ndarray):
        return {"array": hashlib.sha256(np.ascontiguousarray(value).tobytes()).hexdigest()}
    if isinstance(value, (str, int, float, bool)) or value is None:
        return value
    return repr(value)


def scene_digest(scene: Any) -> str:
    """SHA-256 hex digest of everything of ``scene`` that a render reads: meshes (positions,
    faces, normals, uv, attributes), transforms, materials, camera, lights, ambient, background,
    style table and animation tracks."""
    h = hashlib.sha256()
    c = scene.camera
    h.update(repr((scene.name, scene.ambient, scene.background)).encode())
    _hash_arrays(h, c.eye, c.target, c.up)
    h.update(repr((c.fov_y, c.near, c.far, scene.lights)).encode())
    h.update(json.dumps(_jsonable(scene.style)).encode())
    for obj in scene.objects:
        m = obj.mesh
        h.update(repr((obj.name, m.name, obj.material)).encode())
        _hash_arrays(h, obj.transform, m.positions, m.faces, m.normals, m.uv)
        for k in sorted(m.attributes):
            h.update(k.encode())
            _hash_arrays(h, m.attributes[k])
    if scene.animation is not None:
        h.update(repr(scene.animation).encode())
    return h.hexdigest()


def _style_label(spec: Any) -> Any:
    """The style specification as JSON-able data (for the hash and the record)."""
    if isinstance(spec, Style):
        return {"instance": repr(spec)}
    return _jsonable(spec)


def _file_sha(path: Path) -> str | None:
    try:
        return hashlib.sha256(path.read_bytes()).hexdigest()
    except OSError:
        return None


def _done(out: Path, stem: str, key: str, exr: bool) -> bool:
    """Whether the frame's record matches ``key`` and its files match the record."""
    try:
        record = json.loads((out / f"{stem}.json").read_text())
    except (OSError, ValueError):
        return False
    if not isinstance(record, dict) or record.get("hash") != key:
        return False
    if record.get("png_sha256") != _file_sha(out / f"{stem}.png"):
        return False
    return not exr or (
        record.get("exr_sha256") is not None
        and record.get("exr_sha256") == _file_sha(out / f"{stem}.exr")
    )


def _write_exr(path: Path, rgba: np.ndarray) -> None:
    """Linear float32 RGBA as OpenEXR (ZIP, scanlines): the convention of the conformance kit."""
    try:
        import OpenEXR
    except ImportError:
        raise ValueError(
            "exr: writing EXR frames needs the OpenEXR package; install it with "
            "`pip install 'refnpr[kit]'` (or leave out --exr)"
        ) from None
    arr = np.asarray(rgba, dtype=np.float32)
    channels = {n: np.ascontiguousarray(arr[..., i]) for i, n in enumerate("RGBA")}
    header = {"compression": OpenEXR.ZIP_COMPRESSION, "type": OpenEXR.scanlineimage}
    with atomic_file(path, suffix=".exr") as tmp:
        with OpenEXR.File(header, channels) as f:
            f.write(str(tmp))


def _remove_stray_temporaries(out: Path) -> None:
    for p in out.iterdir():
        if _TEMP_RE.match(p.name) and p.is_file():
            p.unlink(missing_ok=True)


def _style_tracks(scene: Any) -> list[str]:
    anim = scene.animation
    if anim is None:
        return []
    return [t.parts[2] for t in anim.tracks if t.parts[0] == "style"]


def _check_style_tracks(scene: Any, spec: Any, style: Style, user_style: bool) -> None:
    """Each style track's parameter must be one the style takes."""
    params = _style_tracks(scene)
    if not params:
        return
    if isinstance(spec, Style):
        raise TypeError(
            f"style: scene {scene.name!r} animates style parameters ({', '.join(params)}), "
            "which need the style as a name or a table {name = ..., ...}, not a Style instance"
        )
    target = style
    if style.name == "contoured" and (
        not isinstance(spec, dict) or spec.get("name") != "contoured"
    ):
        target = style.base  # `contours = {...}` wraps the named style: its parameters count
    valid = type(target).parameters()
    for p in params:
        if p not in valid:
            whose = "the chosen style" if user_style else "the scene's style"
            raise ValueError(
                f"style: scene {scene.name!r} has a track 'style.{p}', but {whose} "
                f"{target.name!r} has no parameter {p!r} (its parameters: {', '.join(valid)}); "
                + (
                    "leave out --style to use the scene's own style, or pick a style that "
                    f"takes {p!r}"
                    if user_style
                    else f"remove the track or give [style] a style that takes {p!r}"
                )
            )


@dataclass
class _Plan:
    """Everything a frame's pixels and record depend on, checked once per run (picklable: a
    distributed run sends it to the workers)."""

    scene: Any
    spec: Any
    label: Any
    digest: str
    base_style: Style
    animated_style: bool
    stateful: bool
    todo: range
    out: Path
    width: int
    height: int
    spp: int
    exr: bool

    def key_of(self, f: int) -> str:
        """The restart hash of frame ``f`` (module docstring)."""
        blob = {
            "refnpr": __version__,
            "scene": self.digest,
            "style": self.label,
            "size": [self.width, self.height],
            "spp": self.spp,
            "frame": f,
        }
        return hashlib.sha256(json.dumps(blob, sort_keys=True).encode()).hexdigest()

    def style_of(self, f: int) -> Style:
        """The style of frame ``f``: the base style with the frame's style tracks applied."""
        if not self.animated_style:
            return self.base_style
        return style_from_spec({**self.spec, **self.scene.animation.style_values(float(f))})

    def done(self, f: int) -> bool:
        return _done(self.out, FRAME_NAME.format(f), self.key_of(f), self.exr)


def _plan(
    scene: Any,
    style: Any,
    width: int,
    height: int,
    spp: int,
    out_dir: str | os.PathLike,
    frames: Any,
    exr: bool,
    progress: Any,
) -> _Plan:
    """Check the arguments of a sequence run, create ``out_dir`` and remove stray temporaries."""
    width = check_int("width", width, minimum=1)
    height = check_int("height", height, minimum=1)
    spp = check_int("spp", spp, minimum=1)
    if not isinstance(exr, (bool, np.bool_)):
        raise TypeError(f"exr: expected a bool, got {type(exr).__name__} {exr!r}")
    if progress is not None and not callable(progress):
        raise TypeError(
            f"progress: expected a callable progress(done, total, frame, status) or None, got "
            f"{type(progress).__name__}"
        )
    scene = as_scene(scene)
    todo = frame_range(frames, scene.frames)
    out = Path(out_dir)
    if out.exists() and not out.is_dir():
        raise ValueError(f"out_dir: {str(out)!r} is a file; give a directory for the frames")
    user_style = style is not None
    spec = style if user_style else (scene.style or DEFAULT_STYLE)
    base_style = style_from_spec(spec)
    _check_style_tracks(scene, spec, base_style, user_style)
    animated_style = bool(_style_tracks(scene))
    if isinstance(spec, str):
        spec = {"name": spec}
    out.mkdir(parents=True, exist_ok=True)
    _remove_stray_temporaries(out)
    return _Plan(
        scene=scene,
        spec=spec,
        label=_style_label(spec),
        digest=scene_digest(scene),
        base_style=base_style,
        animated_style=animated_style,
        stateful=is_stateful(base_style),
        todo=todo,
        out=out,
        width=width,
        height=height,
        spp=spp,
        exr=bool(exr),
    )


class _Shader:
    """Shades consecutive frames of a plan: the style protocol, one reused RenderContext.

    ``shade(f)`` renders frame ``f`` from the state the previous ``shade`` left (the style's
    ``initial_state()`` at first); ``skip()`` marks a gap, after which the next frame computes
    its own previous still.
    """

    def __init__(self, plan: _Plan, first: int) -> None:
        self.plan = plan
        self.ctx: RenderContext | None = None
        self.state = plan.base_style.initial_state()
        self.prev = plan.scene.at(first - 1) if first > 0 else None

    def skip(self) -> None:
        self.prev = None

    def shade(self, f: int) -> Any:
        plan = self.plan
        still = plan.scene.at(f)
        if self.prev is None and f > 0:
            self.prev = plan.scene.at(f - 1)
        frame_style = plan.style_of(f).for_frame(still, self.prev)
        if self.ctx is None:
            self.ctx = RenderContext(still, frame_style, plan.width, plan.height, plan.spp)
        image, self.state = self.ctx.render_frame(still, frame_style, self.state)
        self.prev = still
        return image


def _png_bytes(image: Any) -> bytes:
    """The frame's 8-bit sRGB RGBA PNG, encoded in memory (the bytes every run writes)."""
    import imageio.v3 as iio

    return bytes(iio.imwrite("<bytes>", image.to_srgb8(), extension=".png"))


def _write_frame(
    plan: _Plan,
    f: int,
    png: bytes,
    rgba: np.ndarray | None,
    extra: dict[str, Any] | None = None,
) -> None:
    """Write frame ``f``: its PNG (and EXR from ``rgba``), then its record, each atomically.

    ``extra`` adds keys to the record (not to its hash): a distributed chunk's ``state_from``.
    """
    out = plan.out
    stem = FRAME_NAME.format(f)
    (out / f"{stem}.json").unlink(missing_ok=True)  # a stale record must not outlive its PNG
    with atomic_file(out / f"{stem}.png", suffix=".png") as tmp:
        tmp.write_bytes(png)
    record = {
        "hash": plan.key_of(f),
        "frame": f,
        "scene": plan.scene.name,
        "style": plan.label,
        "size": [plan.width, plan.height],
        "spp": plan.spp,
        "refnpr": __version__,
        "png_sha256": hashlib.sha256(png).hexdigest(),
        **(extra or {}),
    }
    if plan.exr:
        _write_exr(out / f"{stem}.exr", rgba)
        record["exr_sha256"] = _file_sha(out / f"{stem}.exr")
    with atomic_file(out / f"{stem}.json", suffix=".json") as tmp:
        tmp.write_text(json.dumps(record, indent=1, sort_keys=True))


def render_sequence(
    scene: Any,
    style: Any = None,
    width: int = 512,
    height: int = 512,
    spp: int = 1,
    *,
    out_dir: str | os.PathLike,
    frames: Any = None,
    exr: bool = False,
    progress: SequenceProgress | None = None,
) -> SequenceResult:
    """Render frames of an animated scene into ``out_dir`` (restartable; module docstring).

    Parameters
    ----------
    scene : Scene, str or path
        An animated scene (or a still: one frame), a built-in name or a .toml file.
    style : Style, str, dict or None
        As for :func:`refnpr.render.render`; None: the scene's ``[style]``. The scene's style
        tracks set their parameters on it each frame (an error if it lacks one).
    width, height, spp : int
        Image size and samples per pixel.
    out_dir : str or path
        Created if missing.
    frames : None, range, (A, B) or "A:B"
        Frames A .. B - 1 (default: all; see :func:`frame_range`).
    exr : bool
        Also write ``frame_NNNNN.exr`` (linear float32 RGBA; needs OpenEXR).
    progress : callable(done, total, frame, status), optional
        Called after each frame of the range (and each state-only frame before it).

    Returns
    -------
    SequenceResult

    See Also
    --------
    refnpr.distributed.render_sequence : the same frames, bytes and records on a Dask cluster.
    """
    t_start = time.perf_counter()
    plan = _plan(scene, style, width, height, spp, out_dir, frames, exr, progress)
    todo, out, stateful = plan.todo, plan.out, plan.stateful

    result = SequenceResult(out, list(todo), stateful=stateful)
    result.paths = [out / f"{FRAME_NAME.format(f)}.png" for f in todo]
    done_flags = {f: plan.done(f) for f in todo}
    if all(done_flags.values()):  # nothing to render: no state to rebuild either
        result.skipped = list(todo)
        result.seconds = time.perf_counter() - t_start
        if progress is not None:
            for i, f in enumerate(todo):
                progress(i + 1, len(todo), f, "skipped")
        return result
    first = todo.start
    count = 0
    if stateful:  # from frame 0, or state_frames() before the first frame still to render
        back = plan.base_style.state_frames()
        need = min(f for f in todo if not done_flags[f])
        first = 0 if back is None else max(0, need - back)
        for f in range(todo.start, min(first, todo.stop)):  # done, and before the state's reach
            result.skipped.append(f)
            count += 1
            if progress is not None:
                progress(count, len(todo), f, "skipped")
    # a stateful style runs up to the last frame still to render; done frames after it are kept
    stop = max(f for f in todo if not done_flags[f]) + 1 if stateful else todo.stop
    run = range(first, todo.stop)

    shader = _Shader(plan, first)
    for f in run:
        in_range = f in todo
        done = in_range and done_flags[f]
        if done and (not stateful or f >= stop):
            result.skipped.append(f)
            count += 1
            if progress is not None:
                progress(count, len(todo), f, "skipped")
            shader.skip()
            continue
        image = shader.shade(f)
        if not in_range:
            if progress is not None:
                progress(count, len(todo), f, "state")
            continue
        count += 1
        if done:  # stateful: shaded for its state; the files on disk are this frame already
            result.skipped.append(f)
            if progress is not None:
                progress(count, len(todo), f, "skipped")
            continue
        _write_frame(plan, f, _png_bytes(image), image.rgba if plan.exr else None)
        result.rendered.append(f)
        if progress is not None:
            progress(count, len(todo), f, "rendered")
    result.seconds = time.perf_counter() - t_start
    return result


def write_video(paths: list[Path] | list[str], path: str | os.PathLike, fps: float) -> Path:
    """Encode PNG frames as an MP4 (H.264 through imageio-ffmpeg's ffmpeg) or an animated GIF.

    Parameters
    ----------
    paths : list of path
        The frames in order (8-bit RGBA PNGs of one size); alpha is dropped.
    path : str or path
        ``.mp4`` or ``.gif``; written through a temporary file and an atomic rename.
    fps : float
        Frames per second (> 0).

    Raises
    ------
    ValueError
        Another suffix, no frames, frames of different sizes, or (MP4) imageio-ffmpeg missing,
        naming the extra to install.
    """
    import imageio.v3 as iio

    target = Path(path)
    suffix = target.suffix.lower()
    if suffix not in (".mp4", ".gif"):
        raise ValueError(f"video: expected a file name ending in .mp4 or .gif, got {str(path)!r}")
    if not paths:
        raise ValueError("video: no frames to encode")
    if isinstance(fps, bool) or not isinstance(fps, (int, float)) or not fps > 0:
        raise ValueError(f"fps: expected a positive number, got {fps!r}")
    if suffix == ".mp4":
        try:
            import imageio_ffmpeg  # noqa: F401
        except ImportError:
            raise ValueError(
                f"video: writing {str(path)!r} (MP4) needs ffmpeg from the imageio-ffmpeg "
                "package; install the extra with `pip install 'refnpr[video]'`, or write a "
                ".gif instead"
            ) from None
    frames = [np.asarray(iio.imread(p))[..., :3] for p in paths]
    shape = frames[0].shape
    for p, fr in zip(paths, frames, strict=True):
        if fr.shape != shape:
            raise ValueError(
                f"video: frame {str(p)!r} is {fr.shape[1]}x{fr.shape[0]}, the first is "
                f"{shape[1]}x{shape[0]}; all frames need one size"
            )
    stack = np.stack(frames)
    with atomic_file(target, suffix=suffix) as tmp:
        if suffix == ".gif":
            iio.imwrite(tmp, stack, extension=".gif", duration=1000.0 / fps, loop=0)
        else:
            # H.264 in yuv420p needs even sizes: repeat the last row / column where odd
            pad = ((0, 0), (0, stack.shape[1] % 2), (0, stack.shape[2] % 2), (0, 0))
            stack = np.pad(stack, pad, mode="edge")
            iio.imwrite(
                tmp,
                stack,
                plugin="FFMPEG",
                extension=".mp4",
                fps=float(fps),
                codec="libx264",
                macro_block_size=1,
                ffmpeg_log_level="error",
            )
    return target
