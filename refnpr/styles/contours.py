"""Contours (Veryovka 2002 sec. 5, Figure 7): silhouette, boundary and crease edges from mesh
adjacency, hidden parts removed against the depth buffer, drawn as anti-aliased lines of a given
width and composited over any style. Every paper's figures use them, so this is a reusable layer:
``{"name": "toon", "contours": {"width": 1.5}}`` wraps any style.

Edges are found on the mesh welded by position (uv seams with duplicated vertices are not
boundaries). Per frame, a face is front-facing when its geometric normal points towards the eye;
a *silhouette* edge joins a front- and a back-facing face, a *boundary* edge has one face, and a
*crease* edge has a dihedral angle above ``crease_angle`` degrees. A point of an edge is visible
when its eye depth is not behind the farthest surface among the 3x3 depth samples around it (a
silhouette borders a farther surface or the background); ``depth_tolerance`` is relative.
"""

from __future__ import annotations

import copy
import threading
import weakref
from dataclasses import dataclass
from typing import Any

import numpy as np

from . import _kernels as K
from ._declare import Param, Params, rgb_param
from ._names import warn_deprecated
from .base import ShadeContext, Style, nested_style, register

__all__ = ["EdgeTable", "ContourLayer", "CONTOURS", "Contoured", "edge_table"]


@dataclass(frozen=True, eq=False)
class EdgeTable:
    """Unique edges of a mesh welded by position, with their adjacent faces.

    Attributes
    ----------
    edges : (E, 2) int64
        Vertex indices (original indexing, one representative per welded position).
    faces : (E, 2) int64
        The two faces sharing each edge; -1 in the second column for boundary edges.
    dihedral_deg : (E,) float64
        Angle between the two face normals (0 for flat, 180 for a fold; 0 on boundaries).
    """

    edges: np.ndarray
    faces: np.ndarray
    dihedral_deg: np.ndarray


def edge_table(positions: np.ndarray, faces: np.ndarray) -> EdgeTable:
    """Build the :class:`EdgeTable` of a mesh ``positions (N, 3)``, ``faces (M, 3)``.

    Edges shared by more than two faces (non-manifold) keep their first two faces.
    """
    _, weld, inverse = np.unique(positions, axis=0, return_index=True, return_inverse=True)
    inverse = inverse.reshape(-1)
    wf = inverse[faces]
    e = np.concatenate([wf[:, [0, 1]], wf[:, [1, 2]], wf[:, [2, 0]]])
    face_of = np.tile(np.arange(faces.shape[0]), 3)
    keep = e[:, 0] != e[:, 1]  # collapsed edges of degenerate triangles
    e, face_of = e[keep], face_of[keep]
    key = np.sort(e, axis=1)
    order = np.lexsort((face_of, key[:, 1], key[:, 0]))
    key, face_of = key[order], face_of[order]
    start = np.concatenate([[True], np.any(key[1:] != key[:-1], axis=1)])
    idx = np.flatnonzero(start)
    counts = np.diff(np.concatenate([idx, [key.shape[0]]]))
    f0 = face_of[idx]
    f1 = np.where(counts >= 2, face_of[np.minimum(idx + 1, key.shape[0] - 1)], -1)
    edges = weld[key[idx]]
    normals = _face_normals(positions, faces)
    cosang = np.where(f1 >= 0, np.sum(normals[f0] * normals[np.maximum(f1, 0)], axis=1), 1.0)
    dihedral = np.degrees(np.arccos(np.clip(cosang, -1.0, 1.0)))
    return EdgeTable(edges.astype(np.int64), np.stack([f0, f1], axis=1), dihedral)


def _face_normals(positions: np.ndarray, faces: np.ndarray) -> np.ndarray:
    p = positions[faces]
    n = np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0])
    length = np.linalg.norm(n, axis=1, keepdims=True)
    return np.divide(n, length, out=np.zeros_like(n), where=length > 0)


@dataclass(frozen=True, eq=False)
class _MeshEdges:
    """What the contour layer needs of a mesh besides the camera: its edge table, unit face
    normals (M, 3) and face centroids (M, 3), float64, read-only."""

    table: EdgeTable
    normals: np.ndarray
    centroid: np.ndarray


