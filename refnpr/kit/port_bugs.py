"""The bugs GPU ports of refnpr's styles really make, rendered with refnpr itself (for ``refnpr
kit mutants``, :mod:`refnpr.kit.mutants`).

Each :class:`Bug` is emulated as faithfully as a port would have it:

* **output** bugs transform refnpr's correct image or its shaded samples (sRGB applied twice
  or never, gamma 2.2, premultiplied colour composited as straight, rows upside down, the
  resolve done on sRGB values);
* **input** bugs change what refnpr is given: the projection (sample positions off by half a
  sample-grid pixel), the meshes' texture coordinates (v flipped), the lights (direction
  negated);
* **pipeline** bugs change the G-buffer a style shades, computed here from the triangles
  themselves (2 x 2 quad finite differences instead of analytic derivatives, d/dy of a y-up
  render target, normals not renormalized, coverage of unsnapped vertices, ``<=`` in the
  depth test) or a style parameter (the mip LOD bias).

:class:`refnpr.kit.mutant_render.CaseRenderer` renders a golden case under each bug; this
module holds what the bugs are and the pure transforms and geometry they are rendered with.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from ..device.sampling import gl_lod as _gl_lod
from ..formulas._face import elementwise
from ..image import linear_to_srgb
from ..raster import Camera, Mesh
from ..raster._kernels import dyadic_scale_of

__all__ = [
    "Bug",
    "BUGS",
    "NotApplicable",
    "ShiftedCamera",
    "srgb8",
    "encode_srgb_twice",
    "encode_linear",
    "encode_gamma",
    "premultiply",
    "resolve_in_srgb",
    "perspective_bary",
    "vertex_table",
    "world_geometry",
    "gl_lod",
    "dyadic_of",
    "is_derivative",
    "repeat_texels",
    "flip_v",
]


@dataclass(frozen=True)
class Bug:
    """One port bug.

    Attributes
    ----------
    name : str
        The name ``--bugs`` takes.
    stage : {"output", "input", "pipeline"}
        Where the emulation acts (see the module docstring).
    port : str
        What the port does wrong, in one sentence.
    emulation : str
        How refnpr renders it.
    """

    name: str
    stage: str
    port: str
    emulation: str


class NotApplicable(Exception):
    """The bug cannot occur in this case (the style has no textures, no derivatives, ...)."""


_BUG_LIST = (
    Bug(
        "half_pixel",
        "input",
        "samples at the sample-grid pixel's corner instead of its centre (NDC x = 2 x / W - 1)",
        "the projection matrix translated in NDC by half a sample-grid pixel (+1/(nW) in x, "
        "-1/(nH) in y, times w): every sample sees the point half a sample pixel up-left of "
        "its centre; everything that uses the projection (coverage, attributes, contours) moves",
    ),
    Bug(
        "v_flip",
        "input",
        "texture coordinates flipped on load (v -> 1 - v, as trimesh does with TEXCOORD_0)",
        "every mesh's uv replaced by (u, 1 - v) before rasterizing (vertex attributes kept)",
    ),
    Bug(
        "srgb_twice",
        "output",
        "sRGB-encoded colour written to an sRGB render target (encoded twice)",
        "the PNG is rint(255 srgb(srgb(rgb))) of refnpr's linear image (alpha kept)",
    ),
    Bug(
        "srgb_never",
        "output",
        "linear colour written to the PNG without the sRGB encoding",
        "the PNG is rint(255 clip(rgb)) of refnpr's linear image",
    ),
    Bug(
        "gamma22",
        "output",
        "a pure 2.2 gamma instead of the sRGB transfer function",
        "the PNG is rint(255 clip(rgb)^(1/2.2)) of refnpr's linear image",
    ),
    Bug(
        "premultiplied",
        "output",
        "the shader returns premultiplied colour to a straight-alpha composite (blending "
        "rgb a^2 + background (1 - a))",
        "every sample's colour multiplied by its alpha before the kit's composite and resolve",
    ),
    Bug(
        "y_flip",
        "output",
        "a y-up render target read back without flipping (row 0 at the bottom)",
        "the image (G-buffer cases: every channel) upside down",
    ),
    Bug(
        "srgb_resolve",
        "output",
        "multisample resolve of sRGB-encoded samples (averaging encoded values)",
        "per sample: composite over the background, sRGB-encode, then the alpha-weighted box "
        "mean of the encoded colours is the pixel (cases with spp > 1)",
    ),
    Bug(
        "light_negated",
        "input",
        "light direction negated (the direction the light travels instead of towards it)",
        "every directional light's direction negated (point lights: not applicable, their L "
        "comes from positions)",
    ),
    Bug(
        "quad_derivatives",
        "pipeline",
        "dFdx/dFdy instead of analytic derivatives, coarse (one difference per 2 x 2 quad, "
        "which GLSL's dFdx may return)",
        "every derivative channel replaced by the quad's difference of the sample's own "
        "triangle's attribute (its perspective-correct interpolant evaluated at the quad's "
        "samples, as helper lanes do: d/dx from the top row, d/dy from the left column) times "
        "n; lod and dyadic_scale recomputed from those uv derivatives",
    ),
    Bug(
        "quad_derivatives_fine",
        "pipeline",
        "dFdxFine/dFdyFine instead of analytic derivatives",
        "as quad_derivatives, with d/dx from the sample's own row of the quad and d/dy from "
        "its own column",
    ),
    Bug(
        "dfdy_sign",
        "pipeline",
        "d/dy taken as dFdy of a y-up render target without negating it",
        "every d*_dy channel negated (lod and dyadic_scale, which use magnitudes, unchanged)",
    ),
    Bug(
        "lod_bias_plus1",
        "pipeline",
        "mip LOD one level too coarse",
        "the style's lod_bias parameter + 1 (G-buffer cases: the lod channel + 1)",
    ),
    Bug(
        "lod_bias_minus1",
        "pipeline",
        "mip LOD one level too fine (e.g. sample-grid derivatives at spp 4 not multiplied by n)",
        "the style's lod_bias parameter - 1 (G-buffer cases: the lod channel - 1)",
    ),
    Bug(
        "no_renormalize",
        "pipeline",
        "interpolated vertex normals used without renormalizing",
        "the normal channel replaced by sum_i b_i NORMAL_i (perspective-correct barycentrics "
        "of the sample's triangle), not normalized",
    ),
    Bug(
        "nearest",
        "pipeline",
        "nearest instead of linear texture filtering (GL_NEAREST_MIPMAP_LINEAR for mip-mapped "
        "textures)",
        "the style's textures (threshold images, halftone screens and normal maps, X-Toon toon "
        "textures) replaced by copies with every texel repeated k x k (k a power of two, 8 for "
        "mip-mapped textures, up to 16 for toon textures) and, where mip-mapped, the LOD bias "
        "lowered by log2 k so the same levels are chosen: linear filtering of them is "
        "GL_NEAREST except within 1/(2k) texel of a texel edge, where it blends the two texels "
        "(a slightly milder bug). Not emulated for TAMISS brushes and X-Toon weight textures",
    ),
    Bug(
        "no_snap",
        "pipeline",
        "coverage from unsnapped float vertex positions (no 8-bit sub-pixel snapping)",
        "the sample grid rasterized k times finer (k odd, up to 15, within a memory budget) "
        "and every k-th sample kept: the kept samples sit exactly on the kit's, the snapping "
        "is k times finer; derivatives rescaled, lod, dyadic_scale and coverage recomputed",
    ),
    Bug(
        "depth_le",
        "pipeline",
        "depth test <= instead of < (equal depths: the later triangle wins)",
        "the triangles rasterized in reverse order (so the strict test keeps the later of two "
        "equal depths) and tri_id / mesh_id mapped back",
    ),
)

#: Every bug, by name, in the order reports list them.
BUGS: dict[str, Bug] = {b.name: b for b in _BUG_LIST}


# -- output transforms --------------------------------------------------------------------------


def _rgba64(rgba: np.ndarray) -> np.ndarray:
    a = np.asarray(rgba, dtype=np.float64)
    if a.ndim != 3 or a.shape[-1] != 4:
        raise ValueError(f"rgba: expected an (H, W, 4) array, got shape {a.shape}")
    return a


def _to8(rgb_encoded: np.ndarray, alpha: np.ndarray) -> np.ndarray:
    out = np.empty(rgb_encoded.shape[:-1] + (4,), dtype=np.uint8)
    out[..., :3] = np.rint(np.clip(rgb_encoded, 0.0, 1.0) * 255.0)
    out[..., 3] = np.rint(np.clip(alpha, 0.0, 1.0) * 255.0)
    return out


def srgb8(rgba: np.ndarray) -> np.ndarray:
    """(H, W, 4) uint8 of linear straight-alpha ``rgba`` (H, W, 4): the kit's encoding
    (``Image.to_srgb8``), rint(255 srgb(clip(rgb))) and rint(255 clip(alpha))."""
    a = _rgba64(rgba)
    return _to8(linear_to_srgb(a[..., :3]), a[..., 3])


def encode_srgb_twice(rgba: np.ndarray) -> np.ndarray:
    """(H, W, 4) uint8: the sRGB encoding applied twice to ``rgba``'s colour."""
    a = _rgba64(rgba)
    return _to8(linear_to_srgb(linear_to_srgb(a[..., :3])), a[..., 3])


