"""The ``halftone`` style's parameters, each declared once (:data:`PARAMS`), and the parsers of
its tables (per-object settings, indication maps, colours)."""

from __future__ import annotations

from pathlib import Path
from typing import Any, NamedTuple

import numpy as np

from refnpr.formulas._validate import BEYOND_FLOAT_RANGE

from .._common import check_uv_scale
from .._declare import Param, Params, number_or, rgb_param
from . import screens as HS

__all__ = ["PARAMS", "Given", "parse_indication", "parse_objects"]

#: The keys of a per-object table (``objects = {name = {...}}``).
OBJECT_KEYS = ("screen", "indication", "indication_scale", "uv_scale")


class Given(NamedTuple):
    """A table parameter parsed (``value``, what the style reads) beside the form the caller
    gave it in (``given``, with current key names: what ``params()`` shows)."""

    value: Any
    given: Any


def parse_indication(value: Any, where: str = "indication") -> np.ndarray | None:
    """An indication map: None, a (rows, cols) nested list of signed values in [-1, 1], or a
    gray image path (value ``2 g - 1``, so mid-grey is 0). Returns (rows, cols) float64."""
    if value is None:
        return None
    if isinstance(value, str):
        path = Path(value)
        if not path.is_file():
            raise ValueError(
                f"{where}: {value!r} is not an existing image file; give a gray PNG (mid-grey = "
                "no change) or a nested list of signed values"
            )
        from refnpr.texture import load_texture

        return 2.0 * load_texture(path, param="indication").astype(np.float64) - 1.0
    try:
        arr = np.array(value, dtype=np.float64)
    except OverflowError:
        raise ValueError(
            f"{where}: holds {BEYOND_FLOAT_RANGE}; expected signed values in "
            "[-1, 1] (0 = no change, > 0 lighter, < 0 darker)"
        ) from None
    except (TypeError, ValueError):
        raise TypeError(
            f"{where}: expected a nested list of numbers (rows of a low-resolution signed map) "
            f"or an image path, got {value!r}"
        ) from None
    if arr.ndim == 1:
        arr = arr[None, :]
    if arr.ndim != 2 or arr.size == 0:
        raise ValueError(
            f"{where}: expected rows of equal length (a 2-D map), got shape {arr.shape}"
        )
    if not np.all(np.isfinite(arr)) or np.any(np.abs(arr) > 1.0):
        raise ValueError(
            f"{where}: expected signed values in [-1, 1] (0 = no change, > 0 lighter, < 0 darker), "
            f"got range [{arr.min()}, {arr.max()}]"
        )
    return arr


def parse_objects(objects: Any) -> dict[str, dict[str, Any]]:
    """Per-object settings by object name, each entry's values parsed (screen spec normalized,
    indication map as an array, scales as ``(su, sv)``)."""
    if objects is None:
        return {}
    if not isinstance(objects, dict):
        raise TypeError(
            f"objects: expected a table {{object name = {{screen = ..., indication = ...}}}}, "
            f"got {type(objects).__name__}"
        )
    out = {}
    for name, table in objects.items():
        if not isinstance(table, dict):
            raise TypeError(f"objects.{name}: expected a table, got {table!r}")
        unknown = sorted(set(table) - set(OBJECT_KEYS))
        if unknown:
            raise ValueError(
                f"objects.{name}.{unknown[0]}: unknown key; valid keys: {', '.join(OBJECT_KEYS)}"
            )
        entry: dict[str, Any] = {}
        if "screen" in table:
            entry["screen"] = HS.normalize_spec(table["screen"])
        if "indication" in table:
            entry["indication"] = parse_indication(
                table["indication"], f"objects.{name}.indication"
            )
        for key in ("indication_scale", "uv_scale"):
            if key in table:
                entry[key] = check_uv_scale(f"objects.{name}.{key}", table[key])
        out[str(name)] = entry
    return out


def _objects(name: str, value: Any) -> Given | None:
    if value is None:
        return None
    parsed = parse_objects(value)  # validates: a table of tables
    given = {
        k: {**v, "screen": HS.current_names(v["screen"])} if "screen" in v else v
        for k, v in value.items()
    }
    return Given(parsed, given)


def _screen(name: str, value: Any) -> Given:
    return Given(HS.normalize_spec(value), HS.current_names(value))


def _indication(name: str, value: Any) -> Given | None:
    return None if value is None else Given(parse_indication(value), value)


def _uv_scale(name: str, value: Any) -> Given | None:
    scale = check_uv_scale(name, value)
    return None if scale is None else Given(scale, value)


