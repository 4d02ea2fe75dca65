"""Per-stroke cubic fits from aggregated moments (TAMISS sec. 3.2, eq. 1).

Private helper of :mod:`refnpr.formulas.tamiss` (which re-exports the public names).
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from .._face import elementwise
from .._validate import (
    as_float,
    as_vectors,
    check_bool,
    check_int,
    check_scalar,
    describe,
    result_dtype,
)
from .curve import cubic, cubic_slope
from .moments import N_REGRESSORS, fragment_regressors, group_ids, normalize_t
from .segments import visible_segments
from .solve import cg_kernel, moment_matrix, visibility_prior

__all__ = ["LEGENDRE", "StrokeFit", "fit_strokes", "fit_fragments", "fit_stroke"]

_P, _BX, _BY = slice(0, 7), slice(7, 11), slice(11, 15)


@dataclass(frozen=True)
class StrokeFit:
    """Fitted cubic strokes (one or a batch).

    Attributes
    ----------
    c_x, c_y, c_v : (..., 4) float, coefficients of x, y and visibility in the fit parameter
    t_min, t_max : (...) float, the stroke's fragment range [min t_i, max t_i]
    count : (...) float, number of fragments
    basis : {"centred", "raw"}; the fit parameter is s = normalize_t(t, t_min, t_max) or t itself
    prior_weight : float, zero-visibility points per fragment used for c_v

    ``batch_shape`` is ``c_x.shape[:-1]``. Methods take t in the original stroke parameter. For a
    single stroke (batch shape ()) t may have any shape; for a batch, the last axis of t holds
    samples and the rest broadcasts against the batch shape (t of shape (S, K) or (K,) for S strokes).
    """

    c_x: np.ndarray
    c_y: np.ndarray
    c_v: np.ndarray
    t_min: np.ndarray
    t_max: np.ndarray
    count: np.ndarray
    basis: str = "centred"
    prior_weight: float = 1.0

    @property
    def batch_shape(self) -> tuple:
        return self.c_x.shape[:-1]

    def take(self, idx) -> StrokeFit:
        """The strokes ``idx`` (an index or an index array) of a batch."""
        return replace(self, **{k: np.asarray(np.asarray(getattr(self, k))[idx]) for k in _ARRAYS})

    def _expand(self, a: np.ndarray) -> np.ndarray:
        return a if self.batch_shape == () else a[..., None]

    def param(self, t) -> np.ndarray:
        """The fit parameter at t (s in [-1, 1] over [t_min, t_max] for the centred basis)."""
        dt = self.c_x.dtype
        t_ = as_float("t", t, finite=True).astype(dt)
        if self.basis == "raw":
            return t_
        lo, hi = self._expand(self.t_min), self._expand(self.t_max)
        return elementwise(normalize_t.scalar, dt, t_, lo, hi, dt.type(0.5), compute=dt)

    def _poly(self, c: np.ndarray, s: np.ndarray, slope: bool = False) -> np.ndarray:
        c = c if self.batch_shape == () else c[..., None, :]
        return (cubic_slope if slope else cubic)(c, s)  # r(t) = c^T (1, t, t^2, t^3)

    def evaluate(self, t):
        """Screen position (x, y) at stroke parameter t."""
        s = self.param(t)
        return self._poly(self.c_x, s), self._poly(self.c_y, s)

    def visibility(self, t) -> np.ndarray:
        """The fitted visibility v(t) (sec. 3.2)."""
        return self._poly(self.c_v, self.param(t))

    def derivative(self, t):
        """(dx/dt, dy/dt) at t."""
        s = self.param(t)
        dt = self.c_x.dtype
        if self.basis == "raw":
            ds_dt = dt.type(1)
        else:
            width = self._expand(self.t_max - self.t_min)
            ok = width > 0
            ds_dt = np.where(ok, dt.type(2) / np.where(ok, width, dt.type(1)), dt.type(0))
        return (
            self._poly(self.c_x, s, slope=True) * ds_dt,
            self._poly(self.c_y, s, slope=True) * ds_dt,
        )

    def visible_segments(self, threshold: float | None = None):
        """Up to two visible t intervals where v >= threshold (sec. 3.2).

        Returns ``segments (..., 2, 2)`` of (t_start, t_end), NaN where absent, and ``count (...)``.
        The default threshold, 1 / (2 (1 + prior_weight)) (1/4 for the default prior), is half the
        value v takes on a fully visible stroke, which is the lowest plateau of visible parts;
        hidden parts tend to 0 (see :func:`fit_strokes`).
        """
        if threshold is None:
            threshold = 0.5 / (1.0 + self.prior_weight)
        if self.basis == "raw":
            return visible_segments(self.c_v, threshold=threshold, lo=self.t_min, hi=self.t_max)
        seg, count = visible_segments(self.c_v, threshold=threshold)
        lo, hi = self.t_min[..., None, None], self.t_max[..., None, None]
        half = (hi - lo) / 2
        return (lo + half + seg * half).astype(self.c_x.dtype), count


_ARRAYS = ("c_x", "c_y", "c_v", "t_min", "t_max", "count")
_BASES = ("legendre", "monomial", "raw")

#: Row i holds the Legendre polynomial P_i(s) in monomials (1, s, s^2, s^3).
LEGENDRE = np.array(
    [[1.0, 0.0, 0.0, 0.0], [0.0, 1.0, 0.0, 0.0], [-0.5, 0.0, 1.5, 0.0], [0.0, -1.5, 0.0, 2.5]]
)


def _check_basis(basis: str) -> None:
    if basis not in _BASES:
        raise ValueError(
            f"basis: expected one of {_BASES}, got {basis!r}; 'legendre' is the accurate default, "
            "'monomial' and 'raw' exist to show where float32 breaks"
        )


def _solve(A: np.ndarray, b: np.ndarray, iterations: int, basis: str) -> np.ndarray:
    """CG on A c = b (…, 4, 4) in monomial coefficients; 'legendre' changes basis and scales."""
    dt = b.dtype
    rtol = 8 * float(np.finfo(dt).eps)
    if basis != "legendre":
        return cg_kernel(A, b, iterations, rtol)
    L = LEGENDRE.astype(dt)
    AL = L @ A @ L.T  # normal matrix of the Legendre basis
    AL = (AL + np.swapaxes(AL, -1, -2)) * dt.type(0.5)
    bL = np.einsum("ij,...j->...i", L, b)
    diag = np.diagonal(AL, axis1=-2, axis2=-1)
    ok = diag > 0
    d = np.where(ok, dt.type(1) / np.sqrt(np.where(ok, diag, dt.type(1))), dt.type(0))
    As = AL * d[..., :, None] * d[..., None, :]  # Jacobi (diagonal) scaling
    y = cg_kernel(As, bL * d, iterations, rtol)
    return np.einsum("ji,...j->...i", L, y * d)  # back to monomials of s


def fit_strokes(
    moments,
    t_min,
    t_max,
    *,
    origin=None,
    iterations: int = 4,
    basis: str = "legendre",
    prior_weight: float = 1.0,
) -> StrokeFit:
    """Fit many strokes at once from their aggregated moments (sec. 3.2, eq. 1).

    Solves A c_x = b_x, A c_y = b_y and (A + D) c_v = b_v with b_v = sum t_i (v_i = 1) by
    ``iterations`` conjugate-gradient steps, where D = :func:`visibility_prior` for
    n = ``prior_weight`` * (number of fragments) zero-visibility points spread over the stroke's
    range. With n equal to the fragment count, v(t) is about 1 / (1 + f) >= 1/2 on visible parts
    (f: visible fraction of the range) and about 0 on hidden parts.

    Parameters
    ----------
    moments : (..., 15) float
        Per-stroke sums of :func:`fragment_regressors` (of s, x - origin_x, y - origin_y).
    t_min, t_max : (...) float, per-stroke fragment range of t
    origin : (..., 2) float, optional
        The point subtracted from (x, y) before summing (default 0); added back to c_x, c_y.
    iterations : int, CG iterations (the paper: 4)
    basis : {"legendre", "monomial", "raw"}
        ``"legendre"`` (default): the moments are in s in [-1, 1]; the 4 x 4 systems are changed to
        the Legendre basis P_0..P_3 and diagonally scaled before CG (condition number near 1
        instead of ~100), the solution is returned in monomials of s. ``"monomial"``: moments in s,
        CG on the monomial system as printed (DESIGN's fix alone). ``"raw"``: moments in raw t,
        the paper verbatim. The last two exist to show where float32 breaks.
    prior_weight : float >= 0

    Returns
    -------
    StrokeFit with batch shape ``moments.shape[:-1]``, float32 if ``moments`` is float32.
    """
    M = as_float("moments", moments, finite=True)
    if M.ndim < 1 or M.shape[-1] != N_REGRESSORS:
        raise ValueError(
            f"moments: expected shape (..., {N_REGRESSORS}) (summed fragment_regressors), "
            f"got {describe(M)}"
        )
    _check_basis(basis)
    iterations = check_int("iterations", iterations, lo=0)
    prior_weight = check_scalar("prior_weight", prior_weight, lo=0.0)
    dt = M.dtype
    batch = M.shape[:-1]
    lo = np.broadcast_to(as_float("t_min", t_min, finite=True).astype(dt), batch)
    hi = np.broadcast_to(as_float("t_max", t_max, finite=True).astype(dt), batch)
    if np.any(lo > hi):
        raise ValueError("t_min, t_max: expected t_min <= t_max for every stroke; swap them")
    if origin is None:
        o = np.zeros(batch + (2,), dtype=dt)
    else:
        o = as_vectors("origin", origin, 2, finite=True).astype(dt)
        o = np.broadcast_to(o, batch + (2,))
    A = moment_matrix(M[..., _P])  # eq. 1: A = sum t_i t_i^T
    b = np.stack([M[..., _BX], M[..., _BY]], axis=-2)  # eq. 1: b = sum t_i x_i, sum t_i y_i
    c_xy = _solve(np.broadcast_to(A[..., None, :, :], batch + (2, 4, 4)), b, iterations, basis)
    c_xy[..., 0] += o  # undo the origin shift
    count = M[..., 0]
    n = count * dt.type(prior_weight)
    if basis == "raw":
        D = visibility_prior(lo, hi, n)
    else:
        D = visibility_prior(np.full(batch, -1, dt), np.full(batch, 1, dt), n)
    c_v = _solve(A + D, M[..., 0:4], iterations, basis)  # sec. 3.2: b = (A + D) c_v, v_i = 1
    return StrokeFit(
        c_x=c_xy[..., 0, :],
        c_y=c_xy[..., 1, :],
        c_v=c_v,
        t_min=np.array(lo),
        t_max=np.array(hi),
        count=np.array(count),
        basis="raw" if basis == "raw" else "centred",
        prior_weight=prior_weight,
    )


def fit_fragments(
    ids,
    t,
    x,
    y,
    *,
    iterations: int = 4,
    basis: str = "legendre",
    centre_xy: bool = True,
    prior_weight: float = 1.0,
):
    """Fit every stroke of a fragment stream (the pipeline's entry point).

    Two passes, as on the GPU: min/max blending of t (and of x, y) per stroke, then additive
    blending of the regressors in the centred parameter s, relative to the centre of the stroke's
    fragment bounding box (``centre_xy``); then :func:`fit_strokes`.

    Parameters
    ----------
    ids : (n,) int, stroke id per fragment
    t, x, y : (n,) float, stroke parameter and pixel position; float32 throughout if all float32
    iterations, basis, prior_weight : see :func:`fit_strokes`
    centre_xy : bool
        Subtract the per-stroke bounding-box centre from (x, y) before summing (default). Pixel
        coordinates in the thousands otherwise dominate the float32 sums.

    Returns
    -------
    stroke_ids : (S,) ascending
    fit : StrokeFit with batch shape (S,)
    """
    t_, x_, y_ = (as_float(k, v, finite=True) for k, v in (("t", t), ("x", x), ("y", y)))
    n = np.asarray(ids).shape[0] if np.ndim(ids) == 1 else -1
    for name, v in (("t", t_), ("x", x_), ("y", y_)):
        if v.shape != (n,):
            raise ValueError(
                f"{name}: expected shape ({n},) (one value per fragment id), got {describe(v)}"
            )
    _check_basis(basis)
    dt = result_dtype(t_, x_, y_)
    t_, x_, y_ = t_.astype(dt), x_.astype(dt), y_.astype(dt)
    uid, order, starts, inverse = group_ids(ids)
    if uid.size == 0:
        raise ValueError("ids: expected at least one fragment, got none")
    lo = np.minimum.reduceat(t_[order], starts)  # min blending pass
    hi = np.maximum.reduceat(t_[order], starts)  # max blending pass
    if check_bool("centre_xy", centre_xy):
        xy = np.stack([x_, y_], axis=-1)[order]
        o = (np.minimum.reduceat(xy, starts) + np.maximum.reduceat(xy, starts)) * dt.type(0.5)
    else:
        o = np.zeros((uid.size, 2), dtype=dt)
    s = t_ if basis == "raw" else normalize_t(t_, lo[inverse], hi[inverse])
    R = fragment_regressors(s, x_ - o[inverse, 0], y_ - o[inverse, 1])
    M = np.add.reduceat(R[order], starts, axis=0)  # additive blending pass
    fit = fit_strokes(
        M, lo, hi, origin=o, iterations=iterations, basis=basis, prior_weight=prior_weight
    )
    return uid, fit


def fit_stroke(
    t,
    x,
    y,
    iterations: int = 4,
    *,
    basis: str = "legendre",
    centre_xy: bool = True,
    prior_weight: float = 1.0,
) -> StrokeFit:
    """Fit one stroke to its fragments (sec. 3.2).

    Parameters
    ----------
    t : (n,) float, stroke parameter of each fragment (n >= 1)
    x, y : (n,) float, pixel positions
    iterations : int, CG iterations (4 in the paper)
    basis : {"legendre", "monomial", "raw"}, see :func:`fit_strokes`;
        ``basis="raw", centre_xy=False`` is the paper verbatim (raw monomials of t).
    centre_xy : bool, see :func:`fit_fragments`
    prior_weight : float, see :func:`fit_strokes`

    Returns
    -------
    StrokeFit with batch shape (); ``.evaluate(t) -> (x, y)``.
    """
    t_ = as_float("t", t, finite=True)
    if t_.ndim != 1 or t_.size < 1:
        raise ValueError(f"t: expected shape (n,) with n >= 1, got {describe(t_)}")
    _, fit = fit_fragments(
        np.zeros(t_.shape[0], dtype=np.int64),
        t,
        x,
        y,
        iterations=iterations,
        basis=basis,
        centre_xy=centre_xy,
        prior_weight=prior_weight,
    )
    return fit.take(0)
