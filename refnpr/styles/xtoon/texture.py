"""The X-Toon style's ``texture`` parameter: a 2D toon texture from a preset, an image, a recipe
table or an array, always returned as ``(rows, cols, 4)`` float32 linear RGBA, oriented as
:func:`refnpr.formulas.xtoon.toon_lookup` reads it (row index growing with D, column index with
tone). An image file is read the same way, row 0 being the top row of the file; pictures drawn
like the paper's figures (D = 1 at the top) need ``{"image": path, "flip": true}``.
"""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path
from typing import Any

import numpy as np

from refnpr.formulas import xtoon
from refnpr.formulas._validate import BEYOND_FLOAT_RANGE
from refnpr.image import srgb_to_linear

from .presets import COLS, PRESETS, ROWS, as_rgba, band_ramp, per_texel

__all__ = ["RECIPES", "resolve_texture"]

#: Recipe name of a ``{"recipe": ...}`` table -> formula-layer builder.
RECIPES = {
    "blur": xtoon.toon_texture_blur,
    "levels": xtoon.toon_texture_levels,
    "receding": xtoon.toon_texture_receding,
    "fade": xtoon.toon_texture_fade,
    "hue": xtoon.toon_texture_hue,
    "backlight": xtoon.toon_texture_backlight,
    "plastic": xtoon.toon_texture_plastic,
    "metal": xtoon.toon_texture_metal,
}


def _how() -> str:
    return (
        f"pass a preset name ({', '.join(sorted(PRESETS))}), an image path, a table {{'recipe': "
        "..., 'ramp': [...]} or {'image': path}, or an array (rows, cols[, C]) whose row index "
        "grows with detail D"
    )


def _check_array(tex: Any, name: str) -> np.ndarray:
    if np.iscomplexobj(tex):  # np.asarray(..., float64) would drop the imaginary part
        raise TypeError(f"{name}: expected a real texture array, got a complex one; {_how()}")
    try:
        a = np.asarray(tex, dtype=np.float64)
    except OverflowError:
        raise ValueError(
            f"{name}: holds {BEYOND_FLOAT_RANGE}; texel values lie in [0, 1] (linear RGB(A))"
        ) from None
    except (TypeError, ValueError) as exc:
        raise TypeError(f"{name}: expected a numeric texture array, got {tex!r}; {_how()}") from exc
    if (
        a.ndim not in (2, 3)
        or a.shape[0] < 1
        or a.shape[1] < 1
        or (a.ndim == 3 and not 1 <= a.shape[2] <= 4)
    ):
        raise ValueError(
            f"{name}: expected a 2D toon texture of shape (rows, cols) or (rows, cols, C) with "
            f"C in 1..4 (rows: detail D, cols: tone), got shape {a.shape}; a 1D ramp r becomes "
            "a texture with r[None, :] (constant along D)"
        )
    if not np.all(np.isfinite(a)) or a.min() < 0.0 or a.max() > 1.0:
        raise ValueError(
            f"{name}: texel values must be finite and lie in [0, 1] (linear RGB(A)), got range "
            f"[{np.nanmin(a)}, {np.nanmax(a)}]; rescale the texture"
        )
    return a


def _image(path: Any, *, flip: bool, srgb: bool, name: str) -> np.ndarray:
    from refnpr.texture import load_texture

    p = Path(path)
    if not p.is_file():
        raise ValueError(f"{name}: image file {str(path)!r} does not exist; {_how()}")
    img = load_texture(p, gray=False, param=name).astype(np.float64)
    img = img[..., :4] if img.ndim == 3 else img[..., None]
    if srgb:  # colour channels are sRGB-encoded in image files; alpha is linear
        colour = 1 if img.shape[2] in (1, 2) else 3
        img[..., :colour] = srgb_to_linear(img[..., :colour])
    return img[::-1] if flip else img


def _ramp_of(spec: Mapping, key: str, name: str) -> np.ndarray:
    colours = spec[key]
    edges = spec.get("edges")
    try:
        return band_ramp(
            colours, edges, cols=int(spec.get("cols", COLS)), smooth=bool(spec.get("smooth", False))
        )
    except (TypeError, ValueError, IndexError) as exc:
        raise ValueError(
            f"{name}[{key!r}]: expected a list of band colours (each 1-4 numbers, darkest tone "
            f"first) and optional 'edges' (K - 1 increasing tones), got {colours!r}: {exc}"
        ) from None


