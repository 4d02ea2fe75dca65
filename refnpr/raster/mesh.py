"""Triangle meshes as the rasterizer sees them: validated float64 arrays in one space."""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping
from dataclasses import dataclass, field

import numpy as np

from .gbuffer import BUILTIN_CHANNELS

__all__ = ["Mesh", "RESERVED_NAMES", "MAX_COORDINATE"]

#: Names that are G-buffer channels and therefore cannot be vertex attribute names.
RESERVED_NAMES = frozenset(BUILTIN_CHANNELS)

#: Largest accepted ``|coordinate|`` of a vertex position (absolute, in world units).
#:
#: Why a bound, and why this one: the rasterizer clips in float64 homogeneous space against a
#: guard band of G = 16 NDC units. An edge whose two endpoints lie far outside the view is cut
#: at ``a + s (b - a)``, which cancels catastrophically: the clipped corner is off by about
#: ``2**-53 * |clip|`` in clip units, i.e. ``2**-53 * f |p_eye| / w`` in NDC (f = cot(fov_y/2),
#: w >= near after clipping). Once that exceeds the guard margin G - 1 = 15, clipped corners land
#: inside the view and whole quadrants of a screen-covering triangle vanish (measured: the
#: failure sets in at |NDC| ~ 1.4e17 = 15 * 2**53 for any depth). For the default camera
#: (near = 0.1) and fields of view down to 30 degrees (f <= 3.73), with the eye itself within the
#: limit, ``|p_eye| <= sqrt(3) * 2 * MAX_COORDINATE`` keeps |NDC| below ~1.3e17: geometry is then
#: never dropped. The bound is absolute because a Mesh has no camera; a camera-relative check
#: (|clip| / near per view, which also governs sub-pixel exactness) belongs to the rasterizer.
MAX_COORDINATE = 1e15


def coordinate_limit_message(subject: str, pos: np.ndarray) -> str | None:
    """The refusal of positions beyond :data:`MAX_COORDINATE` (see there for the derivation),
    in the one wording Mesh and the mesh-file checks share; ``None`` when every coordinate is
    within the limit. ``subject`` names what holds the positions (``"mesh 'ball'"``)."""
    mag = np.abs(pos)
    big = float(mag.max()) if mag.size else 0.0
    if not big > MAX_COORDINATE:
        return None
    row = int(np.argmax(mag.max(axis=1)))
    return (
        f"{subject} has a vertex coordinate of magnitude {big:.3g} (vertex {row}: "
        f"{pos[row].tolist()}), above the limit {MAX_COORDINATE:.0e} beyond which float64 "
        "clipping loses geometry; rescale the model (e.g. to metres or kilometres) so that every "
        f"|coordinate| is <= {MAX_COORDINATE:.0e}"
    )


def _check_magnitude(pos: np.ndarray, mesh_name: str, prefix: str) -> None:
    """Refuse positions beyond :data:`MAX_COORDINATE`."""
    msg = coordinate_limit_message(f"mesh {mesh_name!r}", pos)
    if msg is not None:
        raise ValueError(f"{prefix}: {msg}")


def _as_float_array(name: str, value, ncols: int | None, nverts: int | None) -> np.ndarray:
    try:
        arr = np.asarray(value, dtype=np.float64)
    except (TypeError, ValueError) as exc:
        raise TypeError(
            f"{name}: expected a numeric array, got {type(value).__name__}; "
            "pass a numpy array of floats"
        ) from exc
    if ncols is not None:
        if arr.ndim != 2 or arr.shape[1] != ncols:
            raise ValueError(
                f"{name}: expected shape (N, {ncols}), got {arr.shape}; "
                f"reshape to one row of {ncols} values per vertex"
            )
    if nverts is not None and arr.shape[0] != nverts:
        raise ValueError(
            f"{name}: expected {nverts} rows (one per vertex), got {arr.shape[0]}; "
            "give one value per vertex of `positions`"
        )
    if not np.all(np.isfinite(arr)):
        bad = tuple(int(i) for i in np.argwhere(~np.isfinite(arr))[0])
        raise ValueError(
            f"{name}: contains NaN or inf (first at index {bad}, value {arr[bad]}); "
            "remove or repair non-finite vertices"
        )
    return arr


