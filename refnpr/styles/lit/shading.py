"""Toon and smooth shading of a whole frame in one numba pass (``_kernels.shade_toon_for``,
``_kernels.shade_smooth_for``): the kernels' records and tables, built once per frame."""

from __future__ import annotations

from typing import Any

import numpy as np

from refnpr._jit import frozen
from refnpr.formulas import lighting
from refnpr.formulas.threshold import step_n

from .._common import keep_all, kept_out, needs_position, rgba_out
from .._frame import frame_record
from ..albedo import albedo_channels, albedo_grid
from ..base import ShadeContext, Style
from . import _kernels as K

__all__ = ["lit_rgba", "lake_ramp", "LitStyle"]

#: Largest integer shininess whose f_s the kernel computes by multiplications (then checked).
_POW_INT_MAX = 1024
#: Relative widening of the breakpoints of T_n in base space (see ``_step_edges``).
_EDGE_MARGIN = 1e-7
#: Below this shininess the widening is too small against pow's rounding: always pow.
_EDGE_MIN_SHININESS = 1e-4


def lake_ramp(n: int, t: float, size: int = 1024) -> np.ndarray:
    """Lake et al.'s ramp of the toon style: n + 1 tones 0, 1/n, ..., 1 split at (k + t) / n,
    ``size`` texels (``lighting.toon_ramp_texture``), float64."""
    bounds = (np.arange(n) + t) / n
    ramp = lighting.toon_ramp_texture(bounds, np.arange(n + 1) / n, size=size)
    return np.ascontiguousarray(ramp, dtype=np.float64)


