"""The ``halftone`` style class (Freudenberg et al. 2002): parameters, channels and per-sample
shading; the package docstring (:mod:`refnpr.styles.halftone`) describes the technique.
"""

from __future__ import annotations

import json
import math
from typing import Any

import numpy as np

from refnpr.formulas import halftone
from refnpr.image import srgb_to_linear

from .._common import (
    check_choice,
    check_count,
    check_number,
    check_uv_scale,
    needs_position,
    rgba_from,
    rgba_out,
    warn_unused,
)
from ..base import ShadeContext, Style, register
from . import screens as HS
from .fused import LIGHT_CODES, prepare_into, shade_object_into
from .shading import lit_intensity, parse_indication, sample_indication, tangent_frame

__all__ = ["HalftoneStyle"]

_OBJECT_KEYS = ("screen", "indication", "indication_scale", "uv_scale")


def _colour(name: str, value: Any) -> tuple[float, float, float]:
    try:
        c = np.array(value, dtype=np.float64)
    except (TypeError, ValueError):
        c = np.array([np.nan])
    if c.shape != (3,) or not np.all(np.isfinite(c)) or np.any(c < 0) or np.any(c > 1):
        raise ValueError(f"{name}: expected 3 linear RGB values in [0, 1], got {value!r}")
    return (float(c[0]), float(c[1]), float(c[2]))


