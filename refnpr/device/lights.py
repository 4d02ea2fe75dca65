"""The scene's lights as a record, and the direction from a surface point towards a light."""

from __future__ import annotations

from typing import Any, NamedTuple

import numpy as np

from refnpr._jit import njit

from .vectors import towards, unit_scaled

__all__ = ["LIGHT_DIRECTIONAL", "LIGHT_POINT", "Lights", "lights_record", "light_dir"]

LIGHT_DIRECTIONAL = 0
LIGHT_POINT = 1


class Lights(NamedTuple):
    """The lights of a frame (numba record).

    Attributes
    ----------
    kind : (L,) int64, ``LIGHT_DIRECTIONAL`` or ``LIGHT_POINT``
    vec : (L, 3) float64, unit direction towards a directional light (``d / |d|`` of the
        scene's direction), position of a point light
    unit : (L, 3) float64, ``unit_scaled(vec)`` of directional lights (the normalization
        ``lighting.diffuse`` applies to L), zeros for point lights
    color : (L, 3) float64, linear RGB
    """

    kind: np.ndarray
    vec: np.ndarray
    unit: np.ndarray
    color: np.ndarray


def lights_record(lights: Any) -> Lights:
    """:class:`Lights` of a scene's ``lights`` (``refnpr.scenes.Light`` objects)."""
    kinds, vecs, units, colors = [], [], [], []
    for light in lights:
        colors.append(np.asarray(light.color, dtype=np.float64))
        if light.kind == "point":
            kinds.append(LIGHT_POINT)
            vecs.append(np.asarray(light.position, dtype=np.float64))
            units.append((0.0, 0.0, 0.0))
        else:
            d = np.asarray(light.direction, dtype=np.float64)
            d = d / np.linalg.norm(d)
            kinds.append(LIGHT_DIRECTIONAL)
            vecs.append(d)
            units.append(unit_scaled((float(d[0]), float(d[1]), float(d[2]))))
    n = len(kinds)

    def rows(values: list) -> np.ndarray:
        return np.ascontiguousarray(np.array(values, dtype=np.float64).reshape(n, 3))

    return Lights(np.array(kinds, dtype=np.int64), rows(vecs), rows(units), rows(colors))


@njit
def light_dir(point, v, p):
    """The unit direction from point ``p`` towards a light whose record entry is ``v`` (its
    row of ``Lights.vec``): ``towards(v, p)`` for a point light (zero at the light itself),
    ``v`` for a directional light. Kernels read ``kind`` and ``vec`` of a frame's
    :class:`Lights` once, outside their loops, and pass one light's values here."""
    if point:
        return towards(v, p)
    return v