def _step_edges(
    shininess: np.ndarray, n: int, t: float
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Where T_n(base ** p, t, n) (eq. 4 of a specular term) is known without pow.

    T_n (``threshold.step_n``) is a monotone step function of f_s whose steps lie at the
    breakpoints c = k / n and (k + t) / n; in float64 it is constant on each open interval
    between them up to a few ulps from its ends. With b_j = c_j ** (1 / p), a base in
    [b_{j-1} (1 + m), b_j (1 - m)] (m = 1e-7) has pow(base, p) inside (c_{j-1}, c_j) at a
    relative distance of about p m >= 1e-11 from both ends (pow is accurate to an ulp), so its
    tone is T_n of the interval's midpoint, ``tones[j]``. ``tones[j] = -1`` marks the intervals
    where pow must be evaluated: the first one when t = 0 (T_n jumps at f_s = 0 and pow may
    underflow to 0 there) and the last one (f_s above every breakpoint); objects with
    shininess < 1e-4, or whose widened edges overlap or underflow, evaluate pow everywhere.

    Returns ``edge_lo (O, B)``, ``edge_hi (O, B)``, ``tones (B + 1,)``, float64.
    """
    k = np.arange(n + 2, dtype=np.float64)
    c = np.unique(np.concatenate([k / n, (k[: n + 1] + t) / n]))
    mid = np.concatenate([[-1.0], (c[:-1] + c[1:]) / 2, [2.0]])
    # T_n by the kernels' own device function, with their argument types (float64, float64,
    # int64): the kernel then reuses this compilation; the numpy face would compile its
    # elementwise loop (0.3 s of a cold start) for these few values
    scalar = step_n.scalar
    tones = np.array([scalar(float(m), float(t), int(n)) for m in mid], dtype=np.float64)
    tones[0] = tones[-1] = -1.0  # below 0 (unreachable), above every breakpoint
    if t == 0.0:
        tones[1] = -1.0
    p = np.asarray(shininess, dtype=np.float64)[:, None]
    with np.errstate(divide="ignore", over="ignore"):
        b = c[None, :] ** (1.0 / p)
    edge_lo = b * (1.0 - _EDGE_MARGIN)
    edge_hi = b * (1.0 + _EDGE_MARGIN)
    # pow everywhere for a tiny shininess, or where the widened edges overlap or underflow
    # (b_j = 0 for j >= 1 when c_j ** (1 / p) is below the smallest float)
    always = (p[:, 0] < _EDGE_MIN_SHININESS) | ~np.all(edge_hi[:, :-1] < edge_lo[:, 1:], axis=1)
    edge_lo[always] = -np.inf
    edge_hi[always] = np.inf
    return np.ascontiguousarray(edge_lo), np.ascontiguousarray(edge_hi), tones


def _out(ctx: Any, out: np.ndarray | None, shape: tuple[int, int]) -> np.ndarray:
    if out is None:
        return rgba_out(ctx, shape)  # written in full by the kernel
    if (
        not isinstance(out, np.ndarray)
        or out.shape != shape + (4,)
        or out.dtype not in (np.float32, np.float64)
        or not out.flags.c_contiguous
        or not out.flags.writeable
    ):
        raise ValueError(
            f"out: expected a writable C-contiguous {shape + (4,)} float32 array, got "
            f"{type(out).__name__} {getattr(out, 'shape', '')} {getattr(out, 'dtype', '')}; "
            "pass None for a new one"
        )
    return out


def lit_rgba(
    ctx: Any, record: Any, *, smooth: bool, pow_int: bool = True, out: np.ndarray | None = None
) -> np.ndarray:
    """Smooth (Veryovka eq. 1; ``record`` of the smooth style) or toon shading (eqs. 2-4 or Lake
    et al.'s ramp; ``record`` of the toon style) of every sample in one numba pass: (nH, nW, 4)
    float32 RGBA, colours clipped to [0, 1], alpha 1 where covered and everything 0 elsewhere.

    ``pow_int``: smooth shading forms f_s of an integer shininess by multiplications, checked
    against pow's float32 result (False: pow everywhere; a float64 ``out`` is pow too).
    ``out``, optional: a C-contiguous (nH, nW, 4) float32 (or float64, for tests of the
    arithmetic) array to write into and return, every element overwritten (repeated frames).
    """
    scene = ctx.scene
    specular = bool(record.specular)
    need_pos = needs_position(scene, specular)
    frame = frame_record(ctx, ("normal", "position") if need_pos else ("normal",))
    shape = frame.cover.shape
    out = _out(ctx, out, shape)
    m = frame.materials
    color = frame.lights.color
    # the objects and lights with a specular colour (m_s and l_i both nonzero in a channel):
    # elsewhere the kernels skip the specular term, whose value is a signed zero there
    spec_on = np.ascontiguousarray(
        np.any((m.specular[:, None, :] != 0.0) & (color[None, :, :] != 0.0), axis=2)
    )
    none = np.zeros((1, 0))
    albedo = albedo_grid(ctx)  # the colour maps' factors (None: no object has one)
    albedo = np.ones((0, 0, 3)) if albedo is None else albedo
    if smooth:
        # f_s = base ** shininess by multiplications where the shininess is a small integer,
        # checked against pow's float32 result in the kernel (a float64 ``out``: pow itself)
        p = m.shininess
        whole = (p == np.floor(p)) & (p >= 1) & (p <= _POW_INT_MAX)
        powers = np.where(whole, p, 0).astype(np.int64)
        terms = (m.ambient, m.diffuse, m.specular, color)
        if (
            not (pow_int and specular)
            or out.dtype != np.float32
            or any(np.any(a < 0) for a in terms)
        ):
            powers[:] = 0
        spec_mag = 1.01 * np.abs(m.specular[:, None, :] * color[None, :, :]).sum(axis=2)
        spec_mag = np.ascontiguousarray(spec_mag)
        tables = frozen(
            K.Tables(np.zeros(1), none, none, np.zeros(1), spec_on, powers, spec_mag, albedo)
        )
        kept = kept_out(ctx, shape, 2)
        K.shade_smooth_for(albedo.shape[0] > 0, kept.shape[0] > 0)(frame, record, tables, out, kept)
        keep_all(ctx, kept, ("tone",))
        return out
    ramp = lake_ramp(record.n, record.t) if record.mode == K.LAKE else np.zeros(1)
    edge_lo, edge_hi, tones = none, none, np.zeros(1)
    if specular and record.mode != K.LAKE:
        edge_lo, edge_hi, tones = _step_edges(m.shininess, record.n, record.t)
    no_powers = np.zeros(1, dtype=np.int64)
    tables = frozen(
        K.Tables(ramp, edge_lo, edge_hi, tones, spec_on, no_powers, np.zeros((1, 1)), albedo)
    )
    kept = kept_out(ctx, shape, 2)
    K.shade_toon_for(albedo.shape[0] > 0, kept.shape[0] > 0)(frame, record, tables, out, kept)
    keep_all(ctx, kept, ("tone", "toon_tone"))
    return out


class LitStyle(Style):
    """What the toon and smooth styles share: their parameters ``self.p`` (validated by the
    subclass's ``PARAMS``; also attributes, ``style.n``), the channels they read and one numba
    pass (:func:`lit_rgba`)."""

    #: Smooth shading (eq. 1) rather than toon (eqs. 2-4, Lake's ramp).
    smooth: bool = False

    def __init__(self, **params: Any) -> None:
        self.p = self._settled(self.PARAMS.validate(params))
        self._params = self.p.as_dict()
        for name in self.PARAMS.names:
            setattr(self, name, self.p[name])

    @staticmethod
    def _settled(p: Any) -> Any:
        """``p`` with the values the chosen modes fix."""
        return p

    def requires(self, scene: Any) -> frozenset[str]:
        req = {"normal", "mesh_id"}
        if needs_position(scene, self.p.specular):
            req.add("position")
        req |= albedo_channels(scene)  # the colour maps multiplying m_a and m_d
        return frozenset(req)

    def shade(self, ctx: ShadeContext, out: np.ndarray | None = None) -> np.ndarray:
        record = self.PARAMS.record(self.p)
        return lit_rgba(ctx, record, smooth=self.smooth, out=out)  # one numba pass
