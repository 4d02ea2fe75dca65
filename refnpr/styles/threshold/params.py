"""Validated parameters of the ``threshold`` style (Veryovka 2002); all TOML-representable."""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass, fields
from typing import Any

import numpy as np

from refnpr.texture import TILINGS

from .._common import check_choice, check_count, check_number, check_uv_scale, warn_unused
from .._names import check_known, renamed_params, warn_deprecated

__all__ = [
    "SOURCES",
    "FILTERS",
    "CLAHE_LEVELS",
    "MIPS",
    "RENAMED",
    "ThresholdParams",
    "parse_params",
]

SOURCES = ("constant", "image", "lines", "stipple")
FILTERS = ("none", "pcf", "analytic")
CLAHE_LEVELS = ("all", "base", "none")
MIPS = ("per_level", "trilinear")
#: Deprecated names -> the names the other styles use for the same thing (accepted with a
#: DeprecationWarning). ``scale`` and ``pcf_levels`` changed form too; see :func:`parse_params`.
RENAMED = {"angles": "directions"}
DEPRECATED = ("scale", "pcf_levels")
_WHERE = "style 'threshold'"


def _bool(name: str, value: Any) -> bool:
    if not isinstance(value, bool):
        raise TypeError(f"{name}: expected a bool (true/false), got {value!r}")
    return bool(value)


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


@dataclass(frozen=True)
class ThresholdParams:
    """Parameters of :class:`refnpr.styles.threshold.ThresholdStyle` (see its docstring)."""

    source: str = "lines"
    n: int = 1
    t: float = 0.5
    specular: bool = True
    specular_threshold: str | float = "texture"
    filter: str = "none"
    samples: int = 4
    strength: float = 1.0
    facing_fade: float = 0.0
    facing_power: float = 1.0
    tone_fade: tuple[float, float] = (0.0, 0.0)
    uv_scale: tuple[float, float] | None = None
    #: Deprecated (use ``uv_scale``): multiplies the material's uv_scale.
    scale: float | None = None
    # image threshold textures (sec. 3.1)
    texture: str | None = None
    window: int = 16
    clip_limit: float = 0.01
    nbins: int = 256
    rank_equalize: bool = True
    clahe_levels: str = "all"
    tiling: str = "none"
    tone_correct: bool = False
    mip: str = "per_level"
    lod_bias: float = 0.0
    # procedural lines and dots (sec. 3.2)
    period: float = 8.0
    directions: tuple[float, ...] = (0.0,)
    onsets: tuple[float, ...] | None = None
    uniform: bool = False
    multiscale: bool = True
    noise: float = 0.0
    noise_scale: float = 4.0
    noise_seed: int = 0
    jitter: float = 0.2
    # bump mapping (Fig. 2, top centre)
    bump: str | None = None
    bump_height: float = 0.02

    def as_dict(self) -> dict[str, Any]:
        """TOML-friendly dict (tuples as lists, None values dropped)."""
        out = {}
        for k, v in asdict(self).items():
            if v is None:
                continue
            out[k] = list(v) if isinstance(v, tuple) else v
        return out


#: The names the style takes (``scale`` is the deprecated form of ``uv_scale``).
PARAMETERS = tuple(sorted({f.name for f in fields(ThresholdParams)} - {"scale"}))


def _directions(value: Any) -> tuple[float, ...]:
    """Hatching directions: 'u' (0 degrees), 'v' (90) or angles in degrees, as for ``tamiss``;
    a list (tuple, 1-D array) of them or a single one."""
    one = isinstance(value, (str, bytes, dict)) or np.ndim(value) == 0
    vals = [value] if one else list(value)
    named = [{"u": 0.0, "v": 90.0}.get(d, d) if isinstance(d, str) else d for d in vals]
    bad = [d for d in named if isinstance(d, str)]
    if bad:
        raise ValueError(
            f"directions: each layer is 'u', 'v' or an angle in degrees from u towards v, "
            f"got {bad[0]!r}"
        )
    return _numbers("directions", named, lo=-360.0, hi=360.0, what="hatching angles, degrees")


