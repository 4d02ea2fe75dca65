"""``explore(scene, style)``: sliders for a style's parameters and the camera, in Jupyter.

Every numeric parameter of the style gets a slider, every flag a checkbox and every parameter
whose value is one of a listed set a dropdown; the camera gets orbit sliders (azimuth and
elevation about the target, distance) and the vertical field of view. Each change re-renders
into an ``ipywidgets.Image``. The widgets come from the optional extra ``notebook``
(``pip install 'refnpr[notebook]'``): ``import refnpr`` never imports ipywidgets.

Where the parameters and their ranges come from
-----------------------------------------------
* The names: the style class's ``parameters()``; the starting values: the style instance's
  ``params()`` (its current values, defaults filled in). Parameters whose value is not a
  number, a flag or a string (colours, lists, tables, None) get no control.
* Ranges: a span around the starting value ``v`` per type (``[0, 1]`` for a float in (0, 1),
  ``[0, 4 v]`` above, ``[-4, 4]`` for 0, ``[0, max(4 v, v + 8)]`` for an integer), cut to the
  range of the style's parameter declaration (``Style.PARAMS``): where a declared bound cuts
  it, that bound is the slider end (one step, or 1, inside it where the bound is open). An end
  the declaration does not cut is probed against the style's own validation, moved towards
  ``v`` by bisection until the style accepts it, with the modes that read the parameter set
  (its declared ``used_when``): a style does not validate a parameter its mode ignores.
* Choices: the declared choices; for an undeclared parameter, the style's message for an
  unknown string (``expected one of [...]``, or the names it quotes or lists), each listed name
  kept only if the style accepts it. A string parameter without listed choices gets a text box.
* The probes hold the other parameters the style was built with fixed (numpy scalars as
  numbers); a value without a literal form (an array) is left to its default there.
"""

from __future__ import annotations

import ast
import dataclasses
import functools
import html
import math
import re
import sys
import types
import warnings
from collections.abc import Mapping
from typing import Any

import numpy as np

from .image import Image
from .raster import Camera
from .render import DEFAULT_STYLE, as_scene, render
from .styles import Style, get_style, get_style_class, style_from_spec

__all__ = ["Explorer", "Orbit", "explore", "orbit_camera", "orbit_of", "parameter_controls"]


def _widgets():
    try:
        import ipywidgets
    except ImportError as exc:
        raise ImportError(
            "refnpr.explore needs ipywidgets, from the optional extra `notebook`: "
            "pip install 'refnpr[notebook]' (or pip install ipywidgets)"
        ) from exc
    return ipywidgets


# ---------------------------------------------------------------------------- the camera
@dataclasses.dataclass(frozen=True)
class Orbit:
    """A camera as an orbit about its target: angles in degrees, ``distance`` in world units.

    ``azimuth`` turns about ``up`` from ``reference`` (the starting camera's horizontal
    direction, so the starting camera has azimuth 0); ``elevation`` is the angle above the
    plane perpendicular to ``up``.
    """

    target: np.ndarray
    up: np.ndarray
    reference: np.ndarray
    azimuth: float
    elevation: float
    distance: float


def orbit_of(camera: Camera) -> Orbit:
    """The orbit that reproduces ``camera`` (its eye as seen from its target)."""
    if not isinstance(camera, Camera):
        raise TypeError(f"camera: expected a refnpr.raster.Camera, got {type(camera).__name__}")
    target = np.asarray(camera.target, dtype=np.float64)
    up = np.asarray(camera.up, dtype=np.float64)
    up = up / np.linalg.norm(up)
    offset = np.asarray(camera.eye, dtype=np.float64) - target
    distance = float(np.linalg.norm(offset))
    horizontal = offset - np.dot(offset, up) * up
    if np.linalg.norm(horizontal) < 1e-9 * distance:  # looking along up: any perpendicular
        axis = np.eye(3)[int(np.argmin(np.abs(up)))]
        horizontal = np.cross(up, axis)
    reference = horizontal / np.linalg.norm(horizontal)
    elevation = math.degrees(math.asin(float(np.clip(np.dot(offset, up) / distance, -1, 1))))
    return Orbit(target, up, reference, 0.0, elevation, distance)


