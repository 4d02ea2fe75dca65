"""Rendering a golden case correctly and under each port bug of :mod:`refnpr.kit.port_bugs`
(for ``refnpr kit mutants``).

:class:`CaseRenderer` renders one case as ``refnpr golden`` does (:meth:`~CaseRenderer.correct`
is bit-identical to ``refnpr.render``) and under a bug (:meth:`~CaseRenderer.mutant`): input
bugs change the scene or camera it rasterizes, pipeline bugs the G-buffer (recomputed from the
triangles themselves: :func:`~refnpr.kit.port_bugs.perspective_bary`) or the style (its LOD
bias; texel-repeated textures for ``nearest``), output bugs the image or the shaded samples.
"""

from __future__ import annotations

import dataclasses
import math
from typing import Any

import numpy as np

from ..golden import GoldenCase
from ..raster import Camera, GBuffer, rasterize
from .port_bugs import (
    BUGS,
    NotApplicable,
    ShiftedCamera,
    dyadic_of,
    encode_gamma,
    encode_linear,
    encode_srgb_twice,
    flip_v,
    gl_lod,
    is_derivative,
    perspective_bary,
    premultiply,
    repeat_texels,
    resolve_in_srgb,
    srgb8,
    vertex_table,
    world_geometry,
)

__all__ = ["CaseRenderer", "FINE_SAMPLES", "NEAREST_MIP_REPEAT"]

#: Sample budget of the finer grid ``no_snap`` rasterizes (its k shrinks to stay within it).
FINE_SAMPLES = 6_000_000
_MAX_FINE = 15


#: Texel repetition of mip-mapped textures for ``nearest`` (a power of two: exact LOD shift).
NEAREST_MIP_REPEAT = 8
#: Largest repetition of toon textures for ``nearest``, and their texel budget.
_TOON_REPEAT, _TOON_TEXELS = 16, 4_000_000


def _repeated_pyramid(pyramid: Any, k: int) -> Any:
    if pyramid is None:
        return None
    return dataclasses.replace(pyramid, levels=tuple(repeat_texels(lv, k) for lv in pyramid.levels))


class _Repeated:
    """Texel-repeated copies of pyramids, each made once, remembering its original."""

    def __init__(self, k: int) -> None:
        self.k = k
        self._made: dict[int, tuple[Any, Any]] = {}  # id(original) -> (original, copy)
        self._original: dict[int, Any] = {}  # id(copy) -> original

    def __call__(self, pyramid: Any) -> Any:
        if pyramid is None:
            return None
        if id(pyramid) not in self._made:
            copy = _repeated_pyramid(pyramid, self.k)
            self._made[id(pyramid)] = (pyramid, copy)
            self._original[id(copy)] = pyramid
        return self._made[id(pyramid)][1]

    def original(self, pyramid: Any) -> Any:
        return self._original.get(id(pyramid), pyramid)


class _NearestPyramids:
    """A threshold style's pyramid cache handing out texel-repeated pyramids; tone maps stay
    those of the original pyramids (a port reads them from the kit)."""

    def __init__(self, cache: Any, repeated: _Repeated) -> None:
        self._cache, self._repeated = cache, repeated

    def get(self, texture: str, p: Any, *, tiling: str | None = None) -> Any:
        return self._repeated(self._cache.get(texture, p, tiling=tiling))

    def tone_maps(self, pyramid: Any) -> Any:
        return self._cache.tone_maps(self._repeated.original(pyramid))


def _inner(style: Any) -> Any:
    return style.base if style.name == "contoured" else style


def _reads_lod_bias(style: Any) -> bool:
    """Whether the style's chosen modes read its ``lod_bias`` (threshold: source image only)."""
    inner = _inner(style)
    params = getattr(type(inner), "PARAMS", None)
    return params is not None and "lod_bias" in params.by_name and params.reads("lod_bias", inner.p)


