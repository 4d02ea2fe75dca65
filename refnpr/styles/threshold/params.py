"""The ``threshold`` style's parameters (Veryovka 2002), each declared once: :data:`PARAMS`.

Checks between parameters (analytic filtering needs lines, one onset per direction) are the
style's (:func:`checked`); the deprecated forms ``scale`` and ``pcf_levels`` are converted by
:func:`deprecated_forms` before the declaration validates the rest.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from refnpr.texture import TILINGS

from .._common import check_uv_scale
from .._declare import NOT_NONE, Param, Params, check_number, number_or
from .._names import renamed_params, warn_deprecated

__all__ = ["PARAMS", "SOURCES", "FILTERS", "MIPS", "deprecated_forms", "checked"]

SOURCES = ("constant", "image", "lines", "stipple")
FILTERS = ("none", "pcf", "analytic")
CLAHE_LEVELS = ("all", "base", "none")
MIPS = ("per_level", "trilinear")
#: Names whose value changed form, converted by :func:`deprecated_forms` (with a warning).
DEPRECATED = ("scale", "pcf_levels")
_WHERE = "style 'threshold'"
#: Most hatching layers (``directions``): each is a full threshold pass per sample.
MAX_LAYERS = 64
#: Largest ``noise_scale`` (noise cells per texture unit) and deprecated ``scale``: the noise
#: lattice coordinates uv * uv_scale * noise_scale must stay exact integers in float64.
MAX_NOISE_SCALE = 1e6


def _numbers(
    name: str, value: Any, *, lo: float, hi: float, what: str, most: int = MAX_LAYERS
) -> tuple[float, ...]:
    if isinstance(value, (str, bytes, dict)) or not hasattr(value, "__len__"):
        raise TypeError(f"{name}: expected a list of numbers ({what}), got {value!r}")
    if len(value) > most:
        raise ValueError(
            f"{name}: expected at most {most} values ({what}), got a list of {len(value)}"
        )
    out = tuple(check_number(f"{name}[{i}]", x, lo=lo, hi=hi) for i, x in enumerate(value))
    if not out:
        raise ValueError(f"{name}: expected at least one value ({what}), got an empty list")
    return out


def _directions(name: str, value: Any) -> tuple[float, ...]:
    """Hatching directions: 'u' (0 degrees), 'v' (90) or angles in degrees, as for ``tamiss``;
    a list (tuple, 1-D array) of them or a single one."""
    one = isinstance(value, (str, bytes, dict)) or np.ndim(value) == 0
    vals = [value] if one else list(value)
    named = [{"u": 0.0, "v": 90.0}.get(d, d) if isinstance(d, str) else d for d in vals]
    bad = [d for d in named if isinstance(d, str)]
    if bad:
        raise ValueError(
            f"{name}: each layer is 'u', 'v' or an angle in degrees from u towards v, "
            f"got {bad[0]!r}"
        )
    return _numbers(name, named, lo=-360.0, hi=360.0, what="hatching angles, degrees")


def _onsets(name: str, value: Any) -> tuple[float, ...]:
    onsets = _numbers(name, value, lo=0.0, hi=1.0, what="onset intensity per direction")
    if min(onsets) <= 0.0 or max(onsets) != 1.0:
        raise ValueError(
            f"{name}: expected values in (0, 1] whose largest is 1 (the first layer shows at "
            f"every tone below white), got {list(onsets)}"
        )
    return onsets


def _tone_fade(name: str, value: Any) -> tuple[float, float]:
    widths = _numbers(name, value, lo=0.0, hi=0.5, what="[dark, bright] widths")
    if len(widths) != 2:
        raise ValueError(f"{name}: expected two widths [dark, bright], got {list(widths)}")
    return widths[0], widths[1]


def _samples(name: str, value: int) -> int:
    if math.isqrt(value) ** 2 != value:
        raise ValueError(
            f"{name}: expected a square number of threshold samples (1, 4, 9, 16, ...) laid out "
            f"on a k x k grid over the footprint, got {value}"
        )
    return value


def _texture(name: str, value: Any) -> str:
    if not isinstance(value, str) or not value:
        what = " for the height map" if name == "bump" else ""
        raise TypeError(
            f"{name}: expected a built-in texture name or an image path (str){what}, got {value!r}"
        )
    return value


def _pyramid(name: str, value: Any) -> Any:
    from refnpr.texture import MipPyramid

    if not isinstance(value, MipPyramid):
        raise TypeError(
            f"{name}: expected a refnpr.texture.MipPyramid (clahe_pyramid(...)), got "
            f"{type(value).__name__}"
        )
    if value.channels != 1:
        raise ValueError(f"{name}: threshold pyramids are gray, got {value.channels} channels")
    return value


_IMAGE = {"source": ("image",)}
_LINES = {"source": ("lines",)}
_SCREENS = {"source": ("lines", "stipple")}  # the procedural sources: eq. 5's scale

PARAMS = Params(
    "threshold",
    Param(
        "source",
        "lines",
        "where thresholds come from: the constant t (the toon step), an image threshold "
        "texture (texture, else each material's; sec. 3.1), multi-scale lines (sec. 3.2) or "
        "stipple dots (Fig. 4)",
        kind="choice",
        choices=SOURCES,
    ),
    Param("n", 1, "steps of T_n (eq. 4): n + 1 tones", kind="int", lo=1, hi=256),
    Param(
        "t",
        0.5,
        "threshold: source constant, untextured objects of image",
        lo=0.0,
        hi=1.0,
        used_when={"source": ("constant", "image")},
    ),
    Param("specular", True, "add the thresholded specular term (needs positions)", kind="bool"),
    Param(
        "specular_threshold",
        "texture",
        "threshold the specular term against the same texture, or against this constant",
        kind="any",
        parse=number_or("texture", lo=0.0, hi=1.0),
        accepts='"texture" or float in [0, 1]',
    ),
    Param(
        "filter",
        "none",
        "none: one threshold per sample (binary); pcf: samples thresholds over the footprint, "
        "results averaged (images: at two mip levels each, sec. 4); analytic: exact box filter "
        "of the thresholded lines (source lines only)",
        kind="choice",
        choices=FILTERS,
    ),
    Param(
        "samples",
        4,
        "threshold samples of pcf, on a k x k grid over the footprint (a square: 1, 4, 9, ...)",
        kind="int",
        lo=1,
        hi=256,
        parse=_samples,
        used_when={"filter": ("pcf",)},
    ),
    Param("strength", 1.0, "blend from eq. 1 (0) to eq. 2 (1) (sec. 5)", lo=0.0, hi=1.0),
    Param(
        "facing_fade",
        0.0,
        "orientation fade: strength times 1 - facing_fade |n.v|^facing_power (Fig. 5 centre)",
        lo=0.0,
        hi=1.0,
    ),
    Param("facing_power", 1.0, "exponent of the orientation fade", lo=0.0, lo_open=True),
    Param(
        "tone_fade",
        (0.0, 0.0),
        "illumination fade: widths [dark, bright] in [0, 0.5] of the smoothsteps to no effect "
        "at x = 0 and x = 1 (Fig. 5 right)",
        kind="any",
        parse=_tone_fade,
        accepts="2 floats",
    ),
    Param(
        "uv_scale",
        None,
        "multiplies texture coordinates in place of each material's uv_scale (none: the "
        "materials'); deprecated: scale, which multiplied the material's",
        kind="any",
        parse=check_uv_scale,
        accepts="float or 2 floats",
    ),
    Param(
        "texture",
        None,
        "image threshold texture (built-in name or path) for every object (none: the materials')",
        kind="any",
        parse=_texture,
        accepts="str",
        used_when=_IMAGE,
    ),
    Param(
        "window",
        16,
        "CLAHE window w in texels (sec. 3.1), on the torus: contextual regions wrap around, so "
        "every level tiles",
        kind="int",
        lo=2,
        hi=4096,
        used_when=_IMAGE,
    ),
    Param("clip_limit", 0.01, "CLAHE clip limit", lo=0.0, lo_open=True, hi=1.0, used_when=_IMAGE),
    Param("nbins", 256, "CLAHE histogram bins", kind="int", lo=2, hi=65536, used_when=_IMAGE),
    Param(
        "rank_equalize",
        True,
        "make each CLAHE level exactly uniform (clahe_pyramid(uniform=True))",
        kind="bool",
        used_when=_IMAGE,
    ),
    Param(
        "clahe_levels",
        "all",
        "CLAHE on every mip level (sec. 3.1), on level 0 only (plain mip-map, Fig. 3 right "
        "wall) or not at all (raw image, Fig. 2 top right)",
        kind="choice",
        choices=CLAHE_LEVELS,
        used_when=_IMAGE,
    ),
    Param(
        "tiling",
        "none",
        "how an image file is made to repeat before CLAHE: periodic uses its periodic "
        "component (Moisan 2011), so a photograph whose borders differ tiles without a seam",
        kind="choice",
        choices=TILINGS,
        used_when=_IMAGE,
    ),
    Param(
        "tone_correct",
        False,
        "map each level's bilinear threshold samples through that level's interpolant CDF "
        "(exact tone per level; refnpr's addition, see below)",
        kind="bool",
        used_when=_IMAGE,
    ),
    Param(
        "mip",
        "per_level",
        "image pcf: threshold every footprint sample at the two mip levels and blend (sec. 4), "
        "or against one trilinear threshold; deprecated: pcf_levels = 2 | 1",
        kind="choice",
        choices=MIPS,
        used_when={"source": ("image",), "filter": ("pcf",)},
    ),
    Param("lod_bias", 0.0, "added to the mip LOD", lo=-16.0, hi=16.0, used_when=_IMAGE),
    Param(
        "period",
        8.0,
        "line period w of eq. 5 (lines and dots; the screen period lies in [w, 2 w))",
        lo=0.0,
        lo_open=True,
        unit="px",
        used_when=_SCREENS,
    ),
    Param(
        "directions",
        (0.0,),
        "hatching directions in texture space: u (0, lines parallel to u), v (90) or angles; "
        "several give cross-hatching; deprecated: angles",
        kind="any",
        parse=_directions,
        unit="degrees",
        accepts="u, v, float or a list",
        used_when=_LINES,
    ),
    Param(
        "onsets",
        None,
        "per direction, the intensity below which that layer appears (the largest 1; none: all 1)",
        kind="any",
        parse=_onsets,
        accepts="list of floats in (0, 1]",
        used_when=_LINES,
    ),
    Param(
        "uniform",
        False,
        "tone-preserving multi-scale blend (lines: multiscale_line(uniform=True); dots: the "
        "tone table) instead of eq. 8, which drifts in tone between integer scales",
        kind="bool",
        used_when=_SCREENS,
    ),
    Param(
        "multiscale",
        True,
        "eqs. 7-8's transition between dyadic scales; false floors the scale (eq. 6 alone: "
        "lines pop where the scale crosses an integer)",
        kind="bool",
        used_when=_SCREENS,
    ),
    Param(
        "noise",
        0.0,
        "amplitude of the lines' phase modulation (sec. 3.2)",
        lo=0.0,
        hi=1.0,
        unit="periods",
        used_when=_LINES,
    ),
    Param(
        "noise_scale",
        4.0,
        "value-noise cells per texture unit",
        lo=0.0,
        lo_open=True,
        hi=MAX_NOISE_SCALE,
        used_when=_LINES,
    ),
    Param(
        "noise_seed",
        0,
        "seed of the line noise and of the stipple's dot placement (its low 32 bits)",
        kind="int",
        record=False,
        used_when=_SCREENS,
    ),
    Param(
        "jitter",
        0.2,
        "stipple: dot offsets (rows of dots at random phases, each dot up to jitter off its "
        "lattice point; 0: a rectangular lattice per level)",
        lo=0.0,
        hi=0.4,
        unit="tiles",
        used_when={"source": ("stipple",)},
    ),
    Param(
        "bump",
        None,
        "a height texture (built-in name or path) bump-mapping the normals before shading: "
        "the alternative to threshold textures of Fig. 2 (top centre), usually with source "
        "constant",
        kind="any",
        parse=_texture,
        accepts="str",
    ),
    Param(
        "bump_height",
        0.02,
        "world units per unit of bump texture value (negative: dents)",
        lo=-1e3,
        hi=1e3,
        unit="world units",
        used_when={"bump": NOT_NONE},
    ),
    Param(
        "pyramid",
        None,
        "a prebuilt threshold pyramid (clahe_pyramid(...)) for every object, overriding "
        "texture (Python only)",
        kind="any",
        parse=_pyramid,
        summary=lambda _: "prebuilt",
        accepts="MipPyramid",
    ),
    renamed={"angles": "directions"},
    frame=("dark", "bright", "spec_t", "log2_w", "seed", "n_sub", "has_grad"),
    module=__name__,
)


def deprecated_forms(kw: dict[str, Any]) -> tuple[dict[str, Any], float | None]:
    """Old parameter names whose value changed form: ``pcf_levels`` (2 | 1) is ``mip``
    ("per_level" | "trilinear", the halftone style's name); ``scale`` (a multiplier of the
    material's uv_scale, returned apart) gives way to ``uv_scale`` (replaces it, as in every
    other style). Both with a DeprecationWarning."""
    kw = dict(kw)
    if "pcf_levels" in kw:
        levels = check_number("pcf_levels", kw["pcf_levels"], integer=True, lo=1, hi=2)
        kw = renamed_params(_WHERE, kw, {"pcf_levels": "mip"})
        kw["mip"] = MIPS[0] if levels == 2 else MIPS[1]
    scale = None
    if "scale" in kw:
        warn_deprecated(
            f"{_WHERE}: parameter 'scale' is deprecated, use 'uv_scale' (one name across styles;"
            " it replaces the material's uv_scale, while 'scale' multiplied it)"
        )
        if kw.get("uv_scale") is not None:
            raise TypeError(
                f"{_WHERE}: got both 'scale' (deprecated) and 'uv_scale'; pass only 'uv_scale'"
            )
        scale = kw.pop("scale")
        if scale is not None:
            scale = check_number("scale", scale, lo=1e-6, hi=MAX_NOISE_SCALE)
    return kw, scale


def checked(p: Any) -> Any:
    """The checks between parameters of validated values ``p``."""
    if p.filter == "analytic" and p.source != "lines":
        raise ValueError(
            f"filter: 'analytic' filtering exists for source='lines' only (got source="
            f"{p.source!r}); use filter='pcf' for image and stipple thresholds"
        )
    if p.onsets is not None and len(p.onsets) != len(p.directions):
        raise ValueError(
            f"onsets: expected one onset per direction ({len(p.directions)}), got {list(p.onsets)}"
        )
    return p
