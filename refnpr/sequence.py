"""Render frames of an animated scene to a directory, restartably (``refnpr animate``).

Frame ``f`` is ``DIR/frame_00000.png`` (8-bit sRGB RGBA), optionally ``.exr`` (linear float32
RGBA and the frame's G-buffer passes, the layout of :mod:`refnpr.exr`), and ``.json``, the
restart record, written last; every file through a temporary file and an atomic rename (a
SIGKILL's temporaries are removed by the next run). A record holds a hash of everything the
pixels depend on (:func:`scene_digest`; the style's parameter values, arrays by their dtype,
shape and bytes; the content of the image files the scene and the style name) and the SHA-256
of the files it describes; a frame whose record and files match is done. A frame rendered again
without ``.exr`` loses the ``.exr`` of its earlier render. A stateless style skips done frames;
a stateful one re-runs from frame 0 (or ``Style.state_frames()`` frames before the first frame
still to render) up to the last frame still to render, without rewriting done frames. Either way
the directory after any number of kills and restarts is byte-identical to an uninterrupted run
(docs/animation.md).

One run at a time writes a directory: a run holds an exclusive ``flock`` on ``DIR`` itself (POSIX;
released when the run ends or its process dies; no file is left), and a second run on the same
directory, in any process, is refused with a ValueError instead of removing the first run's
temporary files under way.
"""

from __future__ import annotations

import contextlib
import dataclasses
import hashlib
import json
import os
import re
import time
from collections.abc import Callable, Iterator
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from . import __version__
from ._atomic import check_output_file, check_parent_writable
from .exr import image_channels, write_exr_channels
from .image import Image, atomic_file
from .render import DEFAULT_STYLE, RenderContext, _check_args, as_scene
from .scenes._params import check_int
from .styles import Style, style_from_spec
from .styles._declare import Values
from .texture import EmbeddedImage

try:
    import fcntl
except ImportError:  # not POSIX: no lock
    fcntl = None

__all__ = [
    "SequenceResult",
    "frame_range",
    "is_stateful",
    "render_sequence",
    "scene_digest",
    "write_video",
]

#: Frame file names: ``frame_00042.png`` / ``.exr`` / ``.json`` (six digits from frame 100000).
FRAME_NAME = "frame_{:05d}"
#: The temporary files of :func:`refnpr.image.atomic_file` for frame files (``.frame_00042.<10
#: hex digits>.png``): removed when a run starts (left only by a SIGKILL).
_TEMP_RE = re.compile(r"^\.frame_\d{5,}\.[0-9a-f]{10}\.(png|exr|json)$")

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

    def _tick(self, f: int, status: str, progress: SequenceProgress | None) -> None:
        """Record frame ``f`` as rendered or skipped (not a "state" frame) and report it."""
        if status != "state":
            (self.rendered if status == "rendered" else self.skipped).append(f)
        if progress is not None:
            progress(len(self.rendered) + len(self.skipped), len(self.frames), f, status)


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
    a, b = (v + count if v < 0 else v for v in (a, b))
    if not 0 <= a < b <= count:
        raise ValueError(
            f"frames: {frames!r} selects no frames of 0..{count - 1} ({count} frames); give "
            f"A:B with 0 <= A < B <= {count}"
        )
    return range(a, b)


def is_stateful(style: Style) -> bool:
    """Whether ``style`` carries state from frame to frame: exactly when its
    :meth:`~refnpr.styles.Style.initial_state` is not None (not whether it overrides
    ``shade_frame``: the contour layer passes that through to its base)."""
    return style.initial_state() is not None


def _hash_arrays(h: Any, *arrays: Any) -> None:
    for a in arrays:
        if a is None:
            h.update(b"none")
            continue
        a = np.ascontiguousarray(a)
        h.update(f"{a.dtype.str}{a.shape}".encode())
        h.update(a.tobytes())


def _array_entry(a: np.ndarray) -> dict[str, Any]:
    """An array as JSON: the SHA-256 of its bytes, its dtype and its shape."""
    a = np.ascontiguousarray(a)
    digest = hashlib.sha256(a.tobytes()).hexdigest()
    return {"array": digest, "dtype": a.dtype.str, "shape": list(a.shape)}


