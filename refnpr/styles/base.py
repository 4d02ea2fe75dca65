"""What every style shares: the Style interface, the per-frame shading context, the registry.

A style composes formulas on a G-buffer. It declares the channels it ``requires``; the renderer
rasterizes exactly their union, so a flat toon render never pays for derivatives and a scene
without textures never interpolates uv.
"""

from __future__ import annotations

import dataclasses
import functools
import inspect
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from typing import Any, ClassVar

import numpy as np

from ._declare import short_repr
from ._names import check_known, renamed_params

__all__ = [
    "Style",
    "ShadeContext",
    "register",
    "get_style",
    "get_style_class",
    "list_styles",
    "style_from_spec",
    "nested_style",
]


class Style:
    """Base class of shading styles.

    Subclasses set ``name`` (registry key) and implement :meth:`requires` and :meth:`shade`.
    Parameters are keyword arguments of ``__init__`` validated there (clear ``ValueError``).
    """

    name: ClassVar[str] = ""
    description: ClassVar[str] = ""
    #: Deprecated parameter names -> current names, still accepted with a DeprecationWarning.
    renamed: ClassVar[Mapping[str, str]] = {}
    #: Deprecated names whose value changed form; the style converts them itself (with a warning).
    deprecated: ClassVar[tuple[str, ...]] = ()
    #: The style's parameter declaration (:class:`refnpr.styles._declare.Params`), if it has one.
    PARAMS: ClassVar[Any] = None
    #: The intermediates the style stores when asked (``ShadeContext.keep``): channel name ->
    #: what it holds, one line (the EXR passes of ``render(..., passes=True)``).
    INTERMEDIATES: ClassVar[Mapping[str, str]] = {}

    @classmethod
    def parameters(cls) -> tuple[str, ...]:
        """The parameter names the style takes (current names; sorted)."""
        if cls.PARAMS is not None:
            return tuple(sorted(cls.PARAMS.names))
        sig = inspect.signature(inspect.unwrap(cls.__init__))
        kinds = (inspect.Parameter.VAR_POSITIONAL, inspect.Parameter.VAR_KEYWORD)
        return tuple(
            sorted(n for n, p in sig.parameters.items() if n != "self" and p.kind not in kinds)
        )

    def requires(self, scene: Any) -> frozenset[str]:
        """G-buffer channels this style reads for ``scene``."""
        raise NotImplementedError

    def raster_options(self, scene: Any) -> dict[str, Any]:
        """Extra keyword arguments for ``rasterize`` (texture_size, line_period, ...)."""
        return {}

    def shade(self, ctx: ShadeContext) -> np.ndarray:
        """Per-sample straight-alpha linear RGBA, ``(n H, n W, 4)`` float32; alpha 0 where empty."""
        raise NotImplementedError

    # -- sequences: a still is frame 0 of a one-frame sequence (DESIGN, "Frames, state and speed")
    def for_frame(self, scene: Any, prev_scene: Any | None) -> Style:
        """This style configured for one frame of a sequence.

        A sequence driver calls it once per frame, before rasterizing, with the frame's still
        scene and the previous frame's (None on the first frame). Styles whose per-frame inputs
        come from the previous frame (X-Toon's optical flow: the previous camera and object
        transforms) return a configured copy; the default is the style itself.
        """
        return self

    def initial_state(self) -> Any:
        """The state carried into the first frame of a sequence (None: stateless)."""
        return None

    def state_frames(self) -> int | None:
        """For a stateful style, how many frames back its state reaches: K when the state at
        frame f, built by shading frames f - K .. f - 1 from :meth:`initial_state`, equals the
        state carried from frame 0 (a sequence driver resumes K frames before the first frame
        it must render); None (the default): the whole history, resume from frame 0."""
        return None

    def shade_frame(self, ctx: ShadeContext, state: Any) -> tuple[np.ndarray, Any]:
        """Shade one frame of a sequence from the previous frame's ``state``.

        Returns the per-sample RGBA (as :meth:`shade`) and the state for the next frame.
        Stateless styles (the default) return ``(self.shade(ctx), state)``; a stateful style
        (TAMISS hash tables and aggregate history) returns its updated state explicitly, so
        nothing is kept in globals.
        """
        return self.shade(ctx), state

    def params(self) -> dict[str, Any]:
        """The parameters this instance was built with (for golden metadata and repr)."""
        return dict(getattr(self, "_params", {}))

    def __repr__(self) -> str:
        args = ", ".join(f"{k}={v!r}" for k, v in self.params().items())
        return f"{type(self).__name__}({args})"