def orbit_camera(base: Camera, orbit: Orbit, fov_y: float | None = None) -> Camera:
    """``base`` moved to ``orbit`` (same target, up, near; far grown with the distance)."""
    az, el = math.radians(orbit.azimuth), math.radians(orbit.elevation)
    side = np.cross(orbit.up, orbit.reference)
    horizontal = math.cos(az) * orbit.reference + math.sin(az) * side
    eye = orbit.target + orbit.distance * (math.cos(el) * horizontal + math.sin(el) * orbit.up)
    d0 = float(np.linalg.norm(np.asarray(base.eye) - np.asarray(base.target)))
    far = max(base.far, base.far * orbit.distance / d0) if d0 > 0 else base.far
    return Camera.look_at(
        eye, orbit.target, orbit.up, base.fov_y if fov_y is None else fov_y, base.near, far
    )


# ---------------------------------------------------------------------------- parameters
def _error(spec: tuple[tuple[str, Any], ...], name: str, value: Any) -> str | None:
    """The message of building the style of ``spec`` with ``name = value``; None if it builds."""
    params = {**_params_only(spec), name: value}
    with warnings.catch_warnings():  # a probe is not the user's choice: no advice for it
        warnings.simplefilter("ignore")
        try:
            get_style(dict(spec)["name"], **params)
        except (TypeError, ValueError) as exc:
            return str(exc)
    return None


def _plain(value: Any) -> Any:
    """``value`` with numpy scalars as Python numbers (in tuples, lists and tables too)."""
    if isinstance(value, np.generic):
        return value.item()
    if isinstance(value, (tuple, list)):
        items = [_plain(v) for v in value]
        return tuple(items) if isinstance(value, tuple) else items
    if isinstance(value, dict):
        return {k: _plain(v) for k, v in value.items()}
    return value


def _frozen(spec: Mapping[str, Any]) -> tuple[tuple[str, Any], ...]:
    """``spec`` as a hashable key of the probes' caches (values by ``repr``), leaving out the
    values without a literal form (arrays, objects), which the probes leave to their defaults."""
    items = []
    for k, v in spec.items():
        text = repr(_plain(v))
        try:
            ast.literal_eval(text)
        except (ValueError, TypeError, SyntaxError, MemoryError, RecursionError):
            continue
        items.append((k, text))
    return tuple(sorted(items))


def _thawed(style_name: str, base: tuple[tuple[str, Any], ...]) -> tuple[tuple[str, Any], ...]:
    return tuple((k, ast.literal_eval(v)) for k, v in base) + (("name", style_name),)


def _declared(style_name: str, name: str) -> Any:
    """The declaration (``Param``) of parameter ``name`` of style ``style_name``; None where the
    style declares none."""
    params = getattr(get_style_class(style_name), "PARAMS", None)
    return None if params is None else params.by_name.get(name)


def _reading_modes(style_name: str, name: str, spec: Mapping[str, Any]) -> dict[str, Any]:
    """The mode values to add to ``spec`` so that the style reads ``name``: for each mode of
    its declared ``used_when`` (and theirs) that ``spec`` sets to a mode ignoring it, the first
    mode that reads it. Modes that only need a value given (``NOT_NONE``) are left alone."""
    params = getattr(get_style_class(style_name), "PARAMS", None)
    if params is None:
        return {}
    modes: dict[str, Any] = {}
    todo, seen = [name], set()
    while todo:
        p = params.by_name.get(todo.pop())
        if p is None or p.name in seen:
            continue
        seen.add(p.name)
        for other, allowed in p.used_when.items():
            if isinstance(allowed, str) or other not in params.by_name:
                continue  # read where any value is given: none to pick
            now = modes.get(other, spec.get(other, params.by_name[other].default))
            if now not in allowed:
                modes[other] = allowed[0]
            todo.append(other)
    return modes


def _span(value: float, is_int: bool) -> tuple[float, float]:
    """The candidate slider span around a starting ``value`` (module docstring)."""
    if is_int:
        return 0.0, float(max(4 * value, value + 8))
    if value == 0:
        return -4.0, 4.0
    if 0 < value < 1:
        return 0.0, 1.0
    if value > 0:
        return 0.0, 4.0 * value
    return 4.0 * value, -4.0 * value


