"""The G-buffer: named per-sample channels on the supersampling grid, plus the frame they belong to."""

from __future__ import annotations

from collections.abc import Iterator, Mapping
from dataclasses import dataclass, field

import numpy as np

from .camera import Camera

__all__ = ["GBuffer", "BUILTIN_CHANNELS", "box_resolve"]

#: Built-in channels: name -> (components, description). Components 0 means a scalar (H, W) channel.
BUILTIN_CHANNELS: dict[str, tuple[int, str]] = {
    "depth": (0, "eye-space distance along the view axis (w_clip, positive); +inf where empty"),
    "ndc_z": (0, "OpenGL NDC depth z_clip / w_clip in [-1, 1]; 1 where empty"),
    "tri_id": (0, "int32 global triangle index (meshes concatenated in order); -1 where empty"),
    "mesh_id": (0, "int32 index of the mesh the triangle belongs to; -1 where empty"),
    "bary": (3, "perspective-correct barycentrics of the triangle's three vertices"),
    "position": (3, "world-space position"),
    "normal": (3, "interpolated vertex normal, renormalized (world space); 0 where empty"),
    "uv": (2, "perspective-correct texture coordinates"),
    "duv_dx": (2, "analytic d(uv)/dx per pixel (x to the right)"),
    "duv_dy": (2, "analytic d(uv)/dy per pixel (y downward)"),
    "lod": (
        0,
        "GL isotropic LOD log2(rho) for `texture_size` (rho = max footprint length in texels)",
    ),
    "dyadic_scale": (0, "Veryovka eq. 5: s = log2(d / w), d = 1/|grad v| px, w = `line_period`"),
    "coverage": (0, "pixel-resolution fraction of the n x n samples covered (H, W)"),
    "coverage_count": (0, "debug: int32 number of primitives claiming each sample, no depth test"),
    "dposition_dx": (3, "analytic d(position)/dx per pixel"),
    "dposition_dy": (3, "analytic d(position)/dy per pixel"),
}


def box_resolve(samples: np.ndarray, n: int) -> np.ndarray:
    """Box-filter an ``(n H, n W, ...)`` sample image down to ``(H, W, ...)`` (mean of n x n)."""
    if n == 1:
        return samples
    h, w = samples.shape[0] // n, samples.shape[1] // n
    shaped = samples.reshape(h, n, w, n, *samples.shape[2:])
    return shaped.mean(axis=(1, 3), dtype=np.float64).astype(
        samples.dtype if samples.dtype.kind == "f" else np.float64, copy=False
    )


_FRAME_FIELDS = frozenset(
    {"camera", "view_projection", "mesh_first_tri", "texture_size", "line_period", "timings"}
)


@dataclass(frozen=True, eq=False)
class GBuffer(Mapping):
    """Rasterized channels of one view.

    ``gb["name"]`` is a numpy array on the sample grid: ``(n H, n W)`` or ``(n H, n W, C)`` where
    ``spp = n * n`` (``n = 1``: one sample at each pixel centre). Sample ``(sx, sy)`` lies at pixel
    coordinates ``((sx + 0.5) / n, (sy + 0.5) / n)``; derivatives are per *pixel* (not per
    sample). The exception is ``coverage``, which is per pixel ``(H, W)``. Shade per sample and
    call :meth:`resolve` to box-filter to the pixel grid.

    Attributes
    ----------
    width, height : int
        Image size in pixels.
    spp : int
        Samples per pixel (a square number n * n).
    camera : Camera
    view_projection : (4, 4) float64
        ``camera.projection_matrix(width, height) @ camera.view_matrix()``.
    mesh_first_tri : (n_meshes + 1,) int64
        Triangle index ranges of the concatenated meshes (``tri_id`` -> mesh).
    texture_size, line_period : parameters the lod and dyadic_scale channels were computed with.
    """

    channels: dict[str, np.ndarray]
    width: int
    height: int
    spp: int
    camera: Camera
    view_projection: np.ndarray
    mesh_first_tri: np.ndarray
    texture_size: tuple[int, int] | None = None
    line_period: float = 1.0
    timings: dict[str, float] = field(default_factory=dict)
    #: Work buffers of ``rasterize(..., out=self)`` (per-triangle tables, a ``tri_id`` when it
    #: is not a channel), kept so that repeated frames allocate nothing. Private.
    _scratch: dict[str, np.ndarray] = field(default_factory=dict, repr=False, compare=False)

    def _refill(self, **frame) -> GBuffer:
        """Point this G-buffer at the frame ``rasterize(..., out=self)`` wrote in place."""
        for key, value in frame.items():
            if key not in _FRAME_FIELDS:
                raise TypeError(f"_refill: unknown field {key!r}")
            object.__setattr__(self, key, value)
        return self

    @property
    def n(self) -> int:
        """Samples per pixel along each axis."""
        return int(round(self.spp**0.5))

    def __getitem__(self, name: str) -> np.ndarray:
        try:
            return self.channels[name]
        except KeyError:
            raise KeyError(
                f"channel {name!r} was not rasterized; available: {sorted(self.channels)}. "
                "Ask rasterize(..., channels=...) for it."
            ) from None

    def __iter__(self) -> Iterator[str]:
        return iter(self.channels)

    def __len__(self) -> int:
        return len(self.channels)

    @property
    def sample_shape(self) -> tuple[int, int]:
        """(n H, n W)."""
        return (self.height * self.n, self.width * self.n)

    def resolve(self, samples: np.ndarray) -> np.ndarray:
        """Box-filter a per-sample array ``(n H, n W, ...)`` to pixels ``(H, W, ...)``."""
        samples = np.asarray(samples)
        if samples.shape[:2] != self.sample_shape:
            raise ValueError(
                f"samples: expected leading shape {self.sample_shape} (the sample grid), "
                f"got {samples.shape}"
            )
        return box_resolve(samples, self.n)

    def sample_pixel_coords(self) -> tuple[np.ndarray, np.ndarray]:
        """Pixel coordinates (x, y) of every sample centre, each ``(n H, n W)`` float64."""
        n = self.n
        ys, xs = np.mgrid[0 : self.height * n, 0 : self.width * n].astype(np.float64)
        return (xs + 0.5) / n, (ys + 0.5) / n

    def nbytes(self) -> int:
        return int(sum(a.nbytes for a in self.channels.values()))

    def display_grid(self, *, max_tile: int = 256, columns: int = 4) -> np.ndarray:
        """Every channel as a labelled tile at most ``max_tile`` pixels on its long side, in a
        grid of ``columns``: ``(H', W', 3)`` uint8 (the encodings: :mod:`refnpr.raster._display`)."""
        from ._display import gbuffer_grid

        return gbuffer_grid(self, max_tile=max_tile, columns=columns)

    def _repr_png_(self) -> bytes:
        """Jupyter's rich display: :meth:`display_grid` as PNG bytes."""
        from ._display import gbuffer_png

        return gbuffer_png(self)