def _jsonable(value: Any) -> Any:
    """``value`` as JSON for a record: tables and lists as such, arrays by
    :func:`_array_entry`, numpy scalars as numbers, anything else by its ``repr``."""
    if isinstance(value, dict):
        return {str(k): _jsonable(v) for k, v in sorted(value.items(), key=lambda kv: str(kv[0]))}
    if isinstance(value, (list, tuple)):
        return [_jsonable(v) for v in value]
    if isinstance(value, np.ndarray):
        return _array_entry(value)
    if isinstance(value, np.generic):
        value = value.item()
    if isinstance(value, (str, int, float, bool)) or value is None:
        return value
    return repr(value)


#: Files hashed by content up to this size; a larger one by its size and modification time.
_CONTENT_HASH_BYTES = 64 << 20


def _file_entry(path: str, files: dict[str, Any]) -> Any:
    """What a string that names an existing file stands for in a digest: its path and its
    content's SHA-256 (above :data:`_CONTENT_HASH_BYTES`, its size and modification time),
    memoized in ``files``; None where ``path`` names no file."""
    if path in files:
        return files[path]
    entry = None
    try:
        st = os.stat(path)
    except (OSError, ValueError):  # no such file, or a name no file can have
        st = None
    if st is not None and Path(path).is_file():
        if st.st_size > _CONTENT_HASH_BYTES:
            entry = {"file": path, "size": st.st_size, "mtime_ns": st.st_mtime_ns}
        else:
            entry = {"file": path, "sha256": _file_sha(Path(path))}
    files[path] = entry
    return entry


def _canonical(value: Any, files: dict[str, Any], depth: int = 0) -> Any:
    """``value`` as JSON that holds everything a render reads of it: as :func:`_jsonable`,
    and a string naming a file also by the file's content (:func:`_file_entry`), an embedded
    image by its bytes' digest, a Style instance by its class and parameter values
    (:func:`_style_values`), a dataclass by its fields."""
    if depth > 32:
        return repr(value)
    if isinstance(value, EmbeddedImage):
        return {"embedded": value.sha256}
    if isinstance(value, str):
        entry = _file_entry(value, files)
        return value if entry is None else entry
    if isinstance(value, Style):
        return _style_values(value, files, depth + 1)
    if isinstance(value, Values):
        return {n: _canonical(v, files, depth + 1) for n, v in value.items()}
    if isinstance(value, dict):
        items = sorted(value.items(), key=lambda kv: str(kv[0]))
        return {str(k): _canonical(v, files, depth + 1) for k, v in items}
    if isinstance(value, (list, tuple)):
        return [_canonical(v, files, depth + 1) for v in value]
    if dataclasses.is_dataclass(value) and not isinstance(value, type):
        fields = {f.name: getattr(value, f.name) for f in dataclasses.fields(value)}
        return {"type": _type_name(value), **_canonical(fields, files, depth + 1)}
    return _jsonable(value)


def _type_name(value: Any) -> str:
    return f"{type(value).__module__}.{type(value).__qualname__}"


def _style_values(style: Style, files: dict[str, Any], depth: int) -> dict[str, Any]:
    """A Style instance as JSON for a digest: its class, ``params()``, and the full values of
    every parameter declaration it holds (the validated :class:`~refnpr.styles._declare.Values`
    among its attributes and those of its refnpr objects, arrays by their bytes: ``params()``
    shows an array by its shape only) and of the styles it wraps."""
    found: dict[str, Any] = {}

    def visit(obj: Any, where: str, level: int) -> None:
        for k, v in sorted(vars(obj).items()):
            if isinstance(v, (Values, Style)):
                found[f"{where}{k}"] = _canonical(v, files, depth)
            elif level < 2 and type(v).__module__.startswith("refnpr.") and hasattr(v, "__dict__"):
                visit(v, f"{where}{k}.", level + 1)  # a config or a layer holding values

    if hasattr(style, "__dict__"):
        visit(style, "", 0)
    return {
        "type": _type_name(style),
        "params": _canonical(style.params(), files, depth),
        "values": found,
    }


