"""The ``[animation]`` table of a scene file -> :class:`~refnpr.scenes.animation.Animation`.

::

    [animation]
    frames = 48                      # required, >= 1 (frames 0 .. frames - 1)
    fps = 24                         # optional (default 24); time = frame / fps

    [[animation.track]]
    target = "camera.eye"            # see refnpr.scenes.animation for the targets
    interpolation = "catmull_rom"    # optional: linear (default) | catmull_rom; rotations: slerp
    keys = [
        { frame = 0, value = [6.0, 4.5, 8.0] },
        { time = 1.5, value = [0.0, 4.5, 9.0] },    # seconds: frame = time * fps
    ]

    [[animation.track]]
    target = 'object "teapot".rotation'
    keys = [
        { frame = 0, axis = [0, 1, 0], angle_deg = 0 },      # axis-angle ...
        { frame = 47, quaternion = [0, 0.7071068, 0, 0.7071068] },   # ... or [x, y, z, w]
    ]

A style track whose key values are all integers (``style.n``) rounds its interpolated value to
the nearest integer. Errors name the file, the table, the track and the key, like the rest of
the scene format.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Any

from .animation import Animation, Track
from .tracks import Keyframe, quaternion_from_axis_angle

__all__ = ["parse_animation"]

_ANIMATION_KEYS = ("frames", "fps", "track")
_TRACK_KEYS = ("target", "interpolation", "keys", "integer")
_KEY_KEYS = ("frame", "time", "value", "quaternion", "axis", "angle_deg")


def _is_int(v: Any) -> bool:
    return isinstance(v, int) and not isinstance(v, bool)


def _key(where: str, spec: Any, fps: float, rotation: bool) -> Keyframe:
    if not isinstance(spec, Mapping):
        raise ValueError(
            f"{where}: expected a table such as {{ frame = 0, value = [...] }}, got "
            f"{type(spec).__name__} {spec!r}"
        )
    for k in spec:
        if k not in _KEY_KEYS:
            raise ValueError(f"{where}: unknown key {k!r}; valid keys: {', '.join(_KEY_KEYS)}")
    if ("frame" in spec) == ("time" in spec):
        raise ValueError(
            f"{where}: give exactly one of `frame = N` or `time = SECONDS`, got "
            + ("both" if "frame" in spec else "neither")
        )
    if "frame" in spec:
        frame = spec["frame"]
    else:
        t = spec["time"]
        if isinstance(t, bool) or not isinstance(t, (int, float)):
            raise ValueError(f"{where}: time: expected seconds (a number), got {t!r}")
        frame = t * fps
    if rotation:
        has_q, has_aa = "quaternion" in spec, "axis" in spec or "angle_deg" in spec
        if "value" in spec or has_q == has_aa:
            raise ValueError(
                f"{where}: a rotation key needs `quaternion = [x, y, z, w]` or "
                "`axis = [x, y, z]` with `angle_deg = A`, exactly one of the two"
            )
        if has_q:
            value = spec["quaternion"]
        else:
            if "axis" not in spec or "angle_deg" not in spec:
                raise ValueError(f"{where}: an axis-angle key needs both `axis` and `angle_deg`")
            try:
                value = quaternion_from_axis_angle(spec["axis"], spec["angle_deg"])
            except (TypeError, ValueError) as exc:
                raise ValueError(f"{where}: {exc}") from None
    else:
        extra = [k for k in ("quaternion", "axis", "angle_deg") if k in spec]
        if extra:
            raise ValueError(
                f"{where}: {extra[0]!r} is for rotation tracks; this track takes `value`"
            )
        if "value" not in spec:
            raise ValueError(f"{where}: missing `value`")
        value = spec["value"]
    try:
        return Keyframe(frame, value)
    except (TypeError, ValueError) as exc:
        raise ValueError(f"{where}: {exc}") from None


def parse_animation(source: str, value: Any) -> Animation:
    """Build the :class:`Animation` of a scene file's ``[animation]`` table.

    Parameters
    ----------
    source : str
        The file name, the start of every message.
    value : mapping
        The parsed table.

    Raises
    ------
    ValueError
        ``"{source}: [animation]...: <key>: <what is wrong>"`` (the caller's ``SceneFileError``
        wraps it).
    """
    where = f"{source}: [animation]"
    if not isinstance(value, Mapping):
        raise ValueError(f"{where}: expected a table, got {type(value).__name__} {value!r}")
    for k in value:
        if k not in _ANIMATION_KEYS:
            raise ValueError(
                f"{where}: unknown key {k!r}; valid keys: {', '.join(_ANIMATION_KEYS)}"
            )
    if "frames" not in value:
        raise ValueError(f"{where}: missing key 'frames' (the number of frames, >= 1)")
    fps = value.get("fps", 24.0)
    try:
        Animation(value["frames"], fps)  # frames and fps checked before the keys use fps
    except (TypeError, ValueError) as exc:
        raise ValueError(f"{where}: {exc}") from None
    specs = value.get("track", [])
    if not isinstance(specs, list):
        raise ValueError(
            f"{where}: track: expected an array of tables ([[animation.track]]), got "
            f"{type(specs).__name__}"
        )
    tracks = []
    for i, spec in enumerate(specs):
        tw = f"{source}: [[animation.track]] #{i + 1}"
        if not isinstance(spec, Mapping):
            raise ValueError(f"{tw}: expected a table, got {type(spec).__name__} {spec!r}")
        for k in spec:
            if k not in _TRACK_KEYS:
                raise ValueError(f"{tw}: unknown key {k!r}; valid keys: {', '.join(_TRACK_KEYS)}")
        target = spec.get("target")
        if not isinstance(target, str):
            raise ValueError(
                f"{tw}: target: expected a string such as 'camera.eye', got {target!r}"
            )
        tw += f" {target!r}"
        keys = spec.get("keys")
        if not isinstance(keys, list) or not keys:
            raise ValueError(
                f"{tw}: keys: expected a non-empty array of tables "
                "[{ frame = 0, value = [...] }, ...], got "
                + ("nothing" if keys is None else repr(keys))
            )
        rotation = target.strip().endswith(".rotation") and target.strip().startswith("object")
        parsed = [_key(f"{tw}: keys[{j}]", k, float(fps), rotation) for j, k in enumerate(keys)]
        last = value["frames"] - 1
        for j, key in enumerate(parsed):
            if key.frame > last:
                raise ValueError(
                    f"{tw}: keys[{j}]: frame {key.frame:g} (time {key.frame / fps:g} s at "
                    f"{fps:g} fps) lies after the last frame {last} (frames = "
                    f"{value['frames']}); use frames = {math.ceil(key.frame) + 1} or an "
                    "earlier key"
                )
        integer = spec.get("integer")
        if integer is None:
            integer = target.strip().startswith("style.") and all(
                isinstance(k, Mapping)
                and (
                    _is_int(k.get("value"))
                    or (isinstance(k.get("value"), list) and all(map(_is_int, k["value"])))
                )
                for k in keys
            )
        try:
            tracks.append(Track(target, tuple(parsed), spec.get("interpolation"), integer))
        except (TypeError, ValueError) as exc:
            raise ValueError(f"{tw}: {exc}") from None
    try:
        return Animation(value["frames"], fps, tuple(tracks))
    except (TypeError, ValueError) as exc:
        raise ValueError(f"{where}: {exc}") from None
