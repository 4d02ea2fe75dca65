"""``render(scene, style, ...)``: rasterize exactly what the style needs, shade, resolve."""

from __future__ import annotations

import math
import time
from collections.abc import Callable
from typing import Any

import numpy as np

from . import _memory
from .image import Image
from .raster import Camera, rasterize
from .raster.rasterize import attribute_widths
from .scenes._params import check_int
from .styles import ShadeContext, Style, style_from_spec

__all__ = ["render", "required_channels", "as_scene", "DEFAULT_STYLE"]

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


def _style_of(style: Any, scene: Any) -> Style:
    if style is None:
        spec = getattr(scene, "style", None) or DEFAULT_STYLE
        return style_from_spec(spec)
    return style_from_spec(style)


def _check_args(width: Any, height: Any, spp: Any, camera: Any, progress: Any, gbuf: Any):
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
    if not isinstance(gbuf, (bool, np.bool_)):
        raise TypeError(f"return_gbuffer: expected a bool, got {type(gbuf).__name__} {gbuf!r}")
    return width, height, spp


def _check_memory(scene: Any, style: Style, channels, width: int, height: int, spp: int):
    """Refuse a render whose sample grid would not fit, before the rasterizer allocates."""
    if spp > _memory.MAX_SPP or math.isqrt(spp) ** 2 != spp:
        return  # rasterize says what is wrong with spp
    meshes = list(scene.world_meshes())  # memoized per object: rasterize reuses them
    attrs = attribute_widths(meshes) if meshes else {}
    parts = _memory.render_bytes(width, height, spp, channels, style.name, attributes=attrs)
    _memory.check_fits(width, height, spp, parts)


def required_channels(scene: Any, style: Any = None) -> frozenset[str]:
    """The G-buffer channels ``render`` will ask the rasterizer for (the style's ``requires``)."""
    scene = as_scene(scene)
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

    Returns
    -------
    Image
        ``rgba`` (H, W, 4) float32 linear straight-alpha, composited over ``scene.background``.
    """
    t0 = time.perf_counter()
    width, height, spp = _check_args(width, height, spp, camera, progress, return_gbuffer)
    scene = as_scene(scene)
    style = _style_of(style, scene)
    cam = camera if camera is not None else scene.camera
    channels = sorted(style.requires(scene))
    _check_memory(scene, style, channels, width, height, spp)
    if progress is not None:
        progress("rasterize", 0.0)
    gb = rasterize(scene, cam, width, height, channels, spp, **style.raster_options(scene))
    t1 = time.perf_counter()
    if progress is not None:
        progress("shade", 0.4)
    rgba = np.asarray(style.shade(ShadeContext(gb, scene.with_camera(cam))), dtype=np.float32)
    if rgba.shape != gb.sample_shape + (4,):
        raise ValueError(
            f"style {style.name!r} returned shape {rgba.shape}; expected {gb.sample_shape + (4,)}"
        )
    if not np.all(np.isfinite(rgba)):
        raise ValueError(f"style {style.name!r} produced NaN or inf; this is a bug in the style")
    t2 = time.perf_counter()
    if progress is not None:
        progress("resolve", 0.9)
    # composite per sample (premultiplied "over" the background), box-resolve, unpremultiply
    bg = np.asarray(scene.background, dtype=np.float64)
    a = rgba[..., 3:4].astype(np.float64)
    premult = np.concatenate([rgba[..., :3] * a, a], axis=-1)
    bg_premult = np.concatenate([bg[:3] * bg[3], bg[3:4]])
    over = premult + bg_premult * (1.0 - a)
    res = gb.resolve(over)
    alpha = res[..., 3:4]
    rgb = np.divide(res[..., :3], alpha, out=np.zeros_like(res[..., :3]), where=alpha > 0)
    out = np.concatenate([rgb, alpha], axis=-1).astype(np.float32)
    t3 = time.perf_counter()
    timings = {
        "rasterize": t1 - t0,
        "shade": t2 - t1,
        "resolve": t3 - t2,
        "total": t3 - t0,
        **{f"raster.{k}": v for k, v in gb.timings.items()},
    }
    if progress is not None:
        progress("done", 1.0)
    image = Image(out, timings)
    return (image, gb) if return_gbuffer else image
