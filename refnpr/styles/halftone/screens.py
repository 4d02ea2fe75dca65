"""Halftone screens of the ``halftone`` style: TOML-friendly specs -> built, mip-mapped screens
and their tone look-up tables (Freudenberg et al. 2002, secs. 3-4). The kernel samples them
(``_kernels.py``, with :mod:`refnpr.device.sampling`).

A screen spec is a string or a table (scene files, ``--param``):

* ``"engraving"`` or ``{kind = "engraving", profile = "triangle", angle = 90.0, size = 256}``:
  the 1D ramp of sec. 4.1 along ``t = u cos(angle) + v sin(angle)`` (so the
  engraved lines are iso-lines of t; 90 deg: lines of constant v).
* ``"hatching"``, ``"bricks"`` or ``{kind = "strokes", set = "hatching", ...generator options}``:
  the built-in procedural stroke sets of :mod:`refnpr.texture.screens` (sec. 4.2);
  ``{kind = "strokes", layers = ["dark.png", "light.png"], levels = [0.0, 0.5],
  normal_map = "n.png"}`` reads hand-drawn layers (darkest first).
* ``"material"``, a built-in texture name (``"brick"``, ``"grass"``, ...) or an image path, or
  ``{kind = "dither", texture = "brick", window = 16, clip_limit = 0.01, rank_equalize = true,
  tiling = "none"}``: a dither screen, the texture through :func:`refnpr.texture.clahe_pyramid`
  (shared with Veryovka's threshold textures); ``texture = "material"`` (the default) uses each
  object's own ``material.texture``; ``tiling = "periodic"`` makes an image file that does not
  tile repeat without a seam (its periodic component, :func:`refnpr.texture.load_texture`;
  built-in textures tile already).

Every kind accepts ``lighting = true|false``: use the set's normal map for individual stroke
lighting (sec. 5.2) when it has one.
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from refnpr.formulas._validate import to_float
from refnpr.texture import (
    BUILTIN_TEXTURES,
    TILINGS,
    EmbeddedImage,
    MipPyramid,
    clahe_pyramid,
    load_texture,
    sample_level,
)
from refnpr.texture import screens as S

from .._declare import check_number
from .._names import renamed_params

__all__ = [
    "Screen",
    "current_names",
    "normalize_spec",
    "has_normal_map",
    "build_screen",
    "cached_screen",
    "tone_luts",
]

KINDS = ("engraving", "dither", "strokes")
STROKE_SETS = {"hatching": S.hatching_set, "bricks": S.brick_set}
#: Built-in stroke sets that come with a normal map (individual stroke lighting, sec. 5.2).
SETS_WITH_NORMALS = ("bricks",)
_ENGRAVING_KEYS = {"profile": "triangle", "angle": 90.0, "size": 256}
_DITHER_KEYS = {
    "texture": "material",
    "window": 16,
    "clip_limit": 0.01,
    "rank_equalize": True,
    "tiling": "none",
}
#: Deprecated dither keys -> the threshold style's names for the same CLAHE settings.
_DITHER_RENAMED = {"uniform": "rank_equalize"}
_STROKE_FILE_KEYS = ("layers", "levels", "normal_map")
_HOW = (
    "a screen is 'engraving', 'hatching', 'bricks', 'material', a built-in texture name "
    f"{list(BUILTIN_TEXTURES)}, an image path, or a table with kind = {list(KINDS)}"
)


@dataclass(frozen=True, eq=False)
class Screen:
    """A built halftone screen.

    Attributes
    ----------
    kind : {"engraving", "dither", "strokes"}
    pyramid : MipPyramid
        Screen values in [0, 1] per level (engraving: ``(1, size_k)`` along t).
    normals : MipPyramid or None
        RGB-encoded DOT3 normal map (strokes with lighting only).
    direction : (2,) float64 or None
        Engraving only: t = uv . direction.
    """

    kind: str
    pyramid: MipPyramid
    normals: MipPyramid | None = None
    direction: np.ndarray | None = None


def _bad(spec: Any, why: str) -> ValueError:
    return ValueError(f"screen: {why}, got {spec!r}; {_HOW}")


def current_names(spec: Any) -> Any:
    """A screen spec as given, with deprecated keys under their current names (no warning:
    :func:`normalize_spec` warns); for a style's ``params()``."""
    if isinstance(spec, dict) and spec.get("kind") == "dither":
        return renamed_params("screen", spec, _DITHER_RENAMED, warn=False)
    return spec


