"""Abstracted normal fields for X-Toon shape detail (Barla et al. 2006, sec. 4, Fig. 5).

The paper precomputes one abstracted normal per mesh vertex, once. :class:`AbstractedNormals` is
that precomputed value: build it once with :func:`abstract_normals` and pass it back to the style
(``XToonStyle(shape=an)``) to skip the computation on every frame.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from refnpr.formulas import xtoon

__all__ = ["SHAPES", "AbstractedNormals", "abstract_normals", "unit_rows"]

#: Abstracted shapes of sec. 4 -> formula-layer builder ``f(positions, faces, normals, **kw)``.
SHAPES: dict[str, Callable[..., np.ndarray]] = {
    "smoothed": xtoon.smoothed_normals,
    "ellipsoid": xtoon.ellipsoid_normals,
    "cylinder": xtoon.cylinder_normals,
    "sphere": xtoon.sphere_normals,
}


def unit_rows(v: np.ndarray) -> np.ndarray:
    """Rows of ``v (..., 3)`` normalized; zero rows stay zero. float64."""
    v = np.asarray(v, dtype=np.float64)
    length = np.linalg.norm(v, axis=-1, keepdims=True)
    return np.divide(v, length, out=np.zeros_like(v), where=length > 0)


@dataclass(frozen=True, eq=False)
class AbstractedNormals:
    """Per-vertex normals of an abstracted shape for each world mesh of a scene.

    Attributes
    ----------
    shape : str
        "smoothed", "ellipsoid", "cylinder", "sphere" or "custom".
    normals : tuple of ((N_i, 3) float64 unit, or None)
        One entry per world mesh, in scene order; None: that mesh keeps its own normals.
    n_vertices : tuple of int
        Vertex count of each mesh it was built for (checked when used).
    """

    shape: str
    normals: tuple[np.ndarray | None, ...]
    n_vertices: tuple[int, ...]

    def for_meshes(self, meshes: Sequence[Any]) -> list[np.ndarray | None]:
        """The normals for ``meshes`` (the scene's world meshes), after checking they match."""
        counts = tuple(int(m.n_vertices) for m in meshes)
        if counts != self.n_vertices:
            raise ValueError(
                f"shape: these AbstractedNormals were built for meshes with {self.n_vertices} "
                f"vertices, but the scene has {counts}; rebuild them with "
                "abstract_normals(scene, ...) for this scene"
            )
        return list(self.normals)


def abstract_normals(
    scene: Any,
    shape: str | Callable[[Any], np.ndarray] = "sphere",
    *,
    objects: Sequence[str] | None = None,
    frame: str = "pca",
    iterations: int = 10,
) -> AbstractedNormals:
    """Precompute the abstracted normals of every world mesh of ``scene`` (X-Toon sec. 4).

    Parameters
    ----------
    scene : refnpr.scenes.Scene
    shape : {"smoothed", "ellipsoid", "cylinder", "sphere"} or callable
        A callable gets each world :class:`~refnpr.raster.Mesh` and returns ``(N, 3)`` normals.
    objects : list of str, optional
        Names of the objects to abstract (default all); the others keep their own normals.
    frame : {"pca", "aabb"}
        Box frame of the ellipsoid, cylinder and sphere (see ``refnpr.formulas.xtoon``).
    iterations : int
        Smoothing iterations of the "smoothed" shape.

    Returns
    -------
    AbstractedNormals
    """
    meshes = scene.world_meshes()
    names = [o.name for o in scene.objects]
    unknown = sorted(set(objects or ()) - set(names))
    if unknown:
        raise ValueError(
            f"shape_objects: unknown object names {unknown}; the scene's objects are {names}"
        )
    chosen = [objects is None or n in objects for n in names]
    out: list[np.ndarray | None] = []
    for mesh, use in zip(meshes, chosen, strict=True):
        if not use:
            out.append(None)
            continue
        if mesh.normals is None:
            raise ValueError(
                f"shape: mesh {mesh.name!r} has no vertex normals; shape abstraction blends "
                "them with the abstracted shape's normals, so give the mesh normals"
            )
        if callable(shape):
            n = np.asarray(shape(mesh), dtype=np.float64)
            if n.shape != (mesh.n_vertices, 3) or not np.all(np.isfinite(n)):
                raise ValueError(
                    f"shape: the callable returned {n.shape} for mesh {mesh.name!r}; expected "
                    f"finite ({mesh.n_vertices}, 3) normals"
                )
        else:
            kwargs: dict[str, Any] = (
                {"iterations": iterations} if shape == "smoothed" else {"frame": frame}
            )
            n = SHAPES[shape](mesh.positions, mesh.faces, mesh.normals, **kwargs)
        out.append(unit_rows(n))
    label = shape if isinstance(shape, str) else "custom"
    return AbstractedNormals(label, tuple(out), tuple(int(m.n_vertices) for m in meshes))
