"""Rendering one kit case end to end: rasterize, shade (the style's module), contours,
composite over the background per sample, box-resolve, read back."""

from __future__ import annotations

import importlib
import time
from dataclasses import dataclass, field
from pathlib import Path
from types import ModuleType

import numpy as np

from . import contours as contour_layer
from .context import GL
from .exr import write_exr
from .kit_io import Case
from .png import write_png
from .raster import Uploaded, _attribute_widths, _quantities, channel_layout, rasterize
from .resolve import resolve, to_srgb8

__all__ = ["StyleNotImplemented", "style_module", "render_case", "Result", "write_result"]


class StyleNotImplemented(LookupError):
    """The backend has no module ``refnpr_glsl.styles.<name>``."""


def style_module(name: str) -> ModuleType:
    """``refnpr_glsl.styles.<name>`` (``StyleNotImplemented`` when it does not exist)."""
    if not isinstance(name, str) or not name.isidentifier():
        raise ValueError(f"style: expected a style name, got {name!r}")
    try:
        return importlib.import_module(f"refnpr_glsl.styles.{name}")
    except ModuleNotFoundError as exc:
        if exc.name == f"refnpr_glsl.styles.{name}":
            raise StyleNotImplemented(f"style {name!r} not implemented") from None
        raise


@dataclass
class Result:
    """A rendered case: ``image`` (H, W, 4) float32 linear straight-alpha RGBA for image cases,
    ``channels`` name -> array for G-buffer cases, and seconds per phase."""

    case: str
    image: np.ndarray | None = None
    channels: dict[str, np.ndarray] = field(default_factory=dict)
    timings: dict[str, float] = field(default_factory=dict)


def prepare(gl: GL, case: Case) -> Uploaded:
    """Upload the case's geometry (excluded from the end-to-end timing)."""
    layout = channel_layout(case, case.channels)
    return Uploaded(gl, case, _quantities(layout, set(_attribute_widths(case))))


def render_case(
    gl: GL, case: Case, *, derivatives: str = "analytic", uploaded: Uploaded | None = None
) -> Result:
    """Render ``case`` (image or gbuffer kind) with the GPU; read the result back."""
    t0 = time.perf_counter()
    res = Result(case.name)
    if case.kind == "gbuffer":
        tex = rasterize(gl, case, derivatives=derivatives, uploaded=uploaded)
        t1 = time.perf_counter()
        res.channels = {name: gl.read(t) for name, t in tex.items()}
        for t in tex.values():
            t.release()
        t2 = time.perf_counter()
        res.timings = {"rasterize": t1 - t0, "readback": t2 - t1, "total": t2 - t0}
        return res
    name = case.style_name
    module = style_module(name)
    params = case.params
    channels = list(case.channels)
    if params.get("contours") and "depth" not in channels:
        channels.append("depth")
    gbuffer = rasterize(gl, case, channels, derivatives=derivatives, uploaded=uploaded)
    gl.finish()
    t1 = time.perf_counter()
    rgba = module.shade(gl, case, gbuffer, case.sample_size)
    gl.finish()
    t2 = time.perf_counter()
    if params.get("contours"):
        lined = contour_layer.apply(gl, case, rgba, gbuffer, params["contours"])
        rgba.release()
        rgba = lined
    gl.finish()
    t3 = time.perf_counter()
    pixels = resolve(gl, rgba, case.n, case.background)
    gl.finish()
    t4 = time.perf_counter()
    res.image = gl.read(pixels)
    t5 = time.perf_counter()
    for t in (*gbuffer.values(), rgba, pixels):
        t.release()
    res.timings = {
        "rasterize": t1 - t0,
        "shade": t2 - t1,
        "contours": t3 - t2,
        "resolve": t4 - t3,
        "readback": t5 - t4,
        "total": t5 - t0,
    }
    return res


def write_result(result: Result, out_dir: Path) -> list[Path]:
    """OUT/<name>.png (8-bit sRGB RGBA) and OUT/<name>.exr (linear float RGBA), or
    OUT/<name>/<channel>.npy for G-buffer cases."""
    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    written = []
    if result.image is not None:
        written.append(write_png(out_dir / f"{result.case}.png", to_srgb8(result.image)))
        written.append(write_exr(out_dir / f"{result.case}.exr", result.image))
    if result.channels:
        d = out_dir / result.case
        d.mkdir(parents=True, exist_ok=True)
        for name, arr in result.channels.items():
            p = d / f"{name}.npy"
            np.save(p, arr)
            written.append(p)
    return written
