"""``render(scene, style, ...)``: rasterize exactly what the style needs, shade, resolve."""

from __future__ import annotations

import math
import time
from collections.abc import Callable
from typing import Any

import numpy as np

from . import _kernels as K
from . import _memory
from .image import Image
from .raster import Camera, rasterize
from .raster.rasterize import attribute_widths
from .scenes._params import check_int
from .styles import ShadeContext, Style, style_from_spec

__all__ = [
    "render",
    "required_channels",
    "as_scene",
    "composite_resolve",
    "RenderContext",
    "DEFAULT_STYLE",
]

#: Style used when neither the call nor the scene names one.
DEFAULT_STYLE = "toon"

Progress = Callable[[str, float], None]


def as_scene(scene: Any):
    """A Scene from a Scene, a built-in scene name or a .toml path (TypeError otherwise)."""
    if isinstance(scene, str) or hasattr(scene, "__fspath__"):
        from .scenes import load_scene

        return load_scene(scene)
    if not hasattr(scene, "world_meshes") or not hasattr(scene, "camera"):
        raise TypeError(
            f"scene: expected a refnpr.scenes.Scene, a built-in scene name or a .toml path, "
            f"got {type(scene).__name__}"
        )
    return scene


def _still(scene: Any):
    """The still a render draws: an animated scene's frame 0, else the scene itself."""
    return scene.at(0) if getattr(scene, "animation", None) is not None else scene


def _style_of(style: Any, scene: Any) -> Style:
    """``style``, else the scene's own, else ``DEFAULT_STYLE``, built."""
    return style_from_spec(
        style if style is not None else getattr(scene, "style", None) or DEFAULT_STYLE
    )


def _check_args(
    width, height, spp, camera=None, progress=None, gbuf=False, copy=False, passes=False
):
    """render's own arguments, checked before any scene work (spp's square-ness: rasterize)."""
    width = check_int("width", width, minimum=1)
    height = check_int("height", height, minimum=1)
    spp = check_int("spp", spp, minimum=1)
    if camera is not None and not isinstance(camera, Camera):
        raise TypeError(
            f"camera: expected a refnpr.raster.Camera or None (the scene's camera), "
            f"got {type(camera).__name__} {camera!r}"
        )
    if progress is not None and not callable(progress):
        raise TypeError(
            "progress: expected a callable progress(phase: str, fraction: float) or None, "
            f"got {type(progress).__name__} {progress!r}"
        )
    for name, flag in (("return_gbuffer", gbuf), ("copy", copy), ("passes", passes)):
        if not isinstance(flag, (bool, np.bool_)):
            raise TypeError(f"{name}: expected a bool, got {type(flag).__name__} {flag!r}")
    return width, height, spp


def _check_memory(scene: Any, style: Style, channels, width: int, height: int, spp: int):
    """Refuse a render whose sample grid would not fit, before the rasterizer allocates."""
    if spp > _memory.MAX_SPP or math.isqrt(spp) ** 2 != spp:
        return  # rasterize says what is wrong with spp
    meshes = list(scene.world_meshes())  # memoized per object: rasterize reuses them
    attrs = attribute_widths(meshes) if meshes else {}
    parts = _memory.render_bytes(width, height, spp, channels, style.name, attributes=attrs)
    _memory.check_fits(width, height, spp, parts)