@dataclass(frozen=True, eq=False)
class Mesh:
    """An indexed triangle mesh with optional per-vertex normals, uv and named attributes.

    Parameters
    ----------
    positions : (N, 3) float64
        Vertex positions.
    faces : (M, 3) int64
        Zero-based vertex indices, counter-clockwise seen from outside.
    normals : (N, 3) float64, optional
        Per-vertex normals (need not be unit length; they are renormalized per pixel).
    uv : (N, 2) float64, optional
        Texture coordinates.
    attributes : mapping of str to (N,) or (N, C) float64, optional
        Extra per-vertex attributes, interpolated perspective-correctly on request by name.
    name : str
        Label used in error messages and scene listings.

    All arrays are validated on construction (shapes, finite values, face indices in range) and
    stored as read-only contiguous float64/int64 copies.
    """

    positions: np.ndarray
    faces: np.ndarray
    normals: np.ndarray | None = None
    uv: np.ndarray | None = None
    attributes: Mapping[str, np.ndarray] = field(default_factory=dict)
    name: str = "mesh"

    def __post_init__(self) -> None:
        pos = _as_float_array("positions", self.positions, 3, None)
        if pos.shape[0] == 0:
            raise ValueError(
                f"positions: mesh {self.name!r} is empty (0 vertices); give at least 3 vertices"
            )
        _check_magnitude(pos, self.name, "positions")
        try:
            faces_in = np.asarray(self.faces)
        except (TypeError, ValueError) as exc:
            raise TypeError(
                f"faces: expected an integer array, got {type(self.faces).__name__}"
            ) from exc
        if faces_in.ndim != 2 or faces_in.shape[1] != 3:
            raise ValueError(
                f"faces: expected shape (M, 3), got {faces_in.shape}; "
                "triangulate polygons first (trimesh does this on load)"
            )
        if faces_in.shape[0] == 0:
            raise ValueError(f"faces: mesh {self.name!r} has no triangles; give at least one face")
        if faces_in.dtype.kind == "b" or faces_in.dtype.kind not in "iuf":
            raise TypeError(
                f"faces: expected integer indices, got dtype {faces_in.dtype}; "
                "pass an integer array of shape (M, 3)"
            )
        if faces_in.dtype.kind == "f":
            whole = np.isfinite(faces_in) & (faces_in == np.round(faces_in))
            if not np.all(whole):
                bad = tuple(int(i) for i in np.argwhere(~whole)[0])
                raise TypeError(
                    f"faces: expected integer indices, got dtype {faces_in.dtype} with the "
                    f"non-integer value {faces_in[bad]} at index {bad}; pass integer indices"
                )
            if np.abs(faces_in).max() >= 2.0**62:
                raise ValueError(
                    f"faces: index {np.abs(faces_in).max():.3g} is out of range for "
                    f"{pos.shape[0]} vertices; indices are zero-based and must be < len(positions)"
                )
            faces_in = faces_in.astype(np.int64)
        elif faces_in.dtype.kind == "u" and faces_in.max() > np.iinfo(np.int64).max:
            raise ValueError(
                f"faces: index {int(faces_in.max())} is out of range for {pos.shape[0]} vertices; "
                "indices are zero-based and must be < len(positions)"
            )
        faces = np.ascontiguousarray(faces_in, dtype=np.int64)
        lo, hi = int(faces.min()), int(faces.max())
        if lo < 0 or hi >= pos.shape[0]:
            raise ValueError(
                f"faces: index out of range (min {lo}, max {hi}) for {pos.shape[0]} vertices; "
                "indices are zero-based and must be < len(positions)"
            )
        nv = pos.shape[0]
        normals = None if self.normals is None else _as_float_array("normals", self.normals, 3, nv)
        uv = None if self.uv is None else _as_float_array("uv", self.uv, 2, nv)
        attrs: dict[str, np.ndarray] = {}
        for key, val in dict(self.attributes).items():
            if not isinstance(key, str) or not key.isidentifier():
                raise ValueError(f"attributes: name {key!r} must be a Python identifier")
            if key in RESERVED_NAMES:
                raise ValueError(
                    f"attributes: name {key!r} is a G-buffer channel name; rename the attribute "
                    f"(reserved: {sorted(RESERVED_NAMES)})"
                )
            arr = _as_float_array(f"attributes[{key!r}]", val, None, nv)
            if arr.ndim not in (1, 2):
                raise ValueError(
                    f"attributes[{key!r}]: expected shape (N,) or (N, C), got {arr.shape}"
                )
            attrs[key] = arr
        for arr in (pos, faces, normals, uv, *attrs.values()):
            if arr is not None:
                arr.setflags(write=False)
        object.__setattr__(self, "positions", np.ascontiguousarray(pos))
        object.__setattr__(self, "faces", faces)
        object.__setattr__(self, "normals", normals)
        object.__setattr__(self, "uv", uv)
        object.__setattr__(self, "attributes", attrs)

    @property
    def n_vertices(self) -> int:
        return int(self.positions.shape[0])

    @property
    def n_faces(self) -> int:
        return int(self.faces.shape[0])

    def transformed(self, matrix: np.ndarray) -> Mesh:
        """Return this mesh with positions mapped by a 4x4 affine ``matrix`` (normals by its
        inverse transpose, renormalized). uv and attributes are carried unchanged.

        Parameters
        ----------
        matrix : (4, 4) float64
            Object-to-world transform; the last row must be (0, 0, 0, 1).
        """
        m = np.asarray(matrix, dtype=np.float64)
        if m.shape != (4, 4) or not np.all(np.isfinite(m)):
            raise ValueError(f"matrix: expected a finite (4, 4) array, got shape {m.shape}")
        if not np.allclose(m[3], [0.0, 0.0, 0.0, 1.0]):
            raise ValueError(
                f"matrix: last row must be (0, 0, 0, 1) for an affine transform, got {m[3]}"
            )
        lin = m[:3, :3]
        with np.errstate(over="ignore", invalid="ignore"):  # overflow is reported below
            det = np.linalg.det(lin)
            pos = self.positions @ lin.T + m[:3, 3]
        if abs(det) < 1e-300:
            raise ValueError(
                "matrix: the 3x3 part is singular; a mesh transform must be invertible"
            )
        if not np.all(np.isfinite(pos)):
            raise ValueError(
                f"matrix: transforming mesh {self.name!r} gives non-finite positions (largest "
                f"|matrix entry| {float(np.abs(m).max()):.3g}); use a smaller scale or translation"
            )
        _check_magnitude(pos, self.name, "matrix")
        normals = None
        if self.normals is not None:
            nrm = self.normals @ np.linalg.inv(lin)
            length = np.linalg.norm(nrm, axis=1, keepdims=True)
            normals = np.divide(nrm, length, out=np.zeros_like(nrm), where=length > 0)
        faces = self.faces
        if det < 0:  # a mirror flips winding; keep faces counter-clockwise
            faces = faces[:, ::-1]
        return Mesh(pos, faces, normals, self.uv, self.attributes, self.name)

    def with_(self, **changes) -> Mesh:
        """Copy with some fields replaced (``mesh.with_(uv=...)``), validated as a new Mesh."""
        return dataclasses.replace(self, **changes)
