"""Per-style kit exporters (interface A): ``export_style`` dispatches on the style's name.

A style ``NAME`` is exported by ``refnpr.kit.styles.NAME.export(style, scene, case_dir, *,
width, height, spp) -> StyleExport`` when that module exists, else by :mod:`._generic`
(``params()`` as they are). The module's ``derived(style, scene, *, width, height, spp)`` gives
the case's derived texts without building any texture (``export`` returns the same texts), or,
where they are the same for every case, its constant ``DERIVED``; :func:`derived_texts`
dispatches to either. A module may also define ``unresolved(params) ->
list[str]``: the key paths of exported params that still hold something only refnpr could
resolve (the kit tests call it; the generic check looks for "auto" strings).

The ``contoured`` wrapper (a style with ``contours = {...}``) is unwrapped here: its base style is
exported by the base's module, then the contour layer by :func:`.contours.export_contours` (same
arguments, the layer instead of the style; its params go to ``params["contours"]``, its derived
texts and textures are merged). The case's style name is the base style's name.
"""

from __future__ import annotations

import importlib
from pathlib import Path
from types import ModuleType
from typing import Any

from . import _generic, contours
from ._export import StyleExport

__all__ = [
    "StyleExport",
    "export_style",
    "derived_texts",
    "exporter_module",
    "unresolved",
    "style_name",
]


def exporter_module(name: str) -> ModuleType:
    """The kit module that exports style ``name`` (its own, else the generic one)."""
    if not isinstance(name, str) or not name.isidentifier() or name.startswith("_"):
        raise ValueError(f"style name: expected a registered style name, got {name!r}")
    try:
        return importlib.import_module(f"{__name__}.{name}")
    except ModuleNotFoundError as exc:
        if exc.name != f"{__name__}.{name}":
            raise  # the module exists but one of its imports is missing
        return _generic


def style_name(style: Any) -> str:
    """The name a case.json gives ``style`` (the base style's name for ``contoured``)."""
    return style.base.name if style.name == "contoured" else style.name


def export_style(
    style: Any, scene: Any, case_dir: Path, *, width: int, height: int, spp: int
) -> StyleExport:
    """Export a style for one case: resolved params, texture files, derived texts.

    Parameters
    ----------
    style : refnpr.styles.Style
        The style the case renders with (``contoured`` is unwrapped, see the module docstring).
    scene : refnpr.scenes.Scene
    case_dir : Path
        ``DIR/<case>``; texture files go under ``case_dir/textures/<role>/``.
    width, height, spp : int
        Image size and samples per pixel of the case.

    Returns
    -------
    StyleExport
        With ``params["contours"]`` for a contoured style. A module that returns anything else
        is a TypeError naming it.
    """
    size = {"width": width, "height": height, "spp": spp}
    case_dir = Path(case_dir)
    if style.name == "contoured":
        out = export_style(style.base, scene, case_dir, **size)
        layer = contours.export_contours(style.layer, scene, case_dir, **size)
        out.params = {**out.params, "contours": layer.params}
        clash = set(out.textures) & set(layer.textures)
        if clash:
            raise ValueError(f"contours: texture roles {sorted(clash)} clash with the base style's")
        out.textures.update(layer.textures)
        out.derived.update(layer.derived)
        for k, attrs in layer.vertex_attributes.items():
            out.vertex_attributes.setdefault(k, {}).update(attrs)
        return out
    mod = exporter_module(style.name)
    out = mod.export(style, scene, case_dir, **size)
    if not isinstance(out, StyleExport):
        raise TypeError(
            f"{mod.__name__}.export returned {type(out).__name__}; expected a StyleExport"
        )
    return out


def derived_texts(style: Any, scene: Any, *, width: int, height: int, spp: int) -> dict[str, str]:
    """The style's derived texts for one case, as :func:`export_style` gives them, without
    writing or building any texture (cheap: no pyramid, no table).

    Parameters
    ----------
    style : refnpr.styles.Style
        The style the case renders with (``contoured``: the base style's texts, then the
        contour layer's).
    scene : refnpr.scenes.Scene
    width, height, spp : int
        Image size and samples per pixel of the case.

    Returns
    -------
    dict
        name -> paragraph; empty for a style exported by the generic module.
    """
    size = {"width": width, "height": height, "spp": spp}
    if style.name == "contoured":
        out = derived_texts(style.base, scene, **size)
        out.update(contours.DERIVED)
        return out
    mod = exporter_module(style.name)
    make = getattr(mod, "derived", None)
    return dict(getattr(mod, "DERIVED", {})) if make is None else dict(make(style, scene, **size))


def unresolved(name: str, params: dict[str, Any]) -> list[str]:
    """Key paths of an exported style's params that only refnpr could resolve.

    Uses the style module's own ``unresolved(params)`` when it has one, else the generic check
    ("auto"/"default"/"preset" strings). The contour layer's params are checked generically and
    for missing keys.
    """
    check = getattr(exporter_module(name), "unresolved", _generic.unresolved)
    out = list(check({k: v for k, v in params.items() if k != "contours"}))
    if "contours" in params:
        out += _generic.unresolved({"contours": params["contours"]})
        if isinstance(params["contours"], dict):
            out += [
                f"params.contours: {k} missing" for k in contours.unresolved(params["contours"])
            ]
    return out
