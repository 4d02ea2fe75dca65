"""Keyframe tracks: interpolation of vectors (linear, Catmull-Rom) and rotations (slerp of unit
quaternions ``[x, y, z, w]``, glTF order). A track holds its first value before its first key and
its last after its last key; the interpolations are defined in docs/animation.md.
"""

from __future__ import annotations

import bisect
import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from ._params import check_real, check_vec, describe

__all__ = [
    "INTERPOLATIONS",
    "Keyframe",
    "quaternion_from_axis_angle",
    "quaternion_matrix",
    "quaternion_from_matrix",
    "interpolate",
    "slerp",
]

#: Interpolation names by value kind.
INTERPOLATIONS = {"vector": ("linear", "catmull_rom"), "rotation": ("slerp",)}

#: A quaternion key farther than this from unit length is an error (not silently normalized).
UNIT_TOLERANCE = 1e-6


@dataclass(frozen=True)
class Keyframe:
    """One key of a track.

    Attributes
    ----------
    frame : float
        Where the key sits (frames; ``time * fps`` for keys given in seconds), >= 0.
    value : tuple of float
        The value at that frame (a quaternion ``(x, y, z, w)`` for rotations).
    """

    frame: float
    value: tuple[float, ...]

    def __post_init__(self) -> None:
        object.__setattr__(self, "frame", check_real("frame", self.frame, nonnegative=True))
        value = self.value
        if isinstance(value, (int, float, np.number)) and not isinstance(value, bool):
            value = (value,)
        if isinstance(value, (str, bytes)) or not hasattr(value, "__len__") or not len(value):
            raise TypeError(f"value: expected a number or a list of numbers, got {describe(value)}")
        object.__setattr__(self, "value", check_vec("value", value, len(value)))


def quaternion_from_axis_angle(axis: Sequence[float], angle_deg: float) -> tuple[float, ...]:
    """Unit quaternion ``(x, y, z, w)`` of a rotation by ``angle_deg`` about ``axis``.

    Counter-clockwise looking down the axis (right-handed), as ``transform_matrix``'s rotations.

    Raises
    ------
    ValueError
        If ``axis`` is the zero vector or not 3 finite numbers.
    """
    a = np.array(check_vec("axis", axis, 3), dtype=np.float64)
    length = float(np.linalg.norm(a))
    if length == 0.0:
        raise ValueError("axis: must not be the zero vector; give the rotation axis [x, y, z]")
    half = math.radians(check_real("angle_deg", angle_deg)) / 2.0
    s = math.sin(half) / length
    return (a[0] * s, a[1] * s, a[2] * s, math.cos(half))


def check_unit_quaternion(name: str, q) -> tuple[float, ...]:
    """``q`` as 4 floats of unit length (to :data:`UNIT_TOLERANCE`), else a ValueError."""
    q = check_vec(name, q, 4)
    norm = math.sqrt(sum(x * x for x in q))
    if abs(norm - 1.0) > UNIT_TOLERANCE:
        raise ValueError(
            f"{name}: quaternion {list(q)} has length {norm:.9g}, expected a unit quaternion "
            "[x, y, z, w]; normalize it (divide by its length) or give axis and angle_deg"
        )
    return q