def encode_linear(rgba: np.ndarray) -> np.ndarray:
    """(H, W, 4) uint8: ``rgba``'s linear colour written without encoding."""
    a = _rgba64(rgba)
    return _to8(a[..., :3], a[..., 3])


def encode_gamma(rgba: np.ndarray, gamma: float = 2.2) -> np.ndarray:
    """(H, W, 4) uint8: ``rgba``'s colour encoded as clip(rgb)^(1/gamma)."""
    a = _rgba64(rgba)
    return _to8(np.clip(a[..., :3], 0.0, 1.0) ** (1.0 / gamma), a[..., 3])


def premultiply(samples: np.ndarray) -> np.ndarray:
    """(nH, nW, 4) float32: straight-alpha ``samples`` with their colour multiplied by their
    alpha (what a shader returning premultiplied colour hands a straight-alpha composite)."""
    s = np.array(samples, dtype=np.float32)
    if s.ndim != 3 or s.shape[-1] != 4:
        raise ValueError(f"samples: expected an (nH, nW, 4) array, got shape {s.shape}")
    s[..., :3] *= s[..., 3:4]
    return s


def resolve_in_srgb(samples: np.ndarray, n: int, background: Any) -> np.ndarray:
    """(H, W, 4) uint8: the resolve of an sRGB multisample target.

    Per sample, the straight-alpha ``samples`` (n H, n W, 4) are composited over the
    straight-alpha ``background`` (premultiplied "over"), unpremultiplied and sRGB-encoded; a
    pixel's colour is the mean of its samples' encoded colours weighted by their alpha, its
    alpha the plain mean. With one sample per pixel this is the kit's encoding of the
    composite.
    """
    s = _rgba64(samples)
    n = int(n)
    if n < 1 or s.shape[0] % n or s.shape[1] % n:
        raise ValueError(f"samples: shape {s.shape} is not a grid of {n} x {n} blocks")
    bg = np.asarray(background, dtype=np.float64).reshape(4)
    a = np.clip(s[..., 3:4], 0.0, 1.0)
    prem = s[..., :3] * a + bg[:3] * bg[3] * (1.0 - a)
    alpha = a + bg[3] * (1.0 - a)
    safe = np.where(alpha > 0, alpha, 1.0)
    enc = linear_to_srgb(np.where(alpha > 0, prem / safe, 0.0))
    h, w = s.shape[0] // n, s.shape[1] // n

    def box(x: np.ndarray) -> np.ndarray:
        return x.reshape(h, n, w, n, x.shape[-1]).sum(axis=(1, 3))

    num, den = box(enc * alpha), box(alpha)
    rgb = np.where(den > 0, num / np.where(den > 0, den, 1.0), 0.0)
    return _to8(rgb, den[..., 0] / (n * n))