@dataclass(frozen=True, eq=False)
class ShadeContext:
    """Everything a style may read for one frame: the G-buffer and the scene's lights/materials.

    Attributes
    ----------
    gb : refnpr.raster.GBuffer
    scene : refnpr.scenes.Scene
        Provides ``camera``, ``lights``, ``ambient`` (l_a) and ``objects[i].material``.
    spare : list of ndarray
        Buffers :meth:`rgba_out` hands out (a render context's, kept from its last frame);
        empty by default.
    intermediates : dict or None
        Where a style puts the per-sample values of its formulas that a compositor may want
        (:meth:`keep`): a dict to fill when the caller asks for them (``render(...,
        passes=True)``), None (the default) when nobody reads them, and then a style computes
        none of them.
    prefix : str
        What :meth:`keep` puts before a name: ``""``, or ``"base."`` in the context of a style
        drawn under another (:meth:`under`).
    """

    gb: Any
    scene: Any
    spare: list = field(default_factory=list, repr=False)
    intermediates: dict | None = field(default=None, repr=False)
    prefix: str = field(default="", repr=False)

    @property
    def wants_intermediates(self) -> bool:
        """Whether the caller reads the style's intermediates (:meth:`keep` stores them)."""
        return self.intermediates is not None

    def keep(self, name: str, samples: np.ndarray) -> None:
        """Store the intermediate ``name`` of this frame's shading, if the caller asked for
        intermediates (else nothing).

        Parameters
        ----------
        name : str
            Its channel name (``Style.INTERMEDIATES`` documents the style's).
        samples : (nH, nW) float, or int32 / int64 for ids
            One value per sample of the G-buffer's grid; 0 (ids: -1) where nothing is covered.
            Floats are kept as float32, integers as they are.
        """
        if self.intermediates is None:
            return
        a = np.asarray(samples)
        if a.shape != tuple(self.gb.sample_shape):
            raise ValueError(
                f"intermediate {name!r}: expected the sample grid {tuple(self.gb.sample_shape)}, "
                f"got shape {a.shape}"
            )
        if a.dtype not in (np.int32, np.int64):
            a = a.astype(np.float32)
        self.intermediates[self.prefix + name] = a

    def under(self, prefix: str = "base") -> ShadeContext:
        """This context for a style drawn under another one (the strokes' ``base``): the same
        frame, scene and buffers, the intermediates it keeps named ``prefix.name`` beside the
        top style's (``base.tone`` under ``darkness``)."""
        if self.intermediates is None:
            return self
        return dataclasses.replace(self, prefix=f"{self.prefix}{prefix}.")

    def rgba_out(self, shape: tuple[int, int]) -> np.ndarray:
        """A C-contiguous ``shape + (4,)`` float32 array for a style's samples (``shape``: the
        sample grid, (nH, nW)), to be written in full.

        The first call of a frame takes a spare buffer of that shape when the caller gave one
        (``RenderContext`` gives the one it kept from its previous frame: a 1920x1080 spp 4
        frame then pays no ~130 MB of first-touch page faults), later calls and plain
        ``render`` get a new array. Its contents are undefined, and it is only lent for the
        frame: a style must not keep it (nor anything viewing it) past its ``shade``.
        """
        shape = tuple(int(k) for k in shape) + (4,)
        while self.spare:
            buf = self.spare.pop()
            if (
                isinstance(buf, np.ndarray)
                and buf.shape == shape
                and buf.dtype == np.float32
                and buf.flags.c_contiguous
                and buf.flags.writeable
            ):
                return buf
        return np.empty(shape, dtype=np.float32)

    @property
    def mask(self) -> np.ndarray:
        """(nH, nW) bool: samples covered by a triangle (needs ``tri_id`` or ``mesh_id``)."""
        if "tri_id" in self.gb:
            return self.gb["tri_id"] >= 0
        return self.gb["mesh_id"] >= 0

    def material_field(self, attr: str, mask: np.ndarray | None = None) -> np.ndarray:
        """Material property ``attr`` of the object each sample shows (needs ``mesh_id``):
        (nH, nW) for scalars, (nH, nW, C) for tuples, zero where empty; or (K[, C]) at the
        samples where ``mask`` is true."""
        values = np.array(
            [np.asarray(getattr(o.material, attr), dtype=np.float64) for o in self.scene.objects]
        )
        mesh_id = self.gb["mesh_id"]
        if mask is not None:
            return values[np.maximum(mesh_id[mask], 0)]
        out = values[np.maximum(mesh_id, 0)]
        out[mesh_id < 0] = 0.0
        return out