@functools.lru_cache(maxsize=512)
def _number_range(
    style_name: str, base: tuple[tuple[str, Any], ...], name: str, value: float, is_int: bool
) -> tuple[float, float]:
    """(lo, hi) of the slider of number parameter ``name`` starting at ``value``: declared
    bounds where the style declares them, probed ends elsewhere (see the module docstring)."""
    spec = dict(_thawed(style_name, base))
    spec.update(_reading_modes(style_name, name, spec))

    def ok(x: float) -> bool:
        return _error(tuple(spec.items()), name, int(x) if is_int else float(x)) is None

    def settle(end: float) -> float:
        if ok(end):
            return end
        if is_int:  # bisect on whole numbers towards the accepted default
            good, bad = round(value), round(end)
            for _ in range(24):
                if abs(bad - good) <= 1:
                    break
                mid = (good + bad) // 2
                good, bad = (mid, bad) if ok(mid) else (good, mid)
            return float(good)
        good, bad = float(value), end
        for _ in range(7):
            mid = (good + bad) / 2
            good, bad = (mid, bad) if ok(mid) else (good, mid)
        return good

    lo, hi = _span(value, is_int)
    p = _declared(style_name, name)  # a number's declared bounds (None for an undeclared one)
    cut_lo = p is not None and p.lo is not None and p.lo >= lo
    cut_hi = p is not None and p.hi is not None and p.hi <= hi
    lo = float(p.lo) if cut_lo else settle(lo)
    hi = float(p.hi) if cut_hi else settle(hi)
    step = 1.0 if is_int else _step(lo, hi)
    if cut_lo and p.lo_open:
        lo += step
    if cut_hi and p.hi_open:
        hi -= step
    return lo, hi


_LISTED = re.compile(r"expected one of (\[[^\]]*\])")


@functools.lru_cache(maxsize=256)
def _probe_choices(
    style_name: str, base: tuple[tuple[str, Any], ...], name: str
) -> tuple[str, ...]:
    """The strings the style lists for ``name`` in its message for an unknown value, each
    checked by building the style with it; empty when it lists none."""
    p = _declared(style_name, name)
    if getattr(p, "kind", None) == "choice":
        return tuple(p.choices)
    spec = _thawed(style_name, base)
    message = _error(spec, name, "\x00?")
    if message is None:
        return ()
    listed = _LISTED.search(message)
    if listed:
        return tuple(str(c) for c in ast.literal_eval(listed.group(1)))
    words = re.findall(r"[A-Za-z][A-Za-z0-9_\-]*", message.replace(name + ":", "", 1))
    return tuple(w for w in dict.fromkeys(words) if _error(spec, name, w) is None)


def _step(lo: float, hi: float) -> float:
    """A 1-2-5 step giving about 100 positions over [lo, hi]."""
    raw = (hi - lo) / 100.0 if hi > lo else 0.01
    mag = 10.0 ** math.floor(math.log10(raw))
    return next(m * mag for m in (1, 2, 5, 10) if m * mag >= raw)


def parameter_controls(style: Style, spec: Mapping[str, Any] | None = None) -> dict[str, Any]:
    """One ipywidgets control per adjustable parameter of ``style``.

    Parameters
    ----------
    style : Style
        The instance whose current values (``params()``) the controls start from.
    spec : mapping, optional
        The parameters the style was built with (the probes hold them fixed); default
        ``style.params()``.

    Returns
    -------
    dict of str to ipywidgets widget
        ``Checkbox`` for flags, ``IntSlider``/``FloatSlider`` for numbers, ``Dropdown`` for
        listed choices, ``Text`` for other strings, in ``parameters()`` order.
    """
    w = _widgets()
    values = style.params()
    frozen = _frozen(_params_only(values if spec is None else spec))
    controls: dict[str, Any] = {}
    for name in type(style).parameters():
        if name not in values:
            continue
        v = values[name]
        common = _common(name)
        if isinstance(v, (bool, np.bool_)):
            controls[name] = w.Checkbox(value=bool(v), description=name, indent=False)
        elif isinstance(v, (int, np.integer)):
            lo, hi = _number_range(style.name, frozen, name, float(v), True)
            controls[name] = w.IntSlider(value=int(v), min=int(lo), max=int(hi), **common)
        elif isinstance(v, (float, np.floating)) and math.isfinite(v):
            lo, hi = _number_range(style.name, frozen, name, float(v), False)
            step = _step(lo, hi)
            lo, hi = math.ceil(lo / step - 1e-9) * step, math.floor(hi / step + 1e-9) * step
            controls[name] = w.FloatSlider(
                value=float(v), min=min(lo, v), max=max(hi, v), step=step, **common
            )
        elif isinstance(v, str):
            choices = _probe_choices(style.name, frozen, name)
            if choices:
                options = list(choices) + ([v] if v not in choices else [])
                controls[name] = w.Dropdown(
                    options=options, value=v, description=name, style=_LABEL_STYLE
                )
            else:
                common.pop("continuous_update")
                controls[name] = w.Text(value=v, continuous_update=False, **common)
    return controls


