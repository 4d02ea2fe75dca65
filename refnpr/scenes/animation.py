"""Animated scenes: tracks of keyframes for the camera, lights, object transforms and style
parameters, and the still scene of any (fractional) frame.

A :class:`Track` animates one *target*, named the way a scene file names the part
(``camera.eye``, ``light[0].color``, ``object "teapot".rotation``, ``style.n``); the targets,
their values and interpolations are tabled in docs/animation.md. An animated object's transform
is ``T @ R @ S``; the parts without a track come from its static transform, which must then have
no shear.
"""

from __future__ import annotations

import dataclasses
import math
import re
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from ..raster import Camera
from ._params import check_int, check_real, describe
from .tracks import (
    INTERPOLATIONS,
    Keyframe,
    check_unit_quaternion,
    interpolate,
    quaternion_from_matrix,
    quaternion_matrix,
)

__all__ = ["Animation", "Track", "Keyframe", "check_keys_in_range", "parse_target"]

#: The most frames an animation may have (a frame is a file; ~11.5 hours at 24 fps).
MAX_FRAMES = 1_000_000

_PARTS = {
    "camera": {"eye": 3, "target": 3, "up": 3, "fov_y": 1, "near": 1, "far": 1},
    "light": {"direction": 3, "position": 3, "color": 3},
    "object": {"translation": 3, "rotation": 4, "scale": 3},
}
_BROADCAST = {("light", "color"), ("object", "scale")}

_TARGET_RE = re.compile(
    r"^(?:camera\.(?P<camera>\w+)"
    r"|light\[(?P<light>\d+)\]\.(?P<lpart>\w+)"
    r'|object\s*"(?P<object>[^"]+)"\.(?P<opart>\w+)'
    r"|style\.(?P<style>[A-Za-z_]\w*))$"
)
_TARGET_HELP = (
    "camera.eye|target|up|fov_y|near|far, light[i].direction|position|color, "
    'object "name".translation|rotation|scale, style.<param>'
)


def parse_target(target: str) -> tuple[str, Any, str]:
    """Split a track target into ``(part, which, attribute)``.

    ``"camera.eye"`` -> ``("camera", None, "eye")``; ``"light[0].color"`` -> ``("light", 0,
    "color")``; ``'object "teapot".rotation'`` -> ``("object", "teapot", "rotation")``;
    ``"style.n"`` -> ``("style", None, "n")``.

    Raises
    ------
    ValueError
        For anything else, listing the valid forms.
    """
    if not isinstance(target, str):
        raise TypeError(f"target: expected a string such as 'camera.eye', got {describe(target)}")
    m = _TARGET_RE.match(target.strip())
    if m is not None:
        if m["style"] is not None:
            return "style", None, m["style"]
        if m["camera"] is not None:
            part, which, attr = "camera", None, m["camera"]
        elif m["light"] is not None:
            part, which, attr = "light", int(m["light"]), m["lpart"]
        else:
            part, which, attr = "object", m["object"], m["opart"]
        if attr in _PARTS[part]:
            return part, which, attr
    raise ValueError(f"target: unknown track target {target!r}; valid targets: {_TARGET_HELP}")


@dataclass(frozen=True)
class Track:
    """The keys of one animated target.

    Attributes
    ----------
    target : str
        What it animates (see the module docstring), e.g. ``"camera.eye"``.
    keys : tuple of Keyframe
        At least one, frames strictly increasing; ``(frame, value)`` pairs are accepted.
    interpolation : str, optional
        ``"linear"`` (default) or ``"catmull_rom"``; rotations: ``"slerp"`` (the default).
    integer : bool
        Style tracks only: round the value to the nearest integer (a count such as ``n``).
    """

    target: str
    keys: tuple[Keyframe, ...]
    interpolation: str | None = None
    integer: bool = False

    def __post_init__(self) -> None:
        part, which, attr = parse_target(self.target)
        object.__setattr__(self, "target", self.target.strip())
        kind = "rotation" if (part, attr) == ("object", "rotation") else "vector"
        interp = INTERPOLATIONS[kind][0] if self.interpolation is None else self.interpolation
        if interp not in INTERPOLATIONS[kind]:
            raise ValueError(
                f"interpolation: {interp!r} is not available for {self.target!r}; "
                f"expected one of {INTERPOLATIONS[kind]}"
            )
        object.__setattr__(self, "interpolation", interp)
        if not isinstance(self.integer, bool):
            raise TypeError(f"integer: expected a bool, got {describe(self.integer)}")
        if self.integer and part != "style":
            raise ValueError(f"integer: only style tracks round to integers, not {self.target!r}")
        keys = self.keys
        if isinstance(keys, (str, bytes, Mapping)) or not isinstance(keys, Sequence):
            raise TypeError(f"keys: expected a list of keys, got {describe(keys)}")
        if not keys:
            raise ValueError(f"keys: track {self.target!r} needs at least one key")
        size = _PARTS[part][attr] if part in _PARTS else None  # style: any length, one for all
        out = []
        for i, key in enumerate(keys):
            where = f"keys[{i}]"
            if not isinstance(key, Keyframe):
                if isinstance(key, (str, bytes)) or not isinstance(key, Sequence) or len(key) != 2:
                    raise TypeError(
                        f"{where}: expected a Keyframe or a (frame, value) pair, got {describe(key)}"
                    )
                try:
                    key = Keyframe(*key)
                except (TypeError, ValueError) as exc:
                    raise type(exc)(f"{where}: {exc}") from None
            value = key.value
            if size is not None and len(value) == 1 and (part, attr) in _BROADCAST:
                value = value * size
            want = size if size is not None else len(out[0].value) if out else len(value)
            if len(value) != want:
                what = "a quaternion [x, y, z, w]" if kind == "rotation" else f"{want} numbers"
                raise ValueError(
                    f"{where}: {self.target} expects {what}, got {len(value)}: {list(value)}"
                )
            if kind == "rotation":
                value = check_unit_quaternion(f"{where}: value", value)
            if out and key.frame <= out[-1].frame:
                raise ValueError(
                    f"{where}: frame {key.frame:g} is not after the previous key's frame "
                    f"{out[-1].frame:g}; keys must be in increasing frame (or time) order"
                )
            out.append(Keyframe(key.frame, value))
        object.__setattr__(self, "keys", tuple(out))

    @property
    def parts(self) -> tuple[str, Any, str]:
        """``parse_target(self.target)``."""
        return parse_target(self.target)

    def value_at(self, frame: float) -> tuple[float, ...]:
        """The interpolated value at ``frame`` (held before the first and after the last key)."""
        return interpolate(self.keys, float(frame), self.interpolation)


