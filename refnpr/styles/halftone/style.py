"""The ``halftone`` style class (Freudenberg et al. 2002): parameters, channels and per-sample
shading; the package docstring (:mod:`refnpr.styles.halftone`) describes the technique.
"""

from __future__ import annotations

import json
from typing import Any

import numpy as np

from .._declare import warn_unused
from ..base import ShadeContext, Style, register
from . import screens as HS
from .params import PARAMS
from .shading import channels, shade_rgba

__all__ = ["HalftoneStyle"]


@register
class HalftoneStyle(Style):
    """Halftoning against a screen in texture space (Freudenberg et al. 2002).

    Parameters are declared once in :data:`refnpr.styles.halftone.params.PARAMS` (their table
    is in ``docs/halftone.md``); ``HalftoneStyle.PARAMS`` lists them with their defaults, types,
    ranges and the modes that read them. ``equalize`` is the deprecated name of
    ``tone_correct``.
    """

    name = "halftone"
    description = "halftoning against engraving/dither/stroke-map screens (Freudenberg et al. 2002)"
    PARAMS = PARAMS
    INTERMEDIATES = {
        "intensity": "the target intensity I after the indication map (show='intensity')",
        "threshold": "the trilinear screen value (show='screen'): what mip='trilinear' compares "
        "the intensity with (per_level and tone_correct compare two levels' values apart)",
    }

    def __init__(self, **params: Any) -> None:
        p = PARAMS.validate(params)
        if p.c == "auto" and p.threshold == "smooth" and p.centred:
            warn_unused("centred", True, "c='auto' (always centred)", "remove centred")
        #: The validated parameter values (:class:`refnpr.styles._declare.Values`).
        self.p = p
        #: The default screen spec of every object, normalized (``screens.normalize_spec``).
        self.screen_spec: dict[str, Any] = p.screen.value
        #: ``(su, sv)`` in place of each material's uv_scale, or None.
        self.uv_scale = None if p.uv_scale is None else p.uv_scale.value
        #: The default indication map (rows, cols) float64, or None.
        self.indication = None if p.indication is None else p.indication.value
        #: Per-object settings by object name, parsed (``params.parse_objects``).
        self.objects: dict[str, dict[str, Any]] = {} if p.objects is None else p.objects.value
        self._params = p.as_dict()
        self._screens: dict[str, HS.Screen] = {}
        self._tone_luts: dict[int, np.ndarray] = {}

    # -- what the renderer must provide -----------------------------------------------------
    def object_specs(self, scene: Any) -> list[dict[str, Any]]:
        """The normalized screen spec of each object of ``scene`` (its own, else the style's)."""
        names = [o.name for o in scene.objects]
        unknown = sorted(set(self.objects) - set(names))
        if unknown:
            raise ValueError(
                f"objects.{unknown[0]}: the scene has no object of that name; its objects: {names}"
            )
        return [self.objects.get(n, {}).get("screen", self.screen_spec) for n in names]

    def uses_normal_maps(self, scene: Any) -> bool:
        """Whether some object's screen lights its strokes from a normal map (sec. 5.2)."""
        return any(HS.has_normal_map(s) for s in self.object_specs(scene))

    def requires(self, scene: Any) -> frozenset[str]:
        return frozenset({"mesh_id", *channels(self, scene)})

    # -- screens ----------------------------------------------------------------------------
    def screen_for(self, spec: dict[str, Any], material_texture: str | None) -> HS.Screen:
        """The built screen of a normalized spec (built once per style instance)."""
        key = json.dumps(spec, sort_keys=True) + "|" + str(material_texture)
        if key not in self._screens:
            self._screens[key] = HS.cached_screen(spec, material_texture)
        return self._screens[key]

    def _luts(self, screen: HS.Screen) -> np.ndarray:
        """The tone LUTs of ``screen`` (``screens.tone_luts``, built once per screen)."""
        key = id(screen)
        if key not in self._tone_luts:
            self._tone_luts[key] = HS.tone_luts(screen.pyramid)
        return self._tone_luts[key]

    # -- shading ----------------------------------------------------------------------------
    def shade(self, ctx: ShadeContext) -> np.ndarray:
        """Per-sample RGBA (nH, nW, 4) float32: one numba pass per object (:mod:`refnpr.styles.halftone.shading`)."""
        return shade_rgba(self, ctx)