_LABEL_STYLE = {"description_width": "initial"}


def _common(name: str) -> dict[str, Any]:
    return {"description": name, "continuous_update": False, "style": _LABEL_STYLE}


# ---------------------------------------------------------------------------- the explorer
class Explorer:
    """The widgets of :func:`explore` and the state they drive.

    Attributes
    ----------
    scene : refnpr.scenes.Scene
    style : Style
        The style of the last render (rebuilt from the controls at each change).
    camera : Camera
        The camera of the last render.
    controls : dict of str to widget
        The style's parameter controls (see :func:`parameter_controls`).
    camera_controls : dict of str to widget
        ``azimuth``, ``elevation`` (degrees), ``distance`` (world units), ``fov_y`` (degrees).
    image : ipywidgets.Image
        The last render, PNG bytes in ``image.value``.
    status : ipywidgets.HTML
        Render time, or the message of the last error (the previous picture stays).
    widget : ipywidgets.Box
        Everything, laid out; what a notebook displays.
    last : refnpr.image.Image or None
    """

    def __init__(
        self,
        scene: Any,
        style: Any = None,
        *,
        width: int = 384,
        height: int = 288,
        spp: int = 1,
        camera: Camera | None = None,
    ) -> None:
        w = _widgets()
        self.scene = as_scene(scene)
        self.spec = _spec_of(style, self.scene)
        self.style = style_from_spec(self.spec)
        self.width, self.height, self.spp = width, height, spp
        self.base_camera = camera if camera is not None else self.scene.camera
        if not isinstance(self.base_camera, Camera):
            raise TypeError(
                f"camera: expected a refnpr.raster.Camera or None, got {type(camera).__name__}"
            )
        self.orbit = orbit_of(self.base_camera)
        self.camera = self.base_camera
        inner = _inner_style(self.style)
        self.controls = parameter_controls(inner, _params_of_spec(self.spec))
        self._start = {k: c.value for k, c in self.controls.items()}
        d = self.orbit.distance
        sliders = {  # value, min, max, step
            "azimuth": (0.0, -180.0, 180.0, 1.0),
            "elevation": (round(self.orbit.elevation, 3), -89.0, 89.0, 1.0),
            "distance": (d, 0.2 * d, 4.0 * d, _step(0.2 * d, 4.0 * d)),
            "fov_y": (float(self.base_camera.fov_y), 5.0, 120.0, 1.0),
        }
        self.camera_controls = {
            name: w.FloatSlider(value=v, min=lo, max=hi, step=step, **_common(name))
            for name, (v, lo, hi, step) in sliders.items()
        }
        self.image = w.Image(format="png", width=width, height=height)
        self.status = w.HTML()
        self.last: Image | None = None
        for c in (*self.controls.values(), *self.camera_controls.values()):
            c.observe(self._on_change, names="value")
        panel = w.VBox(
            [w.HTML("<b>camera</b>"), *self.camera_controls.values()]
            + [w.HTML(f"<b>{self.style.name}</b>"), *self.controls.values(), self.status],
            layout=w.Layout(overflow="auto", max_height=f"{max(height, 320)}px"),
        )
        self.widget = w.HBox([self.image, panel])
        self.render()

    def current_spec(self) -> dict[str, Any]:
        """The style table the controls stand for: the starting table plus every change."""
        changed = {k: c.value for k, c in self.controls.items() if c.value != self._start[k]}
        if self.spec.get("name") == "contoured":
            return {**self.spec, "base": {**_base_table(self.spec), **changed}}
        return {**self.spec, **changed}

    def current_camera(self) -> Camera:
        """The camera the camera sliders stand for."""
        now = {k: float(c.value) for k, c in self.camera_controls.items()}
        fov_y = now.pop("fov_y")
        return orbit_camera(self.base_camera, dataclasses.replace(self.orbit, **now), fov_y)

    def render(self) -> Image | None:
        """Rebuild style and camera from the controls and render into ``image``; on an error
        keep the previous picture and show the message in ``status``."""
        try:
            style = style_from_spec(self.current_spec())
            camera = self.current_camera()
            img = render(self.scene, style, self.width, self.height, self.spp, camera=camera)
        except (TypeError, ValueError) as exc:
            self.status.value = f"<span style='color:#b00'>{html.escape(str(exc), False)}</span>"
            return None
        self.style, self.camera, self.last = style, camera, img
        self.image.value = img.to_png_bytes()
        self.status.value = f"{img.timings.get('total', 0.0) * 1e3:.0f} ms"
        return img

    def _on_change(self, change: Any) -> None:
        self.render()

    def _repr_mimebundle_(self, **kwargs: Any) -> Any:  # a notebook displays the widget
        return self.widget._repr_mimebundle_(**kwargs)