def check_keys_in_range(where: str, keys, frames: int, fps: float, *, error=ValueError) -> None:
    """An ``error`` starting with ``where`` for the first of ``keys`` after the last frame."""
    for j, key in enumerate(keys):
        if key.frame > frames - 1:
            raise error(
                f"{where}: keys[{j}]: frame {key.frame:g} (time {key.frame / fps:g} s at "
                f"{fps:g} fps) lies after the last frame {frames - 1} (frames = {frames}); use "
                f"frames = {math.ceil(key.frame) + 1} or an earlier key"
            )


def _decompose(name: str, m: np.ndarray) -> tuple[np.ndarray, tuple[float, ...], np.ndarray]:
    """Translation, rotation quaternion and per-axis scale of an affine ``T @ R @ S`` matrix."""
    a = np.asarray(m, dtype=np.float64)[:3, :3]
    s = np.linalg.norm(a, axis=0)
    r = a / s
    if np.linalg.det(r) < 0:
        s[0], r[:, 0] = -s[0], -r[:, 0]
    if not np.allclose(r.T @ r, np.eye(3), atol=1e-9):
        raise ValueError(
            f"object {name!r}: its static transform has shear, so an animated translation, "
            "rotation or scale cannot replace one part of it; give the object a transform of "
            "translate / rotate_deg / scale (or animate its translation, rotation and scale)"
        )
    return np.array(m, dtype=np.float64)[:3, 3].copy(), quaternion_from_matrix(r), s