# -- geometry of the sample's own triangle -----------------------------------------------------


def perspective_bary(
    view_projection: np.ndarray,
    positions: np.ndarray,
    faces: np.ndarray,
    tri: np.ndarray,
    x: np.ndarray,
    y: np.ndarray,
    grid: tuple[int, int],
) -> np.ndarray:
    """Perspective-correct barycentrics of triangles at sample-grid positions.

    Parameters
    ----------
    view_projection : (4, 4) float64
        ``projection_matrix @ view_matrix``.
    positions : (N, 3) float64
        World-space vertices; ``faces`` (M, 3) int index them.
    tri : (S,) int
        The triangle of each query (``>= 0``).
    x, y : (S,) float
        Sample-grid coordinates (sample (sx, sy) has its centre at ``x = sx``, ``y = sy``: the
        half is added here); positions outside the triangle extrapolate its interpolant.
    grid : (int, int)
        ``(n W, n H)``, the sample grid's size.

    Returns
    -------
    (S, 3) float64
        ``b`` with ``sum(b) = 1``: the world-space barycentrics of the point of the triangle's
        plane seen at (x, y), so ``sum_i b_i f_i`` is the perspective-correct interpolant of a
        vertex attribute f. Computed from the 2D homogeneous edge functions of the clip-space
        vertices (no division by w, so triangles crossing w = 0 work).
    """
    tri = np.asarray(tri, dtype=np.int64)
    used, inv = np.unique(tri, return_inverse=True)
    hom = np.concatenate([positions, np.ones((positions.shape[0], 1))], axis=1)
    clip = hom @ np.asarray(view_projection, dtype=np.float64).T
    xyw = clip[:, [0, 1, 3]]
    c0, c1, c2 = (xyw[faces[used, i]] for i in range(3))
    edges = np.stack([np.cross(c1, c2), np.cross(c2, c0), np.cross(c0, c1)], axis=1)  # (K, 3, 3)
    nw, nh = grid
    p = np.stack(
        [
            2.0 * (np.asarray(x, dtype=np.float64) + 0.5) / nw - 1.0,
            1.0 - 2.0 * (np.asarray(y, dtype=np.float64) + 0.5) / nh,
            np.ones(tri.shape[0]),
        ],
        axis=1,
    )
    e = np.einsum("sij,sj->si", edges[inv.reshape(-1)], p)
    total = e.sum(axis=1, keepdims=True)
    return e / np.where(total != 0.0, total, 1.0)