def explore(scene: Any, style: Any = None, **options: Any) -> Explorer:
    """Sliders for ``style``'s parameters and for the camera, re-rendering ``scene`` on change.

    Parameters
    ----------
    scene : Scene, str or path
        A scene, a built-in scene name or a scene TOML file.
    style : Style, str, dict or None
        As for :func:`refnpr.render.render` (None: the scene's style, else the default style).
    width, height : int, keyword-only
        Render size in pixels (default 384 x 288).
    spp : int, keyword-only
        Samples per pixel (a square number; default 1).
    camera : Camera, optional, keyword-only
        The starting camera (default: the scene's); the sliders orbit about its target.

    Returns
    -------
    Explorer
        Displays itself in a notebook; ``.widget`` is the ipywidgets box, ``.controls`` and
        ``.camera_controls`` the sliders, ``.image`` the picture.

    Raises
    ------
    ImportError
        Naming the optional extra ``notebook`` when ipywidgets is not installed.
    """
    return Explorer(scene, style, **options)


# ---------------------------------------------------------------------------- helpers
def _spec_of(style: Any, scene: Any) -> dict[str, Any]:
    """The style as a table ``{"name": ..., **params}`` that rebuilds it."""
    if style is None:
        style = getattr(scene, "style", None) or DEFAULT_STYLE
    if isinstance(style, str):
        return {"name": style}
    if isinstance(style, Mapping):
        if "name" not in style:
            raise ValueError(f"style: a style table needs a 'name' key, got keys {sorted(style)}")
        return dict(style)
    if isinstance(style, Style):
        spec = {"name": style.name, **style.params()}
        try:
            style_from_spec(spec)
        except (TypeError, ValueError):
            spec = {"name": style.name}  # parameters that are not plain values: defaults
        return spec
    raise TypeError(f"style: expected a Style, a style name or a table, got {type(style).__name__}")


def _inner_style(style: Style) -> Style:
    """The style whose parameters get controls (a contoured style's base)."""
    base = getattr(style, "base", None)
    return base if style.name == "contoured" and isinstance(base, Style) else style


def _params_only(spec: Any) -> dict[str, Any]:
    """A style table (mapping or pairs) without its ``name`` and ``contours``."""
    return {k: v for k, v in dict(spec).items() if k not in ("name", "contours")}


def _base_table(spec: Mapping[str, Any]) -> dict[str, Any]:
    """A contoured style table's base style as a table."""
    base = spec.get("base", "toon")
    return {"name": base} if isinstance(base, str) else dict(base)


def _params_of_spec(spec: Mapping[str, Any]) -> dict[str, Any]:
    """The parameters of a style table (a contoured style's: its base's)."""
    return _params_only(_base_table(spec) if spec.get("name") == "contoured" else spec)


class _CallableModule(types.ModuleType):
    """This module, callable as :func:`explore`: the submodule ``refnpr.explore`` and the
    function ``refnpr.explore`` share a name, and whichever of the two an import binds on the
    package, ``refnpr.explore(scene, style)`` works."""

    def __call__(self, *args: Any, **kwargs: Any) -> Explorer:
        return explore(*args, **kwargs)


sys.modules[__name__].__class__ = _CallableModule