_MESH_EDGES: weakref.WeakKeyDictionary = weakref.WeakKeyDictionary()
_MESH_EDGES_LOCK = threading.Lock()


def _mesh_edges(mesh: Any) -> _MeshEdges:
    """The :class:`_MeshEdges` of an (immutable) Mesh, built once per mesh object and kept as
    long as the mesh lives: a world mesh is memoized by its scene object, so the frames of a
    still scene (a RenderContext, a camera path) build the table once, not per frame (the
    welding, sorting and normals took ~16 ms of a 1080p halftone frame)."""
    with _MESH_EDGES_LOCK:
        got = _MESH_EDGES.get(mesh)
    if got is None:
        normals = _face_normals(mesh.positions, mesh.faces)
        centroid = mesh.positions[mesh.faces].mean(axis=1)
        for arr in (normals, centroid):
            arr.setflags(write=False)
        got = _MeshEdges(edge_table(mesh.positions, mesh.faces), normals, centroid)
        with _MESH_EDGES_LOCK:
            got = _MESH_EDGES.setdefault(mesh, got)
    return got


#: Widest line in pixels (wider lines cover everything and overflow the kernel's box).
_MAX_WIDTH = 256.0


#: The contour layer's parameters, each declared once (``refnpr styles contoured`` lists the
#: wrapper's; ``docs/paper-notes.md`` and the kit describe the layer).
CONTOURS = Params(
    "contours",
    Param("width", 1.5, "line width", lo=0.0, lo_open=True, hi=_MAX_WIDTH, unit="px"),
    rgb_param(
        "ink",
        (0.0, 0.0, 0.0),
        "linear RGB of the lines (the name every style uses for its line colour; color is its "
        "deprecated alias)",
    ),
    Param("silhouettes", True, "draw edges between a front- and a back-facing face", kind="bool"),
    Param("boundaries", True, "draw edges with one face", kind="bool"),
    Param(
        "crease_angle",
        None,
        "draw edges whose dihedral angle exceeds this (none: no creases)",
        lo=0.0,
        lo_open=True,
        hi=180.0,
        unit="degrees",
        optional=True,
    ),
    Param("depth_tolerance", 0.01, "relative depth slack of the visibility test", lo=0.0),
    renamed={"color": "ink"},
    module=__name__,
    name="CONTOURS",
    where="contours",
)


class ContourLayer:
    """Parameters of the contour layer (:data:`CONTOURS`: width, ink, silhouettes,
    boundaries, crease_angle, depth_tolerance), as attributes."""

    def __init__(self, **params: Any) -> None:
        self.p = CONTOURS.validate(params)

    def __getattr__(self, name: str) -> Any:
        if name in CONTOURS.by_name:
            return self.p[name]
        raise AttributeError(name)

    def params(self) -> dict[str, Any]:
        """``{name: value}`` of every parameter (tuples as lists; None kept)."""
        return self.p.as_dict(keep_none=True)

    def __eq__(self, other: object) -> bool:
        return isinstance(other, ContourLayer) and self.params() == other.params()

    def __hash__(self) -> int:
        return hash(repr(self))

    def __repr__(self) -> str:
        return "ContourLayer(" + ", ".join(f"{k}={v!r}" for k, v in self.params().items()) + ")"

    @property
    def color(self) -> tuple[float, float, float]:
        """Deprecated name of :attr:`ink`."""
        warn_deprecated(
            "contours: attribute 'color' is deprecated, use 'ink' (one name across styles)"
        )
        return self.ink

    def selected_edges(self, mesh: _MeshEdges, eye: np.ndarray) -> np.ndarray:
        """(K, 2) vertex indices of the silhouette/boundary/crease edges of ``mesh`` seen from
        ``eye`` (3,)."""
        front = np.sum(mesh.normals * (eye - mesh.centroid), axis=1) > 0.0
        table = mesh.table
        f0, f1 = table.faces[:, 0], table.faces[:, 1]
        boundary = f1 < 0
        sel = np.zeros(len(f0), dtype=bool)
        if self.silhouettes:
            sel |= ~boundary & (front[f0] != front[np.maximum(f1, 0)])
        if self.boundaries:
            sel |= boundary
        if self.crease_angle is not None:
            sel |= ~boundary & (table.dihedral_deg > self.crease_angle)
        return table.edges[sel]

    def coverage(self, ctx: ShadeContext) -> np.ndarray:
        """(nH, nW) float64 line coverage in [0, 1] on the sample grid (needs ``depth``)."""
        gb = ctx.gb
        eye = np.asarray(ctx.scene.camera.eye, dtype=np.float64)
        depth = np.ascontiguousarray(gb["depth"], dtype=np.float64)
        cov = np.zeros(depth.shape)
        vp = np.ascontiguousarray(gb.view_projection, dtype=np.float64)
        line = (0.5 * self.width * gb.n, self.depth_tolerance, 0.5)  # radius, slack, piece
        for mesh in ctx.scene.world_meshes():
            edges = self.selected_edges(_mesh_edges(mesh), eye)
            if edges.size == 0:
                continue
            positions = np.ascontiguousarray(mesh.positions, dtype=np.float64)
            K.draw_edges(positions, vp, np.ascontiguousarray(edges), depth, line, cov)
        return cov