def _bump(value: Any) -> str | None:
    if value is not None and (not isinstance(value, str) or not value):
        raise TypeError(
            f"bump: expected a built-in texture name or an image path (str) for the height map, "
            f"got {value!r}"
        )
    return value


def _deprecated_forms(kw: dict[str, Any]) -> dict[str, Any]:
    """Old parameter names whose value changed form: ``pcf_levels`` (2 | 1) is ``mip``
    ("per_level" | "trilinear", the halftone style's name); ``scale`` (a multiplier of the
    material's uv_scale) gives way to ``uv_scale`` (replaces it, as in every other style)."""
    if "pcf_levels" in kw:
        levels = check_count("pcf_levels", kw["pcf_levels"], lo=1, hi=2)
        kw = renamed_params(_WHERE, kw, {"pcf_levels": "mip"})
        kw["mip"] = MIPS[0] if levels == 2 else MIPS[1]
    if "scale" in kw:
        warn_deprecated(
            f"{_WHERE}: parameter 'scale' is deprecated, use 'uv_scale' (one name across styles;"
            " it replaces the material's uv_scale, while 'scale' multiplied it)"
        )
        if kw.get("uv_scale") is not None:
            raise TypeError(
                f"{_WHERE}: got both 'scale' (deprecated) and 'uv_scale'; pass only 'uv_scale'"
            )
    return kw


def _warn_unused(kw: dict[str, Any], source: str, filt: str) -> None:
    """A UserWarning for each parameter given that the chosen source or filter ignores."""
    if kw.get("texture") is not None and source != "image":
        warn_unused(
            "texture", kw["texture"], f"source={source!r}", "remove it or use source='image'"
        )
    if kw.get("tiling", "none") != "none" and source != "image":
        warn_unused(
            "tiling", kw["tiling"], f"source={source!r}", "it applies to image textures only"
        )
    if kw.get("onsets") is not None and source != "lines":
        warn_unused(
            "onsets", kw["onsets"], f"source={source!r}", "onsets order hatching layers only"
        )
    if "jitter" in kw and source != "stipple" and kw["jitter"] != ThresholdParams.jitter:
        warn_unused("jitter", kw["jitter"], f"source={source!r}", "jitter places stipple dots")
    if kw.get("bump") is None and kw.get("bump_height", ThresholdParams.bump_height) != (
        ThresholdParams.bump_height
    ):
        warn_unused("bump_height", kw["bump_height"], "bump=None", "name a height texture in bump")
    if "samples" in kw and filt != "pcf" and kw["samples"] != ThresholdParams.samples:
        warn_unused("samples", kw["samples"], f"filter={filt!r}", "use filter='pcf'")