def _given(name: str, default: Any, doc: str, parse: Any, accepts: str) -> Param:
    """A table parameter parsed to a :class:`Given`; ``params()`` shows the form given."""
    return Param(
        name, default, doc, kind="any", parse=parse, summary=lambda v: v.given, accepts=accepts
    )


_SMOOTH = {"threshold": ("smooth",)}

PARAMS = Params(
    "halftone",
    Param(
        "threshold",
        "smooth",
        "smooth: clip(1 - c (1 - screen - I), 0, 1) (sec. 3.2); binary: white iff screen + I > 1 "
        "(sec. 3.1, the mux form)",
        kind="choice",
        choices=("smooth", "binary"),
    ),
    Param(
        "c",
        4.0,
        "slope of the smooth threshold (the paper's 4); auto: per sample c = 1 / fwidth(screen), "
        "the screen's change over one sample step, with the ramp centred (an extension: the grey "
        "ramp spans the sample's footprint)",
        kind="any",
        parse=number_or("auto", lo=0.0, lo_open=True),
        accepts='float > 0 or "auto"',
        used_when=_SMOOTH,
    ),
    Param(
        "centred",
        False,
        "centre the smooth ramp on the binary threshold (no tone bias; the paper's one-sided ramp "
        "lightens the mean tone by 1/(2c))",
        kind="bool",
        used_when=_SMOOTH,
    ),
    _given(
        "screen",
        "hatching",
        "default screen of every object: engraving, hatching, bricks, material, a texture name "
        'or path, or a table such as {kind = "engraving", profile = "triangle", angle = 90} '
        "(docs/halftone.md, Screens)",
        _screen,
        "str or table",
    ),
    _given(
        "uv_scale",
        None,
        "multiplies uv before the screen lookup, in place of each material's uv_scale (none: "
        "the material's)",
        _uv_scale,
        "float or 2 floats",
    ),
    _given(
        "objects",
        None,
        "per-object settings by object name: {name = {screen, indication, indication_scale, "
        "uv_scale}} (indication_scale multiplies uv before the indication lookup)",
        _objects,
        "table",
    ),
    _given(
        "indication",
        None,
        "default indication map (sec. 5.1): a low-resolution signed map in [-1, 1] over the "
        "object's uv in [0, 1]^2 (before uv_scale; row j covers v in [j/rows, (j+1)/rows)), or a "
        "grey image path (2 g - 1); added to I",
        _indication,
        "nested list or path",
    ),
    Param(
        "specular",
        True,
        "include the specular term (Blinn-Phong) in I (needs positions)",
        kind="bool",
    ),
    rgb_param("ink", (0.0, 0.0, 0.0), "colour of output 0 (linear RGB)"),
    rgb_param("paper", (1.0, 1.0, 1.0), "colour of output 1 (linear RGB)"),
    Param("lod_bias", 0.0, "added to every LOD", lo=-16.0, hi=16.0, unit="mip levels"),
    Param(
        "sample_lod",
        False,
        "false: every sample of a pixel uses the pixel's LOD, so n x n supersampling "
        "anti-aliases the same picture; true: each sample its own footprint (pixel LOD - log2 n), "
        "as rendering at n times the resolution",
        kind="bool",
    ),
    Param(
        "mip",
        "trilinear",
        "trilinear: threshold the trilinearly filtered screen (the paper, as texture hardware "
        "does); per_level: threshold the two bilinear level samples separately and blend the "
        "results with the trilinear weight (Veryovka's filtered thresholding)",
        kind="choice",
        choices=("trilinear", "per_level"),
    ),
    Param(
        "tone_correct",
        False,
        "map each bilinear level sample through the CDF of that level's interpolated values, "
        "keeping the tone under filtering; implies per-level sampling; engraving and dither "
        "screens only",
        kind="bool",
    ),
    Param(
        "anisotropy",
        1,
        "largest anisotropic filtering ratio (GL_TEXTURE_MAX_ANISOTROPY); 1: the paper's "
        "isotropic LOD; N > 1: the level of the footprint's minor axis and up to N trilinear "
        "probes along its major axis (engraving screens stay isotropic)",
        kind="int",
        lo=1,
        hi=16,
    ),
    Param(
        "show",
        "color",
        "color: the halftoned image; screen: the filtered screen value (Fig. 3 (d), Fig. 8); "
        "normals: the RGB-encoded stroke normal map (Fig. 8); intensity: the target intensity I "
        "after the indication map (Fig. 4 (b)); raw values as the linear grey whose sRGB "
        "encoding is the value",
        kind="choice",
        choices=("color", "screen", "normals", "intensity"),
    ),
    renamed={"equalize": "tone_correct"},
    frame=("slope", "fwidth", "lod_offset", "step", "ink_rgb", "paper_rgb"),
    module=__name__,
)