@register
class Contoured(Style):
    """Any style with the contour layer composited over it.

    Parameters
    ----------
    base : Style, str or dict
        The style underneath.
    contours : ContourLayer, dict or bool
        Layer parameters (True: defaults).
    """

    name = "contoured"
    description = "any style (base=...) with silhouette/crease contours drawn over it"

    def __init__(self, *, base: Any = "toon", contours: Any = True) -> None:
        self.base = nested_style("base", base)
        if contours is True:
            contours = ContourLayer()
        elif isinstance(contours, dict):
            try:
                contours = ContourLayer(**contours)
            except (TypeError, ValueError) as exc:  # name the key as the user wrote it
                msg = str(exc)
                raise type(exc)(msg if msg.startswith("contours") else f"contours.{msg}") from None
        elif not isinstance(contours, ContourLayer):
            raise TypeError(f"contours: expected a ContourLayer, a table or True, got {contours!r}")
        self.layer = contours
        self._params = {
            "base": self.base.params() | {"name": self.base.name},
            "contours": contours.params(),
        }

    def requires(self, scene: Any) -> frozenset[str]:
        return frozenset(self.base.requires(scene) | {"depth"})

    def raster_options(self, scene: Any) -> dict[str, Any]:
        return self.base.raster_options(scene)

    def _over(self, ctx: ShadeContext, rgba: np.ndarray) -> np.ndarray:
        """The contour layer composited over the base style's per-sample RGBA (straight-alpha
        "over", float64 arithmetic, float32 result; one numba pass, in place on the base's own
        fresh float32 array, or on a copy when it returned a view or another dtype)."""
        cov = np.ascontiguousarray(self.layer.coverage(ctx), dtype=np.float64)
        out = np.require(rgba, dtype=np.float32, requirements=("C", "W", "O"))
        K.ink_over(out, cov, np.asarray(self.layer.ink, dtype=np.float64))
        return out

    def shade(self, ctx: ShadeContext) -> np.ndarray:
        return self._over(ctx, self.base.shade(ctx))

    # the sequence protocol goes through to the base style (X-Toon flow, TAMISS state)
    def for_frame(self, scene: Any, prev_scene: Any | None) -> Style:
        base = self.base.for_frame(scene, prev_scene)
        if base is self.base:
            return self
        new = copy.copy(self)
        new.base = base
        new._params = {**self._params, "base": base.params() | {"name": base.name}}
        return new

    def initial_state(self) -> Any:
        return self.base.initial_state()

    def state_frames(self) -> int | None:
        return self.base.state_frames()

    def shade_frame(self, ctx: ShadeContext, state: Any) -> tuple[np.ndarray, Any]:
        rgba, state = self.base.shade_frame(ctx, state)
        return self._over(ctx, rgba), state