def parse_params(**kw: Any) -> ThresholdParams:
    """Validate keyword parameters into :class:`ThresholdParams` (clear errors naming each).

    Deprecated names (``angles``, ``pcf_levels``, ``scale``) are accepted with a
    ``DeprecationWarning``.
    """
    kw = _deprecated_forms(renamed_params(_WHERE, kw, RENAMED))
    defaults = ThresholdParams()
    check_known(_WHERE, set(kw) - {"scale"}, PARAMETERS)
    p = {**asdict(defaults), **kw}
    source = check_choice("source", p["source"], SOURCES)
    filt = check_choice("filter", p["filter"], FILTERS)
    if filt == "analytic" and source != "lines":
        raise ValueError(
            f"filter: 'analytic' filtering exists for source='lines' only (got source={source!r});"
            " use filter='pcf' for image and stipple thresholds"
        )
    samples = check_count("samples", p["samples"], lo=1, hi=256)
    if math.isqrt(samples) ** 2 != samples:
        raise ValueError(
            f"samples: expected a square number of threshold samples (1, 4, 9, 16, ...) laid out "
            f"on a k x k grid over the footprint, got {samples}"
        )
    spec_t = p["specular_threshold"]
    if isinstance(spec_t, str):
        if spec_t != "texture":
            raise ValueError(
                f"specular_threshold: expected 'texture' or a number in [0, 1], got {spec_t!r}"
            )
    else:
        spec_t = check_number("specular_threshold", spec_t, lo=0.0, hi=1.0)
    tone_fade = _numbers("tone_fade", p["tone_fade"], lo=0.0, hi=0.5, what="[dark, bright] widths")
    if len(tone_fade) != 2:
        raise ValueError(f"tone_fade: expected two widths [dark, bright], got {list(tone_fade)}")
    texture = p["texture"]
    if texture is not None and (not isinstance(texture, str) or not texture):
        raise TypeError(
            f"texture: expected a built-in texture name or an image path (str), got {texture!r}"
        )
    window = check_count("window", p["window"], lo=2, hi=4096)
    clip_limit = check_number("clip_limit", p["clip_limit"], lo=0.0, lo_open=True, hi=1.0)
    directions = _directions(p["directions"])
    onsets = p["onsets"]
    if onsets is not None:
        onsets = _numbers("onsets", onsets, lo=0.0, hi=1.0, what="onset intensity per direction")
        if len(onsets) != len(directions):
            raise ValueError(
                f"onsets: expected one onset per direction ({len(directions)}), got {list(onsets)}"
            )
        if min(onsets) <= 0.0 or max(onsets) != 1.0:
            raise ValueError(
                f"onsets: expected values in (0, 1] whose largest is 1 (the first layer shows at "
                f"every tone below white), got {list(onsets)}"
            )
    _warn_unused(kw, source, filt)
    noise_seed = p["noise_seed"]
    if isinstance(noise_seed, bool) or not isinstance(noise_seed, int):
        raise TypeError(f"noise_seed: expected an integer, got {noise_seed!r}")
    return ThresholdParams(
        source=source,
        n=check_count("n", p["n"], lo=1, hi=256),
        t=check_number("t", p["t"], lo=0.0, hi=1.0),
        specular=_bool("specular", p["specular"]),
        specular_threshold=spec_t,
        filter=filt,
        samples=samples,
        strength=check_number("strength", p["strength"], lo=0.0, hi=1.0),
        facing_fade=check_number("facing_fade", p["facing_fade"], lo=0.0, hi=1.0),
        facing_power=check_number("facing_power", p["facing_power"], lo=0.0, lo_open=True),
        tone_fade=(tone_fade[0], tone_fade[1]),
        uv_scale=check_uv_scale("uv_scale", p["uv_scale"]),
        scale=None if p["scale"] is None else check_number("scale", p["scale"], lo=1e-6, hi=1e6),
        texture=texture,
        window=window,
        clip_limit=clip_limit,
        nbins=check_count("nbins", p["nbins"], lo=2, hi=65536),
        rank_equalize=_bool("rank_equalize", p["rank_equalize"]),
        clahe_levels=check_choice("clahe_levels", p["clahe_levels"], CLAHE_LEVELS),
        tiling=check_choice("tiling", p["tiling"], TILINGS),
        tone_correct=_bool("tone_correct", p["tone_correct"]),
        mip=check_choice("mip", p["mip"], MIPS),
        lod_bias=check_number("lod_bias", p["lod_bias"], lo=-16.0, hi=16.0),
        period=check_number("period", p["period"], lo=0.0, lo_open=True),
        directions=directions,
        onsets=onsets,
        uniform=_bool("uniform", p["uniform"]),
        multiscale=_bool("multiscale", p["multiscale"]),
        noise=check_number("noise", p["noise"], lo=0.0, hi=1.0),
        noise_scale=check_number(
            "noise_scale", p["noise_scale"], lo=0.0, lo_open=True, hi=MAX_NOISE_SCALE
        ),
        noise_seed=int(noise_seed),
        jitter=check_number("jitter", p["jitter"], lo=0.0, hi=0.4),
        bump=_bump(p["bump"]),
        bump_height=check_number("bump_height", p["bump_height"], lo=-1e3, hi=1e3),
    )