def quaternion_matrix(q: Sequence[float]) -> np.ndarray:
    """(3, 3) float64 rotation matrix of the unit quaternion ``(x, y, z, w)``."""
    x, y, z, w = (float(c) for c in q)
    return np.array(
        [
            [1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
            [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
            [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)],
        ]
    )


def quaternion_from_matrix(r: np.ndarray) -> tuple[float, ...]:
    """Unit quaternion ``(x, y, z, w)`` of a (3, 3) rotation matrix (Shepperd's method)."""
    r = np.asarray(r, dtype=np.float64)
    tr = r[0, 0] + r[1, 1] + r[2, 2]
    if tr > 0.0:
        s = 2.0 * math.sqrt(tr + 1.0)
        q = ((r[2, 1] - r[1, 2]) / s, (r[0, 2] - r[2, 0]) / s, (r[1, 0] - r[0, 1]) / s, s / 4)
    else:
        i = int(np.argmax([r[0, 0], r[1, 1], r[2, 2]]))
        j, k = (i + 1) % 3, (i + 2) % 3
        s = 2.0 * math.sqrt(max(1.0 + r[i, i] - r[j, j] - r[k, k], 0.0))
        v = [0.0, 0.0, 0.0]
        v[i] = s / 4
        v[j] = (r[j, i] + r[i, j]) / s
        v[k] = (r[k, i] + r[i, k]) / s
        q = (v[0], v[1], v[2], (r[k, j] - r[j, k]) / s)
    n = math.sqrt(sum(c * c for c in q))
    return tuple(c / n for c in q)


def slerp(q0: Sequence[float], q1: Sequence[float], u: float) -> tuple[float, ...]:
    """Spherical linear interpolation of unit quaternions along the shorter arc.

    ``slerp(q0, q1, 0) == q0``; at ``u = 1`` it is ``q1`` or ``-q1`` (the same rotation).
    Renormalized, so the result is unit length to rounding.
    """
    a = np.asarray(q0, dtype=np.float64)
    b = np.asarray(q1, dtype=np.float64)
    if float(a @ b) < 0.0:
        b = -b
    # the angle from the norm of the difference: acos(d) loses half the digits near d = 1
    half_chord = float(np.linalg.norm(b - a)) / 2.0
    theta = 2.0 * math.asin(min(half_chord, 1.0))  # angle between a and b on the 4-sphere
    if theta < 1e-6:  # nearly equal: lerp, whose error O(theta^3) is below rounding here
        q = a + u * (b - a)
    else:
        s = math.sin(theta)
        q = (math.sin((1.0 - u) * theta) / s) * a + (math.sin(u * theta) / s) * b
    q = q / np.linalg.norm(q)
    return tuple(float(c) for c in q)


def interpolate(keys: Sequence[Keyframe], frame: float, interpolation: str) -> tuple[float, ...]:
    """The value of a track with ``keys`` (frames strictly increasing) at ``frame``.

    Parameters
    ----------
    keys : sequence of Keyframe
        At least one; values all of one length.
    frame : float
    interpolation : {"linear", "catmull_rom", "slerp"}

    Returns
    -------
    tuple of float
        Held constant outside the keys' range; exactly the key's value at a key's frame.
    """
    frames = [k.frame for k in keys]
    if frame <= frames[0]:
        return keys[0].value
    if frame >= frames[-1]:
        return keys[-1].value
    i = bisect.bisect_right(frames, frame) - 1  # frames[i] <= frame < frames[i + 1]
    if frame == frames[i]:
        return keys[i].value
    f0, f1 = frames[i], frames[i + 1]
    u = (frame - f0) / (f1 - f0)
    values = np.asarray([k.value for k in keys], dtype=np.float64)
    p0, p1 = values[i], values[i + 1]
    if interpolation == "slerp":
        return slerp(p0, p1, u)
    if interpolation == "linear":
        return tuple(float(c) for c in (1.0 - u) * p0 + u * p1)
    if interpolation != "catmull_rom":
        raise ValueError(f"interpolation: unknown interpolation {interpolation!r}")

    def tangent(j: int) -> np.ndarray:  # central difference per frame, one-sided at the ends
        lo, hi = max(j - 1, 0), min(j + 1, len(keys) - 1)
        return (values[hi] - values[lo]) / (frames[hi] - frames[lo])

    h = f1 - f0
    m0, m1 = tangent(i) * h, tangent(i + 1) * h
    u2, u3 = u * u, u * u * u
    h00 = 2 * u3 - 3 * u2 + 1  # cubic Hermite basis
    h10 = u3 - 2 * u2 + u
    h01 = -2 * u3 + 3 * u2
    h11 = u3 - u2
    return tuple(float(c) for c in h00 * p0 + h10 * m0 + h01 * p1 + h11 * m1)