def normalize_spec(spec: Any) -> dict[str, Any]:
    """A screen spec as a full table (kind and every option), validating keys and values."""
    if isinstance(spec, str):
        if spec == "engraving":
            return {"kind": "engraving", **_ENGRAVING_KEYS, "lighting": True}
        if spec in STROKE_SETS:
            return {"kind": "strokes", "set": spec, "lighting": True}
        if spec == "material" or spec in BUILTIN_TEXTURES or "/" in spec or "." in spec:
            return normalize_spec({"kind": "dither", "texture": spec})
        raise _bad(spec, "unknown screen name")
    if not isinstance(spec, dict):
        raise TypeError(f"screen: expected a name or a table, got {type(spec).__name__} {spec!r}")
    spec = dict(spec)
    kind = spec.pop("kind", None)
    if kind not in KINDS:
        raise _bad(kind, f"a screen table needs kind in {list(KINDS)}")
    lighting = spec.pop("lighting", True)
    if not isinstance(lighting, (bool, np.bool_)):  # 1 and 0 are not flags
        raise TypeError(f"screen.lighting: expected a bool, got {lighting!r}")
    if kind == "engraving":
        out = _with_defaults("engraving", spec, _ENGRAVING_KEYS)
        if out["profile"] not in ("ramp", "triangle"):
            raise ValueError(
                f"screen.profile: expected 'ramp' or 'triangle', got {out['profile']!r}"
            )
        a = out["angle"]
        if isinstance(a, bool) or not isinstance(a, (int, float)):
            raise TypeError(f"screen.angle: expected a number of degrees, got {a!r}")
        if not math.isfinite(to_float("screen.angle", a)):
            raise ValueError(f"screen.angle: expected a finite number of degrees, got {a!r}")
    elif kind == "dither":
        spec = renamed_params("screen", spec, _DITHER_RENAMED)
        out = _with_defaults("dither", spec, _DITHER_KEYS)
        if not isinstance(out["texture"], str) or not out["texture"]:
            raise TypeError(
                f"screen.texture: expected 'material', a built-in texture name or an image path, "
                f"got {out['texture']!r}"
            )
        # CLAHE's settings, named as the screen table's keys (clahe_pyramid checks them too)
        out["window"] = check_number("screen.window", out["window"], integer=True, lo=2)
        out["clip_limit"] = check_number(
            "screen.clip_limit", out["clip_limit"], lo=0.0, lo_open=True, hi=1.0
        )
        if not isinstance(out["rank_equalize"], (bool, np.bool_)):  # 1 and 0 are not flags
            raise TypeError(f"screen.rank_equalize: expected a bool, got {out['rank_equalize']!r}")
        if out["tiling"] not in TILINGS:
            raise ValueError(
                f"screen.tiling: expected one of {list(TILINGS)} ('periodic' makes an image "
                f"that does not tile repeat without a seam), got {out['tiling']!r}"
            )
    else:
        # hand-drawn layers; with a set, ``layers`` is the generator's layer count
        if "layers" in spec and "set" not in spec:
            unknown = sorted(set(spec) - set(_STROKE_FILE_KEYS))
            if unknown:
                raise ValueError(
                    f"screen.{unknown[0]}: unknown key for file stroke layers; valid keys: "
                    f"kind, lighting, {', '.join(_STROKE_FILE_KEYS)}"
                )
            layers = spec["layers"]
            if (
                not isinstance(layers, list)
                or not layers
                or not all(isinstance(p, str) for p in layers)
            ):
                raise TypeError(
                    f"screen.layers: expected a list of image paths (darkest layer first), "
                    f"got {layers!r}"
                )
            out = {
                "layers": list(layers),
                "levels": spec.get("levels"),
                "normal_map": spec.get("normal_map"),
            }
        else:
            name = spec.pop("set", "hatching")
            if name not in STROKE_SETS:
                raise ValueError(
                    f"screen.set: expected one of {sorted(STROKE_SETS)} (or give layers = "
                    f"[paths]), got {name!r}"
                )
            out = {"set": name, **spec}  # generator options, validated when built
    return {"kind": kind, **out, "lighting": bool(lighting)}


def has_normal_map(spec: dict[str, Any]) -> bool:
    """Whether a normalized spec lights its strokes from a normal map (needs a tangent frame)."""
    if spec["kind"] != "strokes" or not spec["lighting"]:
        return False
    if "set" not in spec:
        return spec["normal_map"] is not None
    return spec["set"] in SETS_WITH_NORMALS


def _with_defaults(kind: str, spec: dict, defaults: dict) -> dict:
    unknown = sorted(set(spec) - set(defaults))
    if unknown:
        raise ValueError(
            f"screen.{unknown[0]}: unknown key for a {kind} screen; valid keys: kind, lighting, "
            f"{', '.join(defaults)}"
        )
    return {**defaults, **spec}