def _recipe(spec: Mapping, name: str) -> np.ndarray:
    recipe = spec["recipe"]
    if recipe not in RECIPES:
        raise ValueError(
            f"{name}['recipe']: unknown recipe {recipe!r}; expected one of {sorted(RECIPES)}"
        )
    kwargs = {
        k: v
        for k, v in spec.items()
        if k not in ("recipe", "ramp", "ramps", "edges", "smooth", "cols", "rows")
    }
    rows = spec.get("rows", ROWS)
    if recipe == "levels":
        if "ramps" not in spec:
            raise ValueError(
                f"{name}: the 'levels' recipe needs 'ramps': a list of band-colour lists"
            )
        ramps = [_ramp_of({**spec, "ramp": r}, "ramp", name) for r in spec["ramps"]]
        args = (np.stack(ramps),)
    else:
        if "ramp" not in spec:
            raise ValueError(
                f"{name}: the {recipe!r} recipe needs 'ramp': a list of band colours, e.g. "
                "[[0.1, 0.1, 0.1], [0.5, 0.5, 0.5], [0.9, 0.9, 0.9]]"
            )
        ramp = _ramp_of(spec, "ramp", name)
        args = (ramp,)
        if "tone_weight" in kwargs:  # one weight per band -> one per texel
            kwargs["tone_weight"] = per_texel(kwargs["tone_weight"], spec.get("edges"), len(ramp))
    try:
        return RECIPES[recipe](*args, rows, **kwargs)
    except TypeError as exc:
        raise ValueError(f"{name}: recipe {recipe!r}: {exc}") from None


def resolve_texture(spec: Any, *, name: str = "texture") -> np.ndarray:
    """Resolve a texture spec to ``(rows, cols, 4)`` float32 linear RGBA, rows growing with D.

    Parameters
    ----------
    spec : str, mapping or array
        A preset name (``PRESETS``); an image path (a string with a suffix or a slash); a table
        ``{"preset": name}``, ``{"image": path, "flip": False, "srgb": True}`` or
        ``{"recipe": <RECIPES key>, "ramp": [colours...], "edges": [...], "rows": 64,
        "cols": 256, <recipe keyword>: ...}`` (``"ramps"`` for ``levels``; ``tone_weight`` has
        one value per band); or an array ``(rows, cols[, C])``, C in 1..4 (grey, grey + alpha,
        RGB, RGBA) with values in [0, 1].

    Raises
    ------
    ValueError, TypeError
        Naming ``name``, what was received and the accepted forms.
    """
    if isinstance(spec, str):
        if spec in PRESETS:
            tex = PRESETS[spec]()
        elif "/" in spec or "\\" in spec or Path(spec).suffix:
            tex = _image(spec, flip=False, srgb=True, name=name)
        else:
            raise ValueError(f"{name}: unknown preset {spec!r}; {_how()}")
    elif isinstance(spec, Path):
        tex = _image(spec, flip=False, srgb=True, name=name)
    elif isinstance(spec, Mapping):
        keys = {"preset", "image", "recipe"} & set(spec)
        if len(keys) != 1:
            raise ValueError(
                f"{name}: a texture table needs exactly one of 'preset', 'image' or 'recipe', got "
                f"keys {sorted(spec)}; {_how()}"
            )
        if "preset" in spec:
            if set(spec) != {"preset"}:
                raise ValueError(f"{name}: a preset table takes only 'preset', got {sorted(spec)}")
            return resolve_texture(str(spec["preset"]), name=name)
        if "image" in spec:
            extra = set(spec) - {"image", "flip", "srgb"}
            if extra:
                raise ValueError(
                    f"{name}: unknown keys {sorted(extra)} in an image table; valid: image, flip, srgb"
                )
            tex = _image(
                spec["image"],
                flip=bool(spec.get("flip", False)),
                srgb=bool(spec.get("srgb", True)),
                name=name,
            )
        else:
            tex = _recipe(spec, name)
    elif spec is None or isinstance(spec, (bool, int, float)):
        raise TypeError(f"{name}: expected a texture, got {spec!r}; {_how()}")
    else:
        tex = spec
    return as_rgba(_check_array(tex, name)).astype(np.float32)