def vertex_table(meshes: list[Mesh], name: str) -> np.ndarray:
    """(N, C) float64: a per-vertex attribute of the concatenated meshes (N vertices in all):
    ``uv``, ``position``, ``normal`` or a named attribute (scalar ones as C = 1).

    Raises
    ------
    NotApplicable
        A mesh lacks the attribute.
    """
    parts = []
    for m in meshes:
        if name == "position":
            a = m.positions
        elif name == "normal":
            a = m.normals
        elif name == "uv":
            a = m.uv
        else:
            a = m.attributes.get(name)
        if a is None:
            raise NotApplicable(f"mesh {m.name!r} has no {name}")
        a = np.asarray(a, dtype=np.float64)
        parts.append(a.reshape(a.shape[0], -1))
    return np.concatenate(parts)


def world_geometry(meshes: list[Mesh]) -> tuple[np.ndarray, np.ndarray]:
    """The meshes concatenated: positions (N, 3) float64 and faces (M, 3) int64 indexing them
    (the rasterizer's global triangle order: ``tri_id`` indexes ``faces``)."""
    offsets = np.cumsum([0] + [m.positions.shape[0] for m in meshes])
    positions = np.concatenate([m.positions for m in meshes])
    faces = np.concatenate([m.faces + o for m, o in zip(meshes, offsets[:-1], strict=True)])
    return positions, faces


def gl_lod(dx: np.ndarray, dy: np.ndarray, size: tuple[int, int]) -> np.ndarray:
    """(S,) float64: the OpenGL isotropic LOD (sec. 8.14) of per-pixel uv derivatives ``dx``,
    ``dy`` (S, 2) for a ``size = (W, H)`` texel texture, as the rasterizer's ``lod`` channel
    (the rasterizer's own :func:`refnpr.device.sampling.gl_lod`)."""
    tw, th = float(size[0]), float(size[1])
    return elementwise(_gl_lod, np.float64, (dx[:, 0], dx[:, 1]), (dy[:, 0], dy[:, 1]), tw, th)


def dyadic_of(gx: np.ndarray, gy: np.ndarray, line_period: float) -> np.ndarray:
    """(S,) float64: Veryovka eq. 5 as the rasterizer's ``dyadic_scale`` channel, from the line
    coordinate's per-pixel gradient ``(gx, gy)`` (S,) each, with w = ``line_period`` (the
    rasterizer's own per-sample function)."""
    return elementwise(dyadic_scale_of, np.float64, gx, gy, math.log2(line_period))


def is_derivative(name: str) -> bool:
    """Whether G-buffer channel ``name`` is a screen derivative (``d<attr>_dx`` / ``_dy``)."""
    return name.startswith("d") and name.endswith(("_dx", "_dy")) and len(name) > 4


# -- cameras and scenes ---------------------------------------------------------------------------


@dataclass(frozen=True)
class ShiftedCamera(Camera):
    """A camera whose projection is translated in NDC by ``offset`` sample-grid pixels of an
    ``n``-times supersampled image: a sample then sees the point ``offset`` sample pixels up-left
    of its centre (``offset = 0.5``: the pixel's corner)."""

    n: int = 1
    offset: float = 0.5

    @classmethod
    def of(cls, camera: Camera, n: int, offset: float = 0.5) -> ShiftedCamera:
        """``camera`` with its projection shifted (see the class docstring)."""
        fields = {f.name: getattr(camera, f.name) for f in dataclasses.fields(Camera)}
        return cls(**fields, n=int(n), offset=float(offset))

    def projection_matrix(self, width: int, height: int) -> np.ndarray:
        p = super().projection_matrix(width, height)
        shift = np.eye(4)
        shift[0, 3] = 2.0 * self.offset / (self.n * width)
        shift[1, 3] = -2.0 * self.offset / (self.n * height)
        return shift @ p


def repeat_texels(a: np.ndarray, k: int) -> np.ndarray:
    """``a`` (rows, cols[, C]) with every texel repeated ``k`` x ``k`` (rows k, cols k)."""
    return np.repeat(np.repeat(np.asarray(a), k, axis=0), k, axis=1)


def flip_v(mesh: Mesh) -> Mesh:
    """``mesh`` with its uv replaced by (u, 1 - v) (normals and attributes kept)."""
    uv = np.array(mesh.uv, dtype=np.float64)
    uv[:, 1] = 1.0 - uv[:, 1]
    return dataclasses.replace(mesh, uv=uv)