_REGISTRY: dict[str, Callable[..., Style]] = {}


def register(cls: type[Style]) -> type[Style]:
    """Class decorator adding a style to the registry under ``cls.name``.

    Its ``__init__`` is wrapped so that, for direct construction as for :func:`get_style`,
    deprecated names (``cls.renamed``) are accepted with a ``DeprecationWarning`` and an unknown
    name is a ``TypeError`` that lists the valid ones (``cls.parameters()``).
    """
    if not cls.name:
        raise ValueError(f"{cls.__name__}: a registered style needs a non-empty `name`")
    if cls.PARAMS is not None:  # its declaration validates names and values
        self_param = inspect.Parameter("self", inspect.Parameter.POSITIONAL_OR_KEYWORD)
        sig = cls.PARAMS.signature()
        cls.__init__.__signature__ = sig.replace(parameters=[self_param, *sig.parameters.values()])
    elif "__init__" in cls.__dict__:
        init = cls.__init__

        @functools.wraps(init)
        def __init__(self, *args: Any, **params: Any) -> None:
            where = f"style {cls.name!r}"
            params = renamed_params(where, params, cls.renamed)
            check_known(where, set(params) - set(cls.deprecated), cls.parameters())
            init(self, *args, **params)

        cls.__init__ = __init__
    _REGISTRY[cls.name] = cls
    return cls


def list_styles() -> dict[str, str]:
    """Registered style names -> one-line descriptions."""
    from . import _all  # noqa: F401  (imports every style module so they register)

    return {name: cls.description for name, cls in sorted(_REGISTRY.items())}


def get_style_class(name: str) -> type[Style]:
    """The registered style class ``name`` (a ValueError listing the styles otherwise)."""
    from . import _all  # noqa: F401

    if not isinstance(name, str):
        raise TypeError(f"style: expected a style name (str), got {type(name).__name__}")
    if name not in _REGISTRY:
        raise ValueError(f"style: unknown style {name!r}; available styles: {sorted(_REGISTRY)}")
    return _REGISTRY[name]


def get_style(name: str, **params: Any) -> Style:
    """Instantiate a registered style by name with keyword parameters."""
    cls = get_style_class(name)
    try:
        return cls(**params)
    except TypeError as exc:
        msg = str(exc)
        raise TypeError(
            msg if msg.startswith(f"style {name!r}:") else f"style {name!r}: {msg}"
        ) from None


def style_from_spec(spec: Any) -> Style:
    """A Style from an instance, a name, or a mapping ``{"name": ..., **params}`` (scene files)."""
    if isinstance(spec, Style):
        return spec
    if isinstance(spec, str):
        return get_style(spec)
    if isinstance(spec, dict):
        params = dict(spec)
        name = params.pop("name", None)
        if name is None:
            raise ValueError(f"style: a style table needs a 'name' key, got keys {sorted(spec)}")
        contours = params.pop("contours", None) if name != "contoured" else None
        style = get_style(name, **params)
        # None and False (by identity: 0 == False) mean no contour layer; any other value is
        # the layer's to validate
        if contours is not None and contours is not False and contours is not np.False_:
            return get_style("contoured", base=style, contours=contours)
        return style
    raise TypeError(f"style: expected a Style, a name or a table, got {type(spec).__name__}")


def nested_style(name: str, value: Any) -> Style:
    """The style a parameter ``name`` (``base``) holds: a Style, a style name or a table
    ``{name = ..., **params}``; errors name the parameter and the value."""
    if not isinstance(value, (Style, str, dict)):
        raise TypeError(
            f"{name}: expected a style name, a table {{name = ..., ...}} or a Style, got "
            f"{type(value).__name__} {short_repr(value)}"
        )
    try:
        return style_from_spec(value)
    except (TypeError, ValueError) as exc:
        raise type(exc)(f"{name}: {exc} (got {short_repr(value)})") from None