def _share_textures(old: Any, new: Any) -> None:
    """Let ``new`` (the same style with other LOD or texture settings) reuse the textures
    ``old`` built (CLAHE pyramids, halftone screens and their tone tables): the same files and
    parameters give the same textures, and building them again costs seconds per case."""
    old, new = _inner(old), _inner(new)
    if old.name == new.name == "threshold":
        new.pyramids = old.pyramids
    elif old.name == new.name == "halftone":
        new._screens, new._tone_luts = old._screens, old._tone_luts


def _nearest_style(style: Any, spec: Any, lod_bias: float | None) -> Any:
    """A copy of ``style`` that samples its textures nearly as GL_NEAREST (see ``nearest``)."""
    from ..styles import style_from_spec

    inner = _inner(style)
    if inner.name == "xtoon":
        tex = np.asarray(inner.texture)
        rep = _TOON_REPEAT
        while rep > 2 and rep * rep * tex.shape[0] * tex.shape[1] > _TOON_TEXELS:
            rep //= 2
        return style_from_spec(_spec_with(spec, "texture", repeat_texels(tex, rep)))
    if (
        inner.name not in ("threshold", "halftone")
        or lod_bias is None
        or not _reads_lod_bias(style)
    ):
        raise NotApplicable(
            "the style samples no texture with linear filtering"
            if inner.name not in ("tam", "tamiss")
            else "not emulated: the TAMISS brush lookup takes no repeated texture"
        )
    repeated = _Repeated(NEAREST_MIP_REPEAT)
    new = style_from_spec(_spec_with(spec, "lod_bias", lod_bias - math.log2(NEAREST_MIP_REPEAT)))
    _share_textures(style, new)
    base = _inner(new)
    if base.name == "threshold":
        base.pyramids = _NearestPyramids(base.pyramids, repeated)
        base.pyramid = repeated(base.pyramid)
    else:  # halftone: repeated screens, the original screens' tone tables
        screen_for, luts, made, original = base.screen_for, base._luts, {}, {}

        def nearest_screen(spec: dict[str, Any], material_texture: str | None) -> Any:
            screen = screen_for(spec, material_texture)
            if id(screen) not in made:
                copy = dataclasses.replace(
                    screen, pyramid=repeated(screen.pyramid), normals=repeated(screen.normals)
                )
                made[id(screen)], original[id(copy)] = copy, screen
            return made[id(screen)]

        base.screen_for = nearest_screen
        base._luts = lambda screen: luts(original.get(id(screen), screen))
    return new


def _spec_with(spec: Any, key: str, value: Any) -> dict[str, Any]:
    """A style table with ``key`` set on the shading style (inside a ``contoured`` base)."""
    spec = {"name": spec} if isinstance(spec, str) else dict(spec)
    if spec.get("name") == "contoured":
        spec["base"] = _spec_with(spec.get("base", "toon"), key, value)
    else:
        spec[key] = value
    return spec


# -- one case -------------------------------------------------------------------------------------