def composite_resolve(
    rgba: np.ndarray,
    n: int,
    background: Any,
    *,
    out: np.ndarray | None = None,
    style_name: str = "style",
) -> np.ndarray:
    """Composite samples over the background, box-resolve them and unpremultiply, in one pass.

    Per sample, in float64: premultiplied ``(rgb * a, a)`` "over" the premultiplied background;
    the n x n samples of a pixel averaged (box filter); ``rgb / alpha`` (0 where alpha is 0).
    Bit-identical to that numpy expression, for any numba thread count.

    Parameters
    ----------
    rgba : (n H, n W, 4) float32
        Straight-alpha samples, as a style's ``shade`` returns them.
    n : int
        Samples per pixel along each axis (``spp = n * n``).
    background : (4,) array-like
        Straight-alpha RGBA background (converted to float64).
    out : (H, W, 4) float32, optional
        Written in place and returned (a buffer kept from an earlier frame); new if None.
    style_name : str
        Named in the error raised for NaN or inf samples.

    Returns
    -------
    (H, W, 4) float32
        Straight-alpha pixels.

    Raises
    ------
    ValueError
        A wrong shape or dtype, or NaN / inf among the samples or the pixels (out-of-range
        samples can overflow float32: a bug in the style). The pixels returned are finite.
    """
    n = check_int("n", n, minimum=1)
    rgba = np.asarray(rgba)
    if rgba.dtype != np.float32 or rgba.ndim != 3 or rgba.shape[2] != 4:
        raise ValueError(
            f"rgba: expected an (n H, n W, 4) float32 array, got {rgba.shape} {rgba.dtype}"
        )
    if rgba.shape[0] % n or rgba.shape[1] % n:
        raise ValueError(
            f"rgba: shape {rgba.shape} is not a whole number of {n} x {n} sample blocks (n={n})"
        )
    bg = np.asarray(background, dtype=np.float64)
    if bg.shape != (4,):
        raise ValueError(f"background: expected 4 values (RGBA), got shape {bg.shape}")
    shape = (rgba.shape[0] // n, rgba.shape[1] // n, 4)
    if out is None:
        out = np.empty(shape, dtype=np.float32)
    elif (
        not isinstance(out, np.ndarray)
        or out.shape != shape
        or out.dtype != np.float32
        or not out.flags.c_contiguous
        or not out.flags.writeable
    ):
        got = f"{out.shape} {out.dtype}" if isinstance(out, np.ndarray) else type(out).__name__
        raise ValueError(
            f"out: expected a writable C-contiguous {shape} float32 array, got {got}; "
            "pass out=None for a new one"
        )
    bad_rows = np.empty(shape[0], dtype=np.uint8)
    K.composite_resolve_for(n if n <= 2 else 0)(np.ascontiguousarray(rgba), n, bg, out, bad_rows)
    if bad_rows.any():
        raise ValueError(f"style {style_name!r} produced NaN or inf; this is a bug in the style")
    return out


def required_channels(scene: Any, style: Any = None) -> frozenset[str]:
    """The G-buffer channels ``render`` will ask the rasterizer for (the style's ``requires``)."""
    scene = _still(as_scene(scene))
    return frozenset(_style_of(style, scene).requires(scene))


def render(
    scene: Any,
    style: Any = None,
    width: int = 512,
    height: int = 512,
    spp: int = 1,
    *,
    camera: Camera | None = None,
    progress: Progress | None = None,
    return_gbuffer: bool = False,
    passes: bool = False,
) -> Image | tuple[Image, Any]:
    """Render a scene with a style.

    Parameters
    ----------
    scene : Scene, str or path
        A scene object, a built-in scene name (``refnpr.scenes.list_scenes()``) or a TOML file.
    style : Style, str, dict or None
        A style instance, a registered name, a ``{"name": ..., **params}`` table, or None for the
        scene's own style (else ``DEFAULT_STYLE``).
    width, height : int
        Image size in pixels.
    spp : int
        Samples per pixel (a square n * n); shading is per sample, then box-resolved.
    camera : Camera, optional
        Overrides the scene camera.
    progress : callable(phase, fraction), optional
        Called at phase boundaries ("rasterize", "shade", "resolve", "done").
    return_gbuffer : bool
        Also return the G-buffer the style was shaded from.
    passes : bool
        Also rasterize the G-buffer passes of :data:`refnpr.exr.EXR_PASSES` (depth, position,
        tri_id, mesh_id; normal and uv where every mesh has them) and attach every channel the
        frame computed to the image, with the style's intermediates (``style.INTERMEDIATES``:
        tone, X-Toon's detail D, thresholds, stroke ids), one sample per pixel (``Image.passes``,
        see :func:`refnpr.exr.pixel_passes`), for ``image.save("x.exr")``. The pixels are the
        same.

    Returns
    -------
    Image
        ``rgba`` (H, W, 4) float32 linear straight-alpha, composited over ``scene.background``.
    """
    t0 = time.perf_counter()
    _check_args(width, height, spp, camera, progress, return_gbuffer, passes)
    got = RenderContext(scene, style, width, height, spp, passes=passes).render(
        camera, progress=progress, return_gbuffer=return_gbuffer
    )
    image = got[0] if return_gbuffer else got
    image.timings["total"] = time.perf_counter() - t0  # the whole call, as the caller waits for it
    return got


def _same_options(a: dict, b: dict) -> bool:
    """Whether two rasterizer option dicts are equal (False where a value cannot be compared)."""
    try:
        return bool(a.keys() == b.keys() and all(a[k] is b[k] or a[k] == b[k] for k in a))
    except (TypeError, ValueError):
        return False


class RenderContext:
    """A renderer for many frames of one scene and style at one size: ``render`` without the
    per-frame set-up and fresh buffers.

    Scene, style, channel set, rasterizer options and the memory check are resolved once, here;
    each frame rasterizes into the previous frame's G-buffer (``rasterize(..., out=gb)``), lends
    the style the previous per-sample RGBA buffer (``ShadeContext.rgba_out``) and composites
    into the same output buffer, so a steady state pays no page faults for them. Every frame is
    bit-identical to ``render(scene, style, width, height, spp, camera=camera)``.

    Parameters
    ----------
    scene, style, width, height, spp, passes
        As for :func:`render` (``passes``: every frame's image carries its passes, new arrays).

    Notes
    -----
    The image a frame returns (and its G-buffer, with ``return_gbuffer=True``) are the context's
    buffers: the next :meth:`render` overwrites them. Pass ``copy=True`` to keep an image.
    """

    def __init__(
        self,
        scene: Any,
        style: Any = None,
        width: int = 512,
        height: int = 512,
        spp: int = 1,
        *,
        passes: bool = False,
    ) -> None:
        width, height, spp = _check_args(width, height, spp, passes=passes)
        self.scene = _still(as_scene(scene))
        self.style = _style_of(style, self.scene)
        self.width, self.height, self.spp = width, height, spp
        self.passes = bool(passes)
        self.channels = self._channels(self.scene, self.style)
        _check_memory(self.scene, self.style, self.channels, width, height, spp)
        self._options = self.style.raster_options(self.scene)
        self._gb = None
        self._out = None
        self._samples: np.ndarray | None = None  # lent to the styles (ShadeContext.rgba_out)

    def _channels(self, scene: Any, style: Style) -> list[str]:
        """The style's channels, with the EXR passes the scene's meshes can give if ``passes``."""
        wanted = set(style.requires(scene))
        if self.passes:
            from .exr import passes_for

            wanted |= passes_for(scene.world_meshes())
        return sorted(wanted)

    def __repr__(self) -> str:
        return (
            f"RenderContext(scene={getattr(self.scene, 'name', '?')!r}, "
            f"style={self.style.name!r}, {self.width}x{self.height}, spp={self.spp})"
        )

    def render(
        self,
        camera: Camera | None = None,
        *,
        progress: Progress | None = None,
        return_gbuffer: bool = False,
        copy: bool = False,
    ) -> Image | tuple[Image, Any]:
        """Render one frame (the scene's camera, or ``camera``); see :func:`render`.

        Parameters
        ----------
        camera : Camera, optional
            Overrides the scene camera for this frame.
        progress : callable(phase, fraction), optional
            As for :func:`render`.
        return_gbuffer : bool
            Also return the G-buffer (the context's: overwritten by the next frame).
        copy : bool
            Return an image with its own pixels instead of the context's output buffer.

        Returns
        -------
        Image
            ``rgba`` (H, W, 4) float32, the context's buffer unless ``copy``.
        """
        t0 = time.perf_counter()
        _check_args(self.width, self.height, self.spp, camera, progress, return_gbuffer, copy)
        cam = camera if camera is not None else self.scene.camera
        image, gb = self._frame(t0, self.scene, self.style, cam, self._gb, progress, copy)
        return (image, gb) if return_gbuffer else image

    def render_frame(
        self,
        scene: Any,
        style: Any = None,
        state: Any = None,
        *,
        progress: Progress | None = None,
        return_gbuffer: bool = False,
        copy: bool = False,
    ) -> tuple[Image, Any] | tuple[Image, Any, Any]:
        """Render one frame of a sequence: its own still scene and style, shaded from ``state``.

        The scene (``scene.at(frame)``: the same meshes, the frame's camera, lights and
        transforms) and style (``style.for_frame(...)``) replace the context's for this frame;
        the buffers are reused while the channels and rasterizer options stay the same. Shading
        is ``style.shade_frame(ctx, state)``, the sequence protocol of
        :class:`~refnpr.styles.Style`: a stateful style gets its state and returns the next one.

        Parameters
        ----------
        scene : Scene
            The frame's still scene (same image size as the context).
        style : Style, optional
            The frame's style (default: the context's).
        state : any
            The state from the previous frame (``style.initial_state()`` on the first).
        progress, return_gbuffer, copy
            As for :meth:`render`.

        Returns
        -------
        (Image, state) or (Image, GBuffer, state)
            The image (the context's buffer unless ``copy``) and the state for the next frame.
        """
        t0 = time.perf_counter()
        _check_args(self.width, self.height, self.spp, None, progress, return_gbuffer, copy)
        scene = as_scene(scene)
        style = self.style if style is None else style_from_spec(style)
        channels = self._channels(scene, style)
        options = style.raster_options(scene)
        gb_out = self._gb
        if channels != self.channels or not _same_options(options, self._options):
            _check_memory(scene, style, channels, self.width, self.height, self.spp)
            self.channels, self._options, gb_out = channels, options, None
        box: list[Any] = [state]

        def shade(ctx: ShadeContext) -> np.ndarray:
            rgba, box[0] = style.shade_frame(ctx, state)
            return rgba

        image, gb = self._frame(t0, scene, style, scene.camera, gb_out, progress, copy, shade)
        return (image, gb, box[0]) if return_gbuffer else (image, box[0])

    def _frame(self, t0, scene, style, cam, gb_out, progress, copy, shade=None):
        """Rasterize into ``gb_out`` (new if None), shade (``shade(ctx) -> rgba``, default
        ``style.shade``) into the per-sample buffer of the previous frame, composite and resolve
        into the output buffer; the image (the buffer itself unless ``copy``) and G-buffer."""
        tell = progress or (lambda phase, fraction: None)
        tell("rasterize", 0.0)
        w, h, spp = self.width, self.height, self.spp
        gb = rasterize(scene, cam, w, h, self.channels, spp, out=gb_out, **self._options)
        t1 = time.perf_counter()
        tell("shade", 0.4)
        shape = gb.sample_shape + (4,)
        if self._samples is None or self._samples.shape != shape:
            self._samples = np.empty(shape, dtype=np.float32)
        kept: dict | None = {} if self.passes else None  # the style's intermediates
        ctx = ShadeContext(gb, scene.with_camera(cam), [self._samples], kept)
        rgba = np.asarray((shade or style.shade)(ctx), dtype=np.float32)
        if rgba.shape != shape:
            raise ValueError(f"style {style.name!r} returned shape {rgba.shape}; expected {shape}")
        t2 = time.perf_counter()
        tell("resolve", 0.9)
        out = composite_resolve(rgba, gb.n, scene.background, out=self._out, style_name=style.name)
        t3 = time.perf_counter()
        timings = {
            "rasterize": t1 - t0,
            "shade": t2 - t1,
            "resolve": t3 - t2,
            "total": t3 - t0,
            **{f"raster.{k}": v for k, v in gb.timings.items()},
        }
        tell("done", 1.0)
        self._gb, self._out = gb, out
        pixel = None
        if self.passes:
            from .exr import pixel_passes

            pixel = pixel_passes(gb, samples=kept)
        image = Image._of_finite(out.copy() if copy else out, timings, pixel)  # checked them
        timings["total"] = time.perf_counter() - t0  # with the copy: what the caller waits for
        return image, gb