@dataclass(frozen=True)
class Animation:
    """Frames, frame rate and tracks of an animated scene.

    Attributes
    ----------
    frames : int
        Number of frames (1 to :data:`MAX_FRAMES`); frame numbers run over ``[0, frames - 1]``.
    fps : float
        Frames per second (> 0): time = frame / fps.
    tracks : tuple of Track
        At most one per target; every key within ``[0, frames - 1]``.
    """

    frames: int
    fps: float = 24.0
    tracks: tuple[Track, ...] = ()

    def __post_init__(self) -> None:
        frames = check_int("frames", self.frames, minimum=1, maximum=MAX_FRAMES)
        object.__setattr__(self, "frames", frames)
        object.__setattr__(self, "fps", check_real("fps", self.fps, positive=True))
        tracks = tuple(self.tracks)
        seen: set[str] = set()
        for i, track in enumerate(tracks):
            if not isinstance(track, Track):
                raise TypeError(f"tracks[{i}]: expected a Track, got {type(track).__name__}")
            if track.target in seen:
                raise ValueError(
                    f"tracks[{i}]: a second track for {track.target!r}; give each target one "
                    "track (put all its keys in it)"
                )
            seen.add(track.target)
            check_keys_in_range(f"tracks[{i}] {track.target!r}", track.keys, self.frames, self.fps)
        object.__setattr__(self, "tracks", tracks)

    def check_frame(self, frame: Any) -> float:
        """``frame`` as a float in ``[0, frames - 1]`` (fractional allowed), else ValueError."""
        if isinstance(frame, bool) or not isinstance(frame, (int, float, np.integer, np.floating)):
            raise TypeError(f"frame: expected a number, got {describe(frame)}")
        try:
            f = float(frame)
        except OverflowError:  # a Python int beyond the float range
            f = math.inf
        if not math.isfinite(f) or not 0.0 <= f <= self.frames - 1:
            raise ValueError(
                f"frame: {describe(frame)} is outside the animation's frames [0, {self.frames - 1}] "
                f"({self.frames} frames at {self.fps:g} fps)"
            )
        return f

    def style_values(self, frame: float) -> dict[str, Any]:
        """Style parameter -> value at ``frame`` (a number, or a list for several components)."""
        out: dict[str, Any] = {}
        for t in self.tracks:
            part, _, param = t.parts
            if part != "style":
                continue
            v = t.value_at(frame)
            if t.integer:
                v = tuple(math.floor(x + 0.5) for x in v)
            out[param] = v[0] if len(v) == 1 else list(v)
        return out

    def check_scene(self, scene: Any, *, label: str = "tracks[{i}] {target!r}") -> None:
        """Raise ValueError unless every track names a part of ``scene`` that it can animate.

        ``label`` formats the start of a message (``i``: the track's index, ``n = i + 1``,
        ``target``)."""
        names = [o.name for o in scene.objects]
        for i, t in enumerate(self.tracks):
            part, which, attr = t.parts
            where = label.format(i=i, n=i + 1, target=t.target)
            if part == "light":
                if which >= len(scene.lights):
                    raise ValueError(
                        f"{where}: the scene has {len(scene.lights)} light(s), numbered from 0; "
                        f"light[{which}] does not exist"
                    )
                kind = scene.lights[which].kind
                if (attr, kind) in (("direction", "point"), ("position", "directional")):
                    raise ValueError(
                        f"{where}: light[{which}] is a {kind} light, which has no animated "
                        f"{attr}; animate its " + ("position" if kind == "point" else "direction")
                    )
            elif part == "object" and which not in names:
                raise ValueError(
                    f"{where}: no object named {which!r}; objects: {', '.join(map(repr, names))}"
                )
            elif part == "object" and names.count(which) > 1:
                raise ValueError(
                    f"{where}: {names.count(which)} objects are named {which!r}; give them "
                    "unique names"
                )
        for i, t in enumerate(self.tracks):
            part, name, _ = t.parts
            if part != "object":
                continue
            animated = {u.parts[2] for u in self.tracks if u.parts[:2] == ("object", name)}
            if animated != set(_PARTS["object"]):
                try:
                    _decompose(name, scene.objects[names.index(name)].transform)
                except ValueError as exc:
                    where = label.format(i=i, n=i + 1, target=t.target)
                    raise ValueError(f"{where}: {exc}") from None

    def still(self, scene: Any, frame: Any) -> Any:
        """The still scene of ``frame`` (see :meth:`refnpr.scenes.Scene.at`)."""
        f = self.check_frame(frame)
        by_part: dict[tuple, dict[str, tuple[float, ...]]] = {}
        for t in self.tracks:
            part, which, attr = t.parts
            by_part.setdefault((part, which), {})[attr] = t.value_at(f)
        changes: dict[str, Any] = {"animation": None}
        try:
            cam = by_part.get(("camera", None))
            if cam:
                c = scene.camera
                base = {k: getattr(c, k) for k in _PARTS["camera"]}
                base.update({k: (v[0] if _PARTS["camera"][k] == 1 else v) for k, v in cam.items()})
                changes["camera"] = Camera.look_at(**base)
            changes["lights"] = tuple(
                dataclasses.replace(lt, **by_part[("light", i)]) if ("light", i) in by_part else lt
                for i, lt in enumerate(scene.lights)
            )
            objects = list(scene.objects)
            for i, obj in enumerate(objects):
                vals = by_part.get(("object", obj.name))
                if vals:
                    objects[i] = dataclasses.replace(obj, transform=_object_transform(obj, vals))
            changes["objects"] = tuple(objects)
            styled = self.style_values(f)
            if styled:
                changes["style"] = {**scene.style, **styled}
            return dataclasses.replace(scene, **changes)
        except (TypeError, ValueError) as exc:
            raise type(exc)(f"frame {f:g}: {exc}") from exc


def _object_transform(obj: Any, vals: Mapping[str, tuple[float, ...]]) -> np.ndarray:
    if set(vals) == set(_PARTS["object"]):
        t, q, s = vals["translation"], vals["rotation"], vals["scale"]
    else:
        t, q, s = _decompose(obj.name, obj.transform)
        t, q, s = vals.get("translation", t), vals.get("rotation", q), vals.get("scale", s)
    s = np.asarray(s, dtype=np.float64)
    if np.any(s == 0.0):
        raise ValueError(f"object {obj.name!r}: scale {s.tolist()} has a zero component")
    m = np.eye(4)
    m[:3, :3] = quaternion_matrix(q) @ np.diag(s)  # T @ R @ S
    m[:3, 3] = t
    return m