class CaseRenderer:
    """refnpr's render of one golden case, correct and under each :data:`BUGS` entry.

    Parameters
    ----------
    case : GoldenCase
        The suite's case (image or G-buffer).
    lod_bias : float or None
        The case's resolved ``lod_bias`` style parameter (from the kit's ``case.json``), None
        when its style has none.

    Notes
    -----
    Renders are what a backend writes: image cases ``(H, W, 4)`` uint8 sRGB RGBA, G-buffer
    cases a dict of the case's channels (float32 / int32 arrays on the sample grid). Image
    cases render the suite's float64 scene (the goldens' geometry), G-buffer cases the kit's
    float32 meshes (what their expected arrays were rasterized from).
    """

    def __init__(self, case: GoldenCase, *, lod_bias: float | None = None) -> None:
        from ..render import DEFAULT_STYLE
        from ..scenes import load_scene
        from ..styles import style_from_spec

        self.case = case
        scene = load_scene(case.scene)
        self.scene = scene.at(0) if getattr(scene, "animation", None) is not None else scene
        self.kind = case.kind
        self.width, self.height, self.spp = int(case.width), int(case.height), int(case.spp)
        self.n = math.isqrt(self.spp)
        self.lod_bias = lod_bias
        if self.kind == "gbuffer":
            from .scene_export import kit_meshes

            self.spec = None
            self.style = None
            self.channels = sorted(case.channels)
            size = case.texture_size
            self.options: dict[str, Any] = {"texture_size": tuple(size)} if size else {}
            self._meshes = kit_meshes(self.scene)
        else:
            self.spec = (
                case.style if case.style is not None else (self.scene.style or DEFAULT_STYLE)
            )
            self.style = style_from_spec(self.spec)
            self.channels = sorted(self.style.requires(self.scene))
            self.options = dict(self.style.raster_options(self.scene))
            self._meshes = list(self.scene.world_meshes())
        self._samples: np.ndarray | None = None
        self._linear: np.ndarray | None = None
        self._gb: GBuffer | None = None

    # -- the pipeline ---------------------------------------------------------------------
    def _rasterize(
        self, *, meshes: Any = None, camera: Camera | None = None, extra: tuple = ()
    ) -> GBuffer:
        channels = sorted(set(self.channels) | set(extra))
        cam = self.scene.camera if camera is None else camera
        src = self._meshes if meshes is None else meshes
        return rasterize(src, cam, self.width, self.height, channels, self.spp, **self.options)

    def _keep(self, gb: GBuffer, channels: dict[str, np.ndarray] | None = None) -> GBuffer:
        """``gb`` with exactly the case's channels (``channels`` replacing some of them)."""
        chans = dict(gb.channels) if channels is None else {**gb.channels, **channels}
        return dataclasses.replace(gb, channels={k: chans[k] for k in self.channels})

    def _shade(self, gb: GBuffer, scene: Any = None, style: Any = None) -> np.ndarray:
        from ..styles import ShadeContext

        scene = self.scene if scene is None else scene
        style = self.style if style is None else style
        ctx = ShadeContext(self._keep(gb), scene.with_camera(gb.camera))
        return np.asarray(style.shade(ctx), dtype=np.float32)

    def _resolve(self, samples: np.ndarray, scene: Any = None) -> np.ndarray:
        from ..render import composite_resolve

        scene = self.scene if scene is None else scene
        return composite_resolve(samples, self.n, scene.background, style_name=self.style.name)

    def _render(self, gb: GBuffer, scene: Any = None, style: Any = None) -> Any:
        """What a backend writes for the frame ``gb`` (see the class Notes)."""
        if self.kind == "gbuffer":
            return {k: np.array(gb[k]) for k in self.channels}
        return srgb8(self._resolve(self._shade(gb, scene, style), scene))

    def _base(self) -> GBuffer:
        """The correct G-buffer with ``tri_id`` (cached; callers copy what they change)."""
        if self._gb is None:
            self._gb = self._rasterize(extra=("tri_id",))
        return self._gb

    def _correct_linear(self) -> np.ndarray:
        if self._linear is None:
            gb = self._rasterize()
            self._samples = self._shade(gb)
            self._linear = self._resolve(self._samples)
        return self._linear

    def correct(self) -> Any:
        """refnpr's render of the case (image cases: bit-identical to ``refnpr.render``)."""
        if self.kind == "gbuffer":
            return self._render(self._rasterize())
        return srgb8(self._correct_linear())

    def mutant(self, bug: str) -> Any:
        """The render of the case under ``bug`` (a :data:`BUGS` name).

        Raises
        ------
        NotApplicable
            The bug cannot occur in this case (the reason is the message).
        ValueError
            An unknown bug name.
        """
        if bug not in BUGS:
            raise ValueError(f"bug: unknown bug {bug!r}; expected one of {list(BUGS)}")
        return getattr(self, f"_bug_{bug}")()

    # -- output bugs ----------------------------------------------------------------------
    def _image_only(self) -> np.ndarray:
        if self.kind == "gbuffer":
            raise NotApplicable("a G-buffer case has no colour output")
        return self._correct_linear()

    def _bug_srgb_twice(self) -> Any:
        return encode_srgb_twice(self._image_only())

    def _bug_srgb_never(self) -> Any:
        return encode_linear(self._image_only())

    def _bug_gamma22(self) -> Any:
        return encode_gamma(self._image_only(), 2.2)

    def _bug_premultiplied(self) -> Any:
        self._image_only()
        return srgb8(self._resolve(premultiply(self._samples)))

    def _bug_srgb_resolve(self) -> Any:
        self._image_only()
        if self.n == 1:
            raise NotApplicable("one sample per pixel: nothing is resolved")
        return resolve_in_srgb(self._samples, self.n, self.scene.background)

    def _bug_y_flip(self) -> Any:
        if self.kind == "gbuffer":
            return {k: np.ascontiguousarray(v[::-1]) for k, v in self.correct().items()}
        return srgb8(self._correct_linear()[::-1])

    # -- input bugs -----------------------------------------------------------------------
    def _bug_half_pixel(self) -> Any:
        cam = ShiftedCamera.of(self.scene.camera, self.n)
        return self._render(self._rasterize(camera=cam), self.scene.with_camera(cam))

    def _reads(self, *channels: str) -> bool:
        return bool(set(channels) & set(self.channels))

    def _bug_v_flip(self) -> Any:
        if not self._reads("uv", "duv_dx", "duv_dy", "lod", "dyadic_scale"):
            raise NotApplicable("the style reads no texture coordinates")
        if all(m.uv is None for m in self._meshes):
            raise NotApplicable("no mesh has texture coordinates")
        if self.kind == "gbuffer":
            return self._render(self._rasterize(meshes=[flip_v(m) for m in self._meshes]))
        objects = tuple(
            o if o.mesh.uv is None else dataclasses.replace(o, mesh=flip_v(o.mesh))
            for o in self.scene.objects
        )
        scene = dataclasses.replace(self.scene, objects=objects)
        return self._render(self._rasterize(meshes=list(scene.world_meshes())), scene)

    def _bug_light_negated(self) -> Any:
        self._image_only()
        if not any(light.kind == "directional" for light in self.scene.lights):
            raise NotApplicable("no directional light (a point light's L comes from positions)")
        lights = tuple(
            dataclasses.replace(light, direction=tuple(-d for d in light.direction))
            if light.kind == "directional"
            else light
            for light in self.scene.lights
        )
        scene = dataclasses.replace(self.scene, lights=lights)
        return self._render(self._rasterize(), scene)

    # -- pipeline bugs --------------------------------------------------------------------
    def _bug_lod_bias_plus1(self) -> Any:
        return self._lod_bias(1.0)

    def _bug_lod_bias_minus1(self) -> Any:
        return self._lod_bias(-1.0)

    def _lod_bias(self, delta: float) -> Any:
        if self.kind == "gbuffer":
            if "lod" not in self.channels:
                raise NotApplicable("the case has no lod channel")
            gb = self._base()
            lod = np.array(gb["lod"])
            covered = gb["tri_id"] >= 0
            lod[covered] += delta
            return self._render(self._keep(gb, {"lod": lod}))
        if self.lod_bias is None or not _reads_lod_bias(self.style):
            raise NotApplicable("the style samples no mip-mapped texture (no lod_bias parameter)")
        from ..styles import style_from_spec

        style = style_from_spec(_spec_with(self.spec, "lod_bias", self.lod_bias + delta))
        _share_textures(self.style, style)
        return self._render(self._rasterize(), style=style)

    def _bug_nearest(self) -> Any:
        self._image_only()
        style = _nearest_style(self.style, self.spec, self.lod_bias)
        return self._render(self._rasterize(), style=style)

    def _bug_dfdy_sign(self) -> Any:
        names = [c for c in self.channels if is_derivative(c) and c.endswith("_dy")]
        if not names:
            raise NotApplicable("the style reads no d/dy channel")
        gb = self._base()
        return self._render(self._keep(gb, {c: -np.asarray(gb[c]) for c in names}))

    def _bug_quad_derivatives(self) -> Any:
        return self._quad(coarse=True)

    def _bug_quad_derivatives_fine(self) -> Any:
        return self._quad(coarse=False)

    def _quad(self, *, coarse: bool) -> Any:
        derived = [c for c in self.channels if is_derivative(c) or c in ("lod", "dyadic_scale")]
        if not derived:
            raise NotApplicable("the style reads no screen-space derivatives")
        gb, ys, xs, t, faces, bary = self._covered()
        tri = gb["tri_id"]
        x0, y0 = xs & ~1, ys & ~1
        row, col = (y0, x0) if coarse else (ys, xs)  # the quad row / column differenced
        bx0, bx1, by0, by1 = bary(x0, row), bary(x0 + 1, row), bary(col, y0), bary(col, y0 + 1)
        corners = faces[t]  # (S, 3) the samples' triangles' vertices
        n = float(self.n)

        def quad(name: str) -> tuple[np.ndarray, np.ndarray]:
            tab = vertex_table(self._meshes, name)[corners]  # (S, 3, C)

            def at(b):
                return np.einsum("si,sic->sc", b, tab)

            return (at(bx1) - at(bx0)) * n, (at(by1) - at(by0)) * n

        new: dict[str, np.ndarray] = {}
        bases = {c[1:-3] for c in self.channels if is_derivative(c)}
        if self._reads("lod", "dyadic_scale"):
            bases.add("uv")
        stored: dict[str, np.ndarray] = {}
        dtype = np.dtype(self.options.get("dtype", np.float32))
        for base in sorted(bases):
            dx, dy = quad(base)
            for axis, d in (("x", dx), ("y", dy)):
                key = f"d{base}_d{axis}"
                like = gb[key] if key in gb else np.zeros(tri.shape + (d.shape[1],), dtype)
                arr = np.array(like)
                arr[ys, xs] = d.reshape(arr[ys, xs].shape)
                stored[key] = arr
                if key in gb:
                    new[key] = arr
        if self._reads("lod", "dyadic_scale"):
            gx = stored["duv_dx"][ys, xs].astype(np.float64)
            gy = stored["duv_dy"][ys, xs].astype(np.float64)
            if "lod" in self.channels:
                lod = np.array(gb["lod"])
                lod[ys, xs] = gl_lod(gx, gy, gb.texture_size)
                new["lod"] = lod
            if "dyadic_scale" in self.channels:
                k = 0 if self.options.get("dyadic_coord", "v") == "u" else 1
                dy_ = np.array(gb["dyadic_scale"])
                dy_[ys, xs] = dyadic_of(gx[:, k], gy[:, k], gb.line_period)
                new["dyadic_scale"] = dy_
        return self._render(self._keep(gb, new))

    def _covered(self) -> tuple[Any, np.ndarray, np.ndarray, np.ndarray, np.ndarray, Any]:
        """The correct G-buffer, its covered samples (ys, xs) and their triangles t, the world
        faces, and ``bary(x, y)``: the perspective-correct barycentrics of triangle t at the
        sample positions (x, y)."""
        gb = self._base()
        tri = gb["tri_id"]
        ys, xs = np.nonzero(tri >= 0)
        t = tri[ys, xs].astype(np.int64)
        positions, faces = world_geometry(self._meshes)
        grid = (self.n * self.width, self.n * self.height)

        def bary(x: np.ndarray, y: np.ndarray) -> np.ndarray:
            return perspective_bary(gb.view_projection, positions, faces, t, x, y, grid)

        return gb, ys, xs, t, faces, bary

    def _bug_no_renormalize(self) -> Any:
        if "normal" not in self.channels:
            raise NotApplicable("the style reads no normals")
        gb, ys, xs, t, faces, bary = self._covered()
        b = bary(xs, ys)
        tab = vertex_table(self._meshes, "normal")[faces[t]]
        normal = np.array(gb["normal"])
        normal[ys, xs] = np.einsum("si,sic->sc", b, tab)
        return self._render(self._keep(gb, {"normal": normal}))

    def fine_factor(self) -> int:
        """k of ``no_snap``: the largest odd k <= 15 whose k-times finer sample grid holds at
        most :data:`FINE_SAMPLES` samples (at least 3)."""
        base = (self.n * self.width) * (self.n * self.height)
        k = max(1, math.isqrt(FINE_SAMPLES // base))
        k = min(k, _MAX_FINE)
        k -= 1 - k % 2
        return max(k, 3)

    def _bug_no_snap(self) -> Any:
        k = self.fine_factor()
        scale = k * self.n
        wanted = set(self.channels) | {"tri_id"}
        if wanted & {"lod", "dyadic_scale"}:
            wanted |= {"duv_dx", "duv_dy"}
        wanted.discard("coverage")
        fine = rasterize(self._meshes, self.scene.camera, scale * self.width,
                         scale * self.height, sorted(wanted), 1, **self.options)  # fmt: skip
        off = (k - 1) // 2
        chans: dict[str, np.ndarray] = {}
        for name, a in fine.channels.items():
            sub = np.ascontiguousarray(a[off::k, off::k])
            if is_derivative(name):
                sub = (sub.astype(np.float64) * scale).astype(a.dtype)
            chans[name] = sub
        tri = chans["tri_id"]
        ys, xs = np.nonzero(tri >= 0)
        if "lod" in chans or "dyadic_scale" in chans:
            gx = chans["duv_dx"][ys, xs].astype(np.float64)
            gy = chans["duv_dy"][ys, xs].astype(np.float64)
            if "lod" in chans:
                chans["lod"][ys, xs] = gl_lod(gx, gy, fine.texture_size)
            if "dyadic_scale" in chans:
                c = 0 if self.options.get("dyadic_coord", "v") == "u" else 1
                chans["dyadic_scale"][ys, xs] = dyadic_of(gx[:, c], gy[:, c], fine.line_period)
        if "coverage" in self.channels:
            n, h, w = self.n, self.height, self.width
            cov = (tri >= 0).reshape(h, n, w, n).mean(axis=(1, 3))
            dtype = np.dtype(self.options.get("dtype", np.float32))
            chans["coverage"] = cov.astype(dtype)
        gb = GBuffer(
            channels=chans,
            width=self.width,
            height=self.height,
            spp=self.spp,
            camera=fine.camera,
            view_projection=fine.view_projection,
            mesh_first_tri=fine.mesh_first_tri,
            texture_size=fine.texture_size,
            line_period=fine.line_period,
        )
        return self._render(gb)

    def _bug_depth_le(self) -> Any:
        meshes = self._meshes
        reversed_meshes = [dataclasses.replace(m, faces=m.faces[::-1].copy()) for m in meshes[::-1]]
        gb = self._rasterize(meshes=reversed_meshes, extra=("tri_id",))
        counts = np.array([m.faces.shape[0] for m in meshes], dtype=np.int64)
        first = np.concatenate([[0], np.cumsum(counts)])
        rev_first = np.concatenate([[0], np.cumsum(counts[::-1])])
        r = np.asarray(gb["tri_id"], dtype=np.int64)
        covered = r >= 0
        j_rev = np.searchsorted(rev_first, r[covered], side="right") - 1
        j = len(meshes) - 1 - j_rev
        tri = np.full(r.shape, -1, dtype=np.int32)
        tri[covered] = first[j] + counts[j] - 1 - (r[covered] - rev_first[j_rev])
        chans = {"tri_id": tri}
        if "mesh_id" in gb:
            mesh_id = np.full(r.shape, -1, dtype=np.int32)
            mesh_id[covered] = j
            chans["mesh_id"] = mesh_id
        gb = dataclasses.replace(gb, mesh_first_tri=first)
        return self._render(self._keep(gb, chans))