def scene_digest(scene: Any) -> str:
    """SHA-256 hex digest of everything of ``scene`` that a render reads: meshes (positions,
    faces, normals, uv, attributes), transforms, materials (with the content of their texture
    files), camera, lights, ambient, background, style table (with the content of the files it
    names) and animation tracks."""
    return _scene_digest(scene, {})


def _scene_digest(scene: Any, files: dict[str, Any]) -> str:
    h = hashlib.sha256()
    c = scene.camera
    h.update(repr((scene.name, scene.ambient, scene.background)).encode())
    _hash_arrays(h, c.eye, c.target, c.up)
    h.update(repr((c.fov_y, c.near, c.far, scene.lights)).encode())
    h.update(json.dumps(_canonical(scene.style, files)).encode())
    for obj in scene.objects:
        m = obj.mesh
        h.update(repr((obj.name, m.name, obj.material)).encode())
        textures = [obj.material.texture, obj.material.color_texture]
        h.update(json.dumps(_canonical(textures, files)).encode())
        _hash_arrays(h, obj.transform, m.positions, m.faces, m.normals, m.uv)
        for k in sorted(m.attributes):
            h.update(k.encode())
            _hash_arrays(h, m.attributes[k])
    if scene.animation is not None:
        h.update(repr(scene.animation).encode())
    return h.hexdigest()


def _file_sha(path: Path) -> str | None:
    try:
        return hashlib.sha256(path.read_bytes()).hexdigest()
    except OSError:
        return None


def _write_exr(path: Path, rgba: Any) -> None:
    """A frame's EXR (:mod:`refnpr.exr`): ``rgba`` is an ``(H, W, 4)`` linear straight-alpha
    array (RGBA only) or an Image (its RGBA and passes). A failed write (a full disk) is a
    ValueError naming the file and the free space."""
    if isinstance(rgba, Image):
        channels = image_channels(rgba.rgba, rgba.passes)
    else:
        channels = image_channels(np.asarray(rgba, dtype=np.float32))
    write_exr_channels(path, channels, opener=atomic_file)


def _check_style_tracks(scene: Any, spec: Any, style: Style, user_style: bool) -> list[str]:
    """The parameters the scene's style tracks animate, each one the style takes."""
    anim = scene.animation
    params = [t.parts[2] for t in anim.tracks if t.parts[0] == "style"] if anim is not None else []
    if not params:
        return params
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
    return params