def build_screen(spec: dict[str, Any], material_texture: str | None) -> Screen:
    """Build the screen of a normalized spec (``material_texture``: the object's texture, used
    by ``texture = "material"``)."""
    kind = spec["kind"]
    if kind == "engraving":
        pyr = S.engraving_pyramid(spec["size"], profile=spec["profile"])
        a = math.radians(float(spec["angle"]))
        return Screen("engraving", pyr, None, np.array([math.cos(a), math.sin(a)]))
    if kind == "dither":
        name = spec["texture"]
        if name == "material":
            if material_texture is None:
                raise ValueError(
                    "screen: texture = 'material' but the object's material has no texture; "
                    "set material.texture in the scene, or name a texture in the screen spec"
                )
            name = material_texture
        pyr = clahe_pyramid(
            load_texture(name, param="screen", tiling=spec["tiling"]),
            window=spec["window"],
            clip_limit=spec["clip_limit"],
            uniform=spec["rank_equalize"],
        )
        return Screen("dither", pyr)
    if "set" not in spec:
        strokes = S.load_stroke_layers(
            spec["layers"], levels=spec["levels"], normal_map=spec["normal_map"]
        )
    else:
        options = {k: v for k, v in spec.items() if k not in ("kind", "set", "lighting")}
        try:
            strokes = STROKE_SETS[spec["set"]](**options)
        except TypeError as exc:
            raise TypeError(f"screen ({spec['set']!r} options): {exc}") from None
    normals = S.normal_pyramid(strokes) if spec["lighting"] else None
    return Screen("strokes", S.stroke_map_pyramid(strokes), normals)


#: Built screens of specs that read no file, shared by every style instance (``render`` builds a
#: new style per frame; building the hatching set costs about 0.1 s). Bounded; oldest out first.
_BUILT: dict[str, Screen] = {}
_BUILT_MAX = 32


def _reads_no_file(spec: dict[str, Any], material_texture: str | None) -> bool:
    if spec["kind"] == "engraving":
        return True
    if spec["kind"] == "strokes":
        return "set" in spec
    name = material_texture if spec["texture"] == "material" else spec["texture"]
    # an embedded image's text holds its content's digest: the key names the pixels
    return isinstance(name, EmbeddedImage) or (isinstance(name, str) and name in BUILTIN_TEXTURES)


def cached_screen(spec: dict[str, Any], material_texture: str | None) -> Screen:
    """:func:`build_screen`, memoized across calls for specs that read no file (engraving,
    built-in stroke sets, dither screens of built-in textures); file-based specs are rebuilt,
    so an edited image file is read again. The returned screen is shared: do not modify it."""
    if not _reads_no_file(spec, material_texture):
        return build_screen(spec, material_texture)
    key = json.dumps(spec, sort_keys=True) + "|" + str(material_texture)
    screen = _BUILT.get(key)
    if screen is None:
        screen = build_screen(spec, material_texture)
        if len(_BUILT) >= _BUILT_MAX:
            _BUILT.pop(next(iter(_BUILT)))
        _BUILT[key] = screen
    return screen


#: Bins of the tone look-up tables and sub-texel samples per axis used to build them.
LUT_BINS = 2048
LUT_SUBSAMPLES = 4


def tone_luts(pyramid: MipPyramid) -> np.ndarray:
    """Per level, the CDF of the level's *bilinearly interpolated* values, tabulated at
    ``x = linspace(0, 1, LUT_BINS)``: (L, LUT_BINS) float64.

    Rank equalization makes a level's texels uniform, but bilinear interpolation averages
    neighbouring texels and compresses the distribution of the values a sampler returns, so the
    binary threshold then misses the tone by up to ~0.1 at I = 0.1 or 0.9 on coarse noisy levels.
    Mapping a sample through its level's CDF makes the sampled values uniform again. The CDF is
    estimated on a regular grid of ``LUT_SUBSAMPLES ** 2`` points per texel; levels with a single
    texel keep the identity.
    """
    x = np.linspace(0.0, 1.0, LUT_BINS)
    out = np.empty((pyramid.n_levels, LUT_BINS))
    q = LUT_SUBSAMPLES
    for k, lv in enumerate(pyramid.levels):
        rows, cols = lv.shape[:2]
        if rows * cols < 2:
            out[k] = x
            continue
        uu = (np.arange(cols * q) + 0.5) / (cols * q)
        vv = (np.arange(rows * q) + 0.5) / (rows * q)
        grid = np.stack(np.meshgrid(uu, vv), axis=-1).reshape(-1, 2)
        vals = np.sort(sample_level(pyramid, grid, k, dtype=np.float64))
        out[k] = np.searchsorted(vals, x, side="right") / vals.size
    return out