@register
class HalftoneStyle(Style):
    """Halftoning against a screen in texture space (Freudenberg et al. 2002).

    Parameters
    ----------
    threshold : {"smooth", "binary"}
        Sec. 3.2 ``clip(1 - c (1 - screen - I), 0, 1)`` or sec. 3.1 (white iff screen + I > 1).
    c : float > 0 or "auto"
        Slope of the smooth threshold (the paper's 4). "auto" (an extension, not in the paper):
        per sample ``c = 1 / fwidth(screen)``, the screen's change across one sample step
        (central differences at uv +- duv/dx, duv/dy), with the ramp centred, so the grey ramp
        spans exactly the sample's footprint: analytic anti-aliasing of the threshold edge.
    centred : bool
        Centre the smooth ramp on the binary threshold (no tone bias; the paper's one-sided ramp
        lightens the mean tone by 1/(2c)).
    screen : str or table
        Default screen of every object (see :mod:`refnpr.styles.halftone.screens`):
        "hatching" (default), "bricks", "engraving", "material", a texture name or path, or a
        table such as ``{kind = "engraving", profile = "triangle", angle = 90}``.
    uv_scale : float or [su, sv], optional
        Multiplies uv before the screen lookup, overriding each material's ``uv_scale``.
    objects : table, optional
        Per-object settings by object name: ``{name = {screen = ..., indication = ...,
        indication_scale = [su, sv], uv_scale = ...}}`` (``indication_scale`` multiplies uv
        before the indication lookup, so a map can span a part of uv space).
    indication : nested list or image path, optional
        Default indication map (sec. 5.1): a low-resolution signed map over the object's uv in
        [0, 1]^2 (before ``uv_scale``; row j covers v in [j/rows, (j+1)/rows)); added to I.
    specular : bool
        Include the specular term in I (needs positions).
    ink, paper : [r, g, b]
        Colours of output 0 and 1 (linear RGB).
    lod_bias : float
        Added to every LOD.
    sample_lod : bool
        False (default): every sample of a pixel uses the pixel's LOD (the G-buffer's derivatives
        are per pixel), so n x n supersampling anti-aliases the same picture. True: each sample
        uses its own footprint (pixel LOD - log2 n), as rendering at n times the resolution
        would: supersampling then converges to the screen's finest level (for stroke maps a
        different set of strokes).
    mip : {"trilinear", "per_level"}
        "trilinear" (the paper, as texture hardware does): threshold the trilinearly filtered
        screen. "per_level": threshold the two bilinear level samples separately and blend the
        results with the trilinear weight (Veryovka's filtered thresholding); each level keeps
        its own tone, which blending screens does not.
    anisotropy : int in [1, 16]
        Largest anisotropic filtering ratio (GL_TEXTURE_MAX_ANISOTROPY). 1 (default): the
        isotropic LOD of the paper's trilinear lookup, ``log2 max(|duv/dx|, |duv/dy|)`` in texels.
        N > 1: the level is chosen for the footprint's minor axis (``log2(P_max / n)`` with
        ``n = min(ceil(P_max / P_min), N)``) and n trilinear probes along the major axis are
        averaged (:func:`~refnpr.styles.halftone.screens.screen_footprint`). On surfaces seen
        at a grazing angle the isotropic LOD picks levels whose strokes are wide in uv and
        magnifies them across the uncompressed direction (thorn-like strokes near silhouettes);
        anisotropic filtering keeps a stroke map's strokes at their screen width.
    show : {"color", "screen", "normals", "intensity"}
        What to output: "color" (default) the halftoned image; "screen" the filtered screen
        value at each sample's uv and LOD (the raw stroke map or dither screen, Fig. 3 (d),
        Fig. 8); "normals" the RGB-encoded stroke normal map (Fig. 8; flat (0.5, 0.5, 1)
        without one); "intensity" the target intensity I after the indication map (Fig. 4 (b);
        Fig. 8's indication maps). Ink and paper colours apply to "color" only. A raw value x
        is output as the linear colour whose sRGB encoding is x, so an 8-bit image file stores
        x itself (as the texture file of the map would).
    tone_correct : bool
        Map each bilinear level sample through the CDF of that level's interpolated values
        (:func:`~refnpr.styles.halftone.screens.tone_luts`), so that thresholding keeps the tone
        under bilinear filtering; implies per-level sampling. Engraving and dither screens only
        (a stroke map's layer greys are its design and are left alone).
    """

    name = "halftone"
    renamed = {"equalize": "tone_correct"}  # the threshold style's name for the same correction
    description = "halftoning against engraving/dither/stroke-map screens (Freudenberg et al. 2002)"

    def __init__(
        self,
        *,
        threshold: str = "smooth",
        c: float | str = 4.0,
        centred: bool = False,
        screen: Any = "hatching",
        uv_scale: Any = None,
        objects: dict | None = None,
        indication: Any = None,
        specular: bool = True,
        ink: Any = (0.0, 0.0, 0.0),
        paper: Any = (1.0, 1.0, 1.0),
        lod_bias: float = 0.0,
        sample_lod: bool = False,
        mip: str = "trilinear",
        tone_correct: bool = False,
        anisotropy: int = 1,
        show: str = "color",
    ) -> None:
        self.threshold = check_choice("threshold", threshold, ("smooth", "binary"))
        if isinstance(c, str) and c != "auto":
            raise ValueError(f"c: expected a number > 0 or 'auto', got {c!r}")
        self.c = c if c == "auto" else check_number("c", c, lo=0.0, lo_open=True)
        flags = {
            "centred": centred,
            "specular": specular,
            "sample_lod": sample_lod,
            "tone_correct": tone_correct,
        }
        for flag, val in flags.items():
            if not isinstance(val, (bool, np.bool_)):  # 1 and 0 are not flags
                raise TypeError(f"{flag}: expected a bool (true/false), got {val!r}")
        self.centred, self.specular = bool(centred), bool(specular)
        self.sample_lod, self.tone_correct = bool(sample_lod), bool(tone_correct)
        if self.threshold == "binary":
            if c != 4.0:
                warn_unused("c", c, "threshold='binary'", "remove c or use threshold='smooth'")
            if self.centred:
                warn_unused(
                    "centred",
                    True,
                    "threshold='binary'",
                    "remove centred or use threshold='smooth'",
                )
        elif self.c == "auto" and self.centred:
            warn_unused("centred", True, "c='auto' (always centred)", "remove centred")
        self.screen_spec = HS.normalize_spec(screen)
        self.uv_scale = check_uv_scale("uv_scale", uv_scale)
        self.indication = parse_indication(indication)
        self.ink, self.paper = _colour("ink", ink), _colour("paper", paper)
        self.lod_bias = check_number("lod_bias", lod_bias, lo=-16.0, hi=16.0)
        self.mip = check_choice("mip", mip, ("trilinear", "per_level"))
        self.anisotropy = check_count("anisotropy", anisotropy, lo=1, hi=16)
        self.show = check_choice("show", show, ("color", "screen", "normals", "intensity"))
        self.objects = self._parse_objects(objects)
        self._screens: dict[str, HS.Screen] = {}
        self._tone_luts: dict[int, np.ndarray] = {}
        self._params = {
            "threshold": self.threshold,
            "c": self.c,
            "centred": self.centred,
            "screen": HS.current_names(screen),
            "uv_scale": uv_scale,
            "objects": None
            if objects is None
            else {
                k: {**v, "screen": HS.current_names(v["screen"])} if "screen" in v else v
                for k, v in objects.items()
            },
            "indication": indication,
            "specular": self.specular,
            "ink": list(self.ink),
            "paper": list(self.paper),
            "lod_bias": self.lod_bias,
            "sample_lod": self.sample_lod,
            "mip": self.mip,
            "tone_correct": self.tone_correct,
            "anisotropy": self.anisotropy,
            "show": self.show,
        }

    @staticmethod
    def _parse_objects(objects: Any) -> dict[str, dict[str, Any]]:
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
            unknown = sorted(set(table) - set(_OBJECT_KEYS))
            if unknown:
                raise ValueError(
                    f"objects.{name}.{unknown[0]}: unknown key; valid keys: {', '.join(_OBJECT_KEYS)}"
                )
            entry: dict[str, Any] = {}
            if "screen" in table:
                entry["screen"] = HS.normalize_spec(table["screen"])
            if "indication" in table:
                entry["indication"] = parse_indication(
                    table["indication"], f"objects.{name}.indication"
                )
            if "indication_scale" in table:
                entry["indication_scale"] = check_uv_scale(
                    f"objects.{name}.indication_scale", table["indication_scale"]
                )
            if "uv_scale" in table:
                entry["uv_scale"] = check_uv_scale(f"objects.{name}.uv_scale", table["uv_scale"])
            out[str(name)] = entry
        return out

    # -- what the renderer must provide -----------------------------------------------------
    def _object_specs(self, scene: Any) -> list[dict[str, Any]]:
        names = [o.name for o in scene.objects]
        unknown = sorted(set(self.objects) - set(names))
        if unknown:
            raise ValueError(
                f"objects.{unknown[0]}: the scene has no object of that name; its objects: {names}"
            )
        return [self.objects.get(n, {}).get("screen", self.screen_spec) for n in names]

    def _uses_normal_maps(self, scene: Any) -> bool:
        return any(HS.has_normal_map(s) for s in self._object_specs(scene))

    def requires(self, scene: Any) -> frozenset[str]:
        req = {"mesh_id", "normal", "uv", "duv_dx", "duv_dy"}
        if needs_position(scene, self.specular):
            req.add("position")
        if self._uses_normal_maps(scene):
            req |= {"dposition_dx", "dposition_dy"}
        return frozenset(req)

    # -- screens ----------------------------------------------------------------------------
    def screen_for(self, spec: dict[str, Any], material_texture: str | None) -> HS.Screen:
        """The built screen of a normalized spec (built once per style instance)."""
        key = json.dumps(spec, sort_keys=True) + "|" + str(material_texture)
        if key not in self._screens:
            self._screens[key] = HS.cached_screen(spec, material_texture)
        return self._screens[key]

    def _luts(self, screen: HS.Screen) -> np.ndarray:
        key = id(screen)
        if key not in self._tone_luts:
            self._tone_luts[key] = HS.tone_luts(screen.pyramid)
        return self._tone_luts[key]

    # -- shading ----------------------------------------------------------------------------
    def _threshold(self, screen: np.ndarray, intensity: np.ndarray, c_auto=None) -> np.ndarray:
        if self.threshold == "binary":
            return halftone.binary_threshold(screen, intensity)  # sec. 3.1
        if c_auto is not None:  # sec. 3.2 centred, with a per-sample slope c = 1 / fwidth
            return np.clip(0.5 - c_auto * (1.0 - screen - intensity), 0.0, 1.0)
        return halftone.smooth_threshold(screen, intensity, self.c, centred=self.centred)  # 3.2

    def _auto_c(self, screen: HS.Screen, coords, cdx, cdy, lod, n_axis: int, fp) -> np.ndarray:
        """``1 / fwidth(screen)`` per sample: central differences of the trilinear screen over
        one sample step (1/n pixel with n x n samples) along x and along y."""
        step = 1.0 / n_axis
        fw = np.zeros(coords.shape[0])
        for d in (cdx * step, cdy * step):
            plus = HS.sample_screen(screen.pyramid, coords + d, lod, fp)
            minus = HS.sample_screen(screen.pyramid, coords - d, lod, fp)
            fw += np.abs(plus - minus) / 2
        return 1.0 / np.maximum(fw, 1e-6)

    def uses_kernels(self) -> bool:
        """Whether :meth:`shade` takes the numba path (every option but ``c = "auto"``)."""
        return not (self.c == "auto" and self.threshold == "smooth")

    def shade(self, ctx: ShadeContext) -> np.ndarray:
        """Per-sample RGBA (nH, nW, 4) float32: one numba pass per object
        (:mod:`~refnpr.styles.halftone.fused`), or the numpy path for ``c = "auto"``."""
        if not self.uses_kernels():
            return self.shade_numpy(ctx)
        return self._shade_fused(ctx)

    def _lights(self, scene: Any) -> list[tuple[int, np.ndarray, np.ndarray]]:
        """(kind code, unit direction or position, colour) per light, as ``light_dirs``."""
        out = []
        for light in scene.lights:
            color = np.asarray(light.color, dtype=np.float64)
            if light.kind == "point":
                pos = np.asarray(light.position, dtype=np.float64)
                out.append((LIGHT_CODES["point"], pos, color))
            else:
                d = np.asarray(light.direction, dtype=np.float64)
                out.append((LIGHT_CODES["directional"], d / np.linalg.norm(d), color))
        return out

    def _shade_fused(self, ctx: ShadeContext) -> np.ndarray:
        gb, scene = ctx.gb, ctx.scene
        mesh_id = np.asarray(gb["mesh_id"])
        mask = np.asarray(ctx.mask)
        shape = mesh_id.shape
        specs = self._object_specs(scene)
        out = rgba_out(ctx, shape)  # written in full: prepare_into, then every object in view
        raw = None if self.show == "color" else np.ones(shape + (3,))
        one = (1.0, 1.0, 1.0) if self.show != "color" else self.paper  # value 1 off objects
        present = prepare_into(out, mesh_id, mask, one, len(scene.objects))
        lod_offset = self.lod_bias - (math.log2(gb.n) if self.sample_lod else 0.0)
        need_pos = needs_position(scene, self.specular)
        names = ["normal", "uv", "duv_dx", "duv_dy"]
        names += ["position"] if need_pos else []
        if self._uses_normal_maps(scene):
            names += ["dposition_dx", "dposition_dy"]
        channels = {k: gb[k] for k in names}
        lights = self._lights(scene)
        ambient = np.asarray(scene.ambient, dtype=np.float64)
        eye = np.asarray(scene.camera.eye, dtype=np.float64)
        for i, obj in enumerate(scene.objects):
            if not present[i]:
                continue
            settings = self.objects.get(obj.name, {})
            screen = self.screen_for(specs[i], obj.material.texture)
            scale = settings.get("uv_scale") or self.uv_scale or obj.material.uv_scale
            equalize = self.tone_correct and screen.kind != "strokes"
            m = obj.material
            shade_object_into(
                out,
                raw,
                obj=i,
                mesh_id=mesh_id,
                mask=mask,
                channels=channels,
                scale=np.asarray(scale, dtype=np.float64),
                screen=screen,
                luts=self._luts(screen) if equalize else None,
                per_level=self.mip == "per_level",
                indication=settings.get("indication", self.indication),
                indication_scale=settings.get("indication_scale") or (1.0, 1.0),
                ambient=np.asarray(m.ambient, dtype=np.float64) * ambient,  # eq. 1: m_a l_a
                diffuse=np.asarray(m.diffuse, dtype=np.float64),
                specular_color=np.asarray(m.specular, dtype=np.float64),
                shininess=float(m.shininess),
                specular=self.specular,
                lights=lights,
                eye=eye,
                anisotropy=self.anisotropy if screen.direction is None else 1,
                lod_offset=lod_offset,
                threshold=self.threshold,
                c=4.0 if self.c == "auto" else float(self.c),
                centred=self.centred,
                show=self.show,
                ink=self.ink,
                paper=self.paper,
            )
        if raw is not None:  # an 8-bit file of the image stores the raw values
            return rgba_from(srgb_to_linear(raw), mask)
        return out

    def shade_numpy(self, ctx: ShadeContext) -> np.ndarray:
        """The numpy path of :meth:`shade` (whole-object float64 arrays): ``c = "auto"`` and
        the oracle of the kernel tests."""
        gb, scene = ctx.gb, ctx.scene
        mesh_id = gb["mesh_id"].reshape(-1)
        specs = self._object_specs(scene)
        shape = gb["mesh_id"].shape
        out = np.ones(mesh_id.shape[0])
        out_rgb = np.ones((mesh_id.shape[0], 3)) if self.show == "normals" else None
        n_axis = gb.n
        lod_offset = self.lod_bias - (math.log2(n_axis) if self.sample_lod else 0.0)
        normal = gb["normal"].reshape(-1, 3)
        uv_all = gb["uv"].reshape(-1, 2)
        dx_all, dy_all = gb["duv_dx"].reshape(-1, 2), gb["duv_dy"].reshape(-1, 2)
        for i, obj in enumerate(scene.objects):
            sel = np.flatnonzero(mesh_id == i)
            if sel.size == 0:
                continue
            settings = self.objects.get(obj.name, {})
            screen = self.screen_for(specs[i], obj.material.texture)
            scale = settings.get("uv_scale") or self.uv_scale or obj.material.uv_scale
            scale = np.asarray(scale, dtype=np.float64)
            uv = uv_all[sel].astype(np.float64)
            coords, cdx, cdy = HS.screen_coords(
                screen, uv * scale, dx_all[sel] * scale, dy_all[sel] * scale
            )
            aniso = self.anisotropy if screen.direction is None else 1  # engraving: a 1D ramp
            lod, fp = HS.screen_footprint(screen.pyramid, cdx, cdy, aniso)
            lod = lod + lod_offset
            n = normal[sel].astype(np.float64)
            bump = None
            if screen.normals is not None:
                nmap = HS.sample_screen(screen.normals, coords, lod, fp)
                t, b, valid = tangent_frame(
                    n,
                    gb["dposition_dx"].reshape(-1, 3)[sel].astype(np.float64),
                    gb["dposition_dy"].reshape(-1, 3)[sel].astype(np.float64),
                    dx_all[sel].astype(np.float64),
                    dy_all[sel].astype(np.float64),
                )
                bump = (nmap, t, b, valid)
            intensity = lit_intensity(ctx, sel, n, specular=self.specular, bump=bump)
            imap = settings.get("indication", self.indication)
            if imap is not None:
                iscale = np.asarray(settings.get("indication_scale") or (1.0, 1.0))
                ind = sample_indication(imap, uv * iscale)
                intensity = halftone.apply_indication(intensity, ind)  # sec. 5.1
            equalize = self.tone_correct and screen.kind != "strokes"
            c_auto = None
            if self.c == "auto" and self.threshold == "smooth":
                c_auto = self._auto_c(screen, coords, cdx, cdy, lod, n_axis, fp)
            if self.show == "intensity":
                out[sel] = intensity
            elif self.show == "normals":
                if screen.normals is None:
                    out_rgb[sel] = (0.5, 0.5, 1.0)
                else:
                    out_rgb[sel] = HS.sample_screen(screen.normals, coords, lod, fp)
            elif self.show == "screen":
                out[sel] = HS.sample_screen(screen.pyramid, coords, lod, fp)
            elif self.mip == "trilinear" and not equalize:
                value = HS.sample_screen(screen.pyramid, coords, lod, fp)  # sec. 3: (uv, LOD)
                out[sel] = self._threshold(value, intensity, c_auto)
            else:
                s0, s1, k0, k1, w1 = HS.sample_screen_levels(screen.pyramid, coords, lod, fp)
                if equalize:
                    luts = self._luts(screen)
                    s0, s1 = HS.apply_luts(luts, s0, k0), HS.apply_luts(luts, s1, k1)
                t0 = self._threshold(s0, intensity, c_auto)
                t1 = self._threshold(s1, intensity, c_auto)
                out[sel] = (1 - w1) * t0 + w1 * t1
        if self.show == "normals":  # an 8-bit file of the image stores the map's values
            return rgba_from(srgb_to_linear(out_rgb.reshape(shape + (3,))), ctx.mask)
        out = out.reshape(shape)[..., None]
        if self.show != "color":  # the raw value as gray, stored as such in an 8-bit file
            return rgba_from(srgb_to_linear(np.repeat(out, 3, axis=-1)), ctx.mask)
        rgb = out * np.asarray(self.paper) + (1.0 - out) * np.asarray(self.ink)
        return rgba_from(rgb, ctx.mask)