@dataclass
class _Plan:
    """Everything a frame's pixels and record depend on, checked once per run (picklable: a
    distributed run sends it to the workers)."""

    scene: Any
    spec: Any
    label: Any
    digest: str
    style_digest: str
    base_style: Style
    animated_style: bool
    stateful: bool
    todo: range
    out: Path
    width: int
    height: int
    spp: int
    exr: bool
    created: tuple[Path, ...] = ()  # the directories this run made for out_dir, deepest first

    def result(self) -> SequenceResult:
        paths = [self.out / f"{FRAME_NAME.format(f)}.png" for f in self.todo]
        return SequenceResult(self.out, list(self.todo), paths=paths, stateful=self.stateful)

    def key_of(self, f: int) -> str:
        """The restart hash of frame ``f`` (module docstring)."""
        blob = {
            "refnpr": __version__,
            "scene": self.digest,
            "style": self.label,
            "style_values": self.style_digest,
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
        """Whether frame ``f``'s record matches its hash and its files match the record."""
        stem = FRAME_NAME.format(f)
        try:
            record = json.loads((self.out / f"{stem}.json").read_text())
        except (OSError, ValueError):
            return False
        if not isinstance(record, dict) or record.get("hash") != self.key_of(f):
            return False
        if record.get("png_sha256") != _file_sha(self.out / f"{stem}.png"):
            return False
        return not self.exr or (
            record.get("exr_sha256") is not None
            and record.get("exr_sha256") == _file_sha(self.out / f"{stem}.exr")
        )


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
    """Check the arguments of a sequence run and create ``out_dir``."""
    width, height, spp = _check_args(width, height, spp)
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
    check_parent_writable(out / "frame", str(out_dir), "out_dir")  # a file above it, read-only
    user_style = style is not None
    spec = style if user_style else (scene.style or DEFAULT_STYLE)
    base_style = style_from_spec(spec)
    animated_style = bool(_check_style_tracks(scene, spec, base_style, user_style))
    if isinstance(spec, str):
        spec = {"name": spec}
    files: dict[str, Any] = {}  # the files the scene and the style name, hashed once
    digest = _scene_digest(scene, files)
    values = json.dumps(_canonical(spec, files), sort_keys=True).encode()
    created = tuple(p for p in (out, *out.parents) if not p.exists())
    out.mkdir(parents=True, exist_ok=True)
    return _Plan(
        scene=scene,
        spec=spec,
        label={"instance": repr(spec)} if isinstance(spec, Style) else _jsonable(spec),
        digest=digest,
        style_digest=hashlib.sha256(values).hexdigest(),
        base_style=base_style,
        animated_style=animated_style,
        stateful=is_stateful(base_style),
        todo=todo,
        out=out,
        width=width,
        height=height,
        spp=spp,
        exr=bool(exr),
        created=created,
    )


@contextlib.contextmanager
def claim(out: Path, created: tuple[Path, ...] = ()) -> Iterator[None]:
    """Hold ``out``'s run lock for the block and remove the temporaries a killed run left; if
    the block raises, remove the directories of ``created`` (:attr:`_Plan.created`) that are
    still empty, so that a run that wrote no frame leaves no directory behind (only while
    holding the lock: a run refused by it leaves the holder's directory alone).

    Raises
    ------
    ValueError
        Another run (of this or another process) holds the lock.
    """
    if fcntl is None:
        with _removing_on_failure(created):
            _remove_temporaries(out)
            yield
        return
    fd = os.open(out, os.O_RDONLY)
    try:
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except OSError:
            raise ValueError(
                f"out_dir: {str(out)!r} is being written by another `refnpr animate` run; "
                "wait for it to end, or give another directory"
            ) from None
        with _removing_on_failure(created):
            _remove_temporaries(out)
            yield
    finally:
        os.close(fd)  # releases the lock


@contextlib.contextmanager
def _removing_on_failure(created: tuple[Path, ...]) -> Iterator[None]:
    """Remove the empty directories of ``created`` (deepest first) if the block raises."""
    try:
        yield
    except BaseException:
        for d in created:  # a directory with anything in it stays, and its parents
            try:
                d.rmdir()
            except OSError:
                break
        raise


def _remove_temporaries(out: Path) -> None:
    for p in out.iterdir():  # the temporaries a SIGKILL left
        if _TEMP_RE.match(p.name) and p.is_file():
            p.unlink(missing_ok=True)


class _Shader:
    """Shades frames of a plan through the style protocol with one reused RenderContext, each
    from the state the previous ``shade`` left (the style's ``initial_state()`` at first)."""

    def __init__(self, plan: _Plan) -> None:
        self.plan = plan
        self.ctx: RenderContext | None = None
        self.state = plan.base_style.initial_state()
        self.last: tuple[int, Any] | None = None  # the last frame shaded and its still

    def shade(self, f: int) -> Any:
        plan = self.plan
        still = plan.scene.at(f)
        if self.last is not None and self.last[0] == f - 1:
            prev = self.last[1]
        else:  # the previous still comes from the animation, rendered or not
            prev = plan.scene.at(f - 1) if f > 0 else None
        frame_style = plan.style_of(f).for_frame(still, prev)
        if self.ctx is None:
            self.ctx = RenderContext(
                still, frame_style, plan.width, plan.height, plan.spp, passes=plan.exr
            )
        image, self.state = self.ctx.render_frame(still, frame_style, self.state)
        self.last = (f, still)
        return image


def _write_frame(
    plan: _Plan, f: int, png: bytes, frame: Any, extra: dict[str, Any] | None = None
) -> None:
    """Write frame ``f``: its PNG (and EXR from ``frame``: the frame's Image, with its passes, or
    its ``(H, W, 4)`` pixels, RGBA only), then its record, each atomically.

    ``extra`` adds keys to the record (not to its hash): a distributed chunk's ``state_from``.
    Without ``plan.exr`` an earlier render's EXR of the frame is removed: it would not show
    the new PNG's pixels.
    """
    out = plan.out
    stem = FRAME_NAME.format(f)
    (out / f"{stem}.json").unlink(missing_ok=True)  # a stale record must not outlive its PNG
    if not plan.exr:
        (out / f"{stem}.exr").unlink(missing_ok=True)
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
    if plan.animated_style:  # what the scene's style tracks set on "style" for this frame
        record["style_tracks"] = _jsonable(plan.scene.animation.style_values(float(f)))
    if plan.exr:
        _write_exr(out / f"{stem}.exr", frame)
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
        tracks set their parameters on it each frame (an error if it lacks one), also a
        parameter the dict gives: the frame's record lists the tracked values it used
        (``style_tracks``). ``refnpr animate --param`` instead replaces the track of the
        parameter it sets.
    width, height, spp : int
        Image size and samples per pixel.
    out_dir : str or path
        Created if missing.
    frames : None, range, (A, B) or "A:B"
        Frames A .. B - 1 (default: all; see :func:`frame_range`).
    exr : bool
        Also write ``frame_NNNNN.exr`` (linear float32 RGBA and the frame's G-buffer passes,
        :mod:`refnpr.exr`; needs OpenEXR).
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
    with claim(plan.out, plan.created):
        result = _run(plan, progress)
    result.seconds = time.perf_counter() - t_start
    return result


def _run(plan: _Plan, progress: SequenceProgress | None) -> SequenceResult:
    """The frames of ``plan`` not done yet, rendered in order (module docstring)."""
    todo, result = plan.todo, plan.result()
    done_flags = {f: plan.done(f) for f in todo}
    missing = [f for f in todo if not done_flags[f]]
    first = stop = todo.start  # shade from first; skip done frames before first or from stop
    if plan.stateful and missing:  # from frame 0, or state_frames() before the first missing
        back = plan.base_style.state_frames()
        first = 0 if back is None else max(0, missing[0] - back)
        stop = missing[-1] + 1  # done frames after the last missing one are kept, not shaded
    shader = None
    for f in range(min(first, todo.start), todo.stop):
        done = done_flags.get(f, False)
        if done and (f < first or f >= stop):
            result._tick(f, "skipped", progress)
            continue
        shader = shader or _Shader(plan)
        image = shader.shade(f)
        if done or f not in todo:  # shaded for the state only (done: its files are this frame)
            result._tick(f, "skipped" if done else "state", progress)
            continue
        _write_frame(plan, f, image.to_png_bytes(), image if plan.exr else None)
        result._tick(f, "rendered", progress)
    return result


def _video_suffix(path: str | os.PathLike, what: str = "video") -> str:
    """The suffix of a video file name (``.mp4`` or ``.gif``) that can be written (not a
    directory, in a writable directory: :func:`~refnpr._atomic.check_output_file`); for MP4,
    imageio-ffmpeg must be installed. ValueError naming ``what``, the path and the fix
    otherwise."""
    suffix = Path(path).suffix.lower()
    if suffix not in (".mp4", ".gif"):
        raise ValueError(f"{what}: expected a file name ending in .mp4 or .gif, got {str(path)!r}")
    if suffix == ".mp4":
        try:
            import imageio_ffmpeg  # noqa: F401
        except ImportError:
            raise ValueError(
                f"{what}: writing {str(path)!r} (MP4) needs ffmpeg from the imageio-ffmpeg "
                "package; install the extra with `pip install 'refnpr[video]'`, or write a "
                ".gif instead"
            ) from None
    check_output_file(path, what, suffix)
    return suffix


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
    suffix = _video_suffix(path)
    if not paths:
        raise ValueError("video: no frames to encode")
    if isinstance(fps, bool) or not isinstance(fps, (int, float)) or not fps > 0:
        raise ValueError(f"fps: expected a positive number, got {fps!r}")
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
