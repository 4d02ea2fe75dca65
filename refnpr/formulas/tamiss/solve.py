"""Batched conjugate gradients and the visibility prior of TAMISS (Szécsi et al., sec. 3.2).

Private helper of :mod:`refnpr.formulas.tamiss` (which re-exports the public names).
"""

from __future__ import annotations

import numpy as np

from .._validate import as_float, check_int, check_scalar, describe, result_dtype

__all__ = ["cg_solve", "visibility_prior", "moment_matrix"]


def moment_matrix(power_sums) -> np.ndarray:
    """The normal matrix A = sum_i t_i t_i^T of eq. 1 from power sums.

    Parameters
    ----------
    power_sums : (..., 2k - 1) float
        P_m = sum_i t_i^m for m = 0 .. 2k - 2 (k = 4 for cubics: 7 sums).

    Returns
    -------
    A : (..., k, k), A[i, j] = P_{i+j} (a Hankel matrix), same dtype.
    """
    P = as_float("power_sums", power_sums)
    m = P.shape[-1] if P.ndim else 0
    if P.ndim < 1 or m % 2 == 0:
        raise ValueError(
            f"power_sums: expected shape (..., 2k - 1) (7 sums for a cubic), got {describe(P)}; "
            "pass sum_i t_i^m for m = 0 .. 2k - 2"
        )
    k = (m + 1) // 2
    idx = np.arange(k)[:, None] + np.arange(k)[None, :]
    return P[..., idx]  # eq. 1: A = sum_i t_i t_i^T, entry (i, j) = sum t^(i+j)


def cg_solve(A, b, iterations: int = 4, *, rtol: float | None = None) -> np.ndarray:
    """Solve A c = b by conjugate gradients from c = 0, batched (TAMISS sec. 3.2, [NW06]).

    Runs exactly ``iterations`` steps per system (the paper uses four for 4 x 4 systems); a system
    whose residual norm has dropped to ``rtol * |b|`` stops changing (so further steps neither
    divide 0 by 0 nor amplify rounding noise). Started from zero, CG stays in the Krylov space of
    A b, which lies in the range of A: for a singular positive semi-definite A with b in its range
    (always so for normal equations, eq. 1) it converges to the minimum-norm (pseudo-inverse)
    solution.

    Parameters
    ----------
    A : (..., k, k) float, k >= 0
        Symmetric positive (semi-)definite matrices (not checked for definiteness); k = 0
        gives the empty solution (..., 0).
    b : (..., k) float
        Right-hand sides; batch shapes of A and b broadcast.
    iterations : int >= 0
    rtol : float, optional
        Relative residual at which a system is frozen; default 8 * machine epsilon of the dtype.

    Returns
    -------
    c : (..., k), float64, or float32 if A and b are float32 (then all arithmetic is float32).
    """
    A = as_float("A", A, finite=True)
    b = as_float("b", b, finite=True)
    iterations = check_int("iterations", iterations, lo=0)
    if A.ndim < 2 or A.shape[-1] != A.shape[-2]:
        raise ValueError(f"A: expected shape (..., k, k), got {describe(A)}; pass square matrices")
    k = A.shape[-1]
    if b.ndim < 1 or b.shape[-1] != k:
        raise ValueError(
            f"b: expected shape (..., {k}) to match A of shape {A.shape}, got {describe(b)}"
        )
    try:
        batch = np.broadcast_shapes(A.shape[:-2], b.shape[:-1])
    except ValueError:
        raise ValueError(
            f"b: batch shape {b.shape[:-1]} does not broadcast with A's batch shape "
            f"{A.shape[:-2]}; give one right-hand side per matrix"
        ) from None
    dt = result_dtype(A, b)
    rtol = 8 * float(np.finfo(dt).eps) if rtol is None else check_scalar("rtol", rtol, lo=0.0)
    if k == 0:  # 0 x 0 systems: the empty solution
        return np.zeros(batch + (0,), dtype=dt)
    scale = np.max(np.abs(A), axis=(-2, -1), keepdims=True)
    asym = np.abs(A - np.swapaxes(A, -1, -2)) > 1e-5 * scale + np.finfo(np.float64).tiny
    if np.any(asym):
        raise ValueError(
            "A: expected symmetric matrices (conjugate gradients needs A = A^T), got an "
            "asymmetric one; symmetrize with (A + A.swapaxes(-1, -2)) / 2"
        )
    A = np.broadcast_to(A.astype(dt, copy=False), batch + (k, k))
    b = np.broadcast_to(b.astype(dt, copy=False), batch + (k,))
    return cg_kernel(A, b, iterations, rtol)


def cg_kernel(A: np.ndarray, b: np.ndarray, iterations: int, rtol: float) -> np.ndarray:
    """Unvalidated batched CG on same-dtype arrays A (..., k, k), b (..., k) of one batch shape."""
    dt = b.dtype
    x = np.zeros(b.shape, dtype=dt)
    r = b.copy()  # r = b - A 0
    p = r.copy()
    rr = np.einsum("...i,...i->...", r, r)
    stop = dt.type(rtol) ** 2 * rr
    one = dt.type(1)
    for _ in range(iterations):
        Ap = np.einsum("...ij,...j->...i", A, p)
        pAp = np.einsum("...i,...i->...", p, Ap)
        ok = (rr > stop) & (rr > 0) & (pAp > 0)
        alpha = np.where(ok, rr / np.where(ok, pAp, one), dt.type(0))  # step length
        x = x + alpha[..., None] * p
        r = r - alpha[..., None] * Ap
        rr_new = np.einsum("...i,...i->...", r, r)
        beta = np.where(ok, rr_new / np.where(ok, rr, one), dt.type(0))  # Fletcher-Reeves
        p = np.where(ok[..., None], r + beta[..., None] * p, p)
        rr = np.where(ok, rr_new, rr)
    return x


def visibility_prior(t_min, t_max, n, *, k: int = 4) -> np.ndarray:
    """Contribution of n zero-visibility points spread evenly over [t_min, t_max] (sec. 3.2).

    The expected value of sum_j t_j t_j^T for n points t_j uniform on [t_min, t_max]::

        D = n / (t_max - t_min) * integral_{t_min}^{t_max} t t^T dt,
        d_ij = n * (t_max^(m+1) - t_min^(m+1)) / ((m + 1) (t_max - t_min)),  m = i + j (0-based)

    evaluated as n * h_m(t_min, t_max) / (m + 1) with h_m(a, b) = sum_q a^q b^(m-q), which is exact
    for t_min = t_max (all points at one place). The paper prints D = n * integral(t t^T) without the
    1 / (t_max - t_min): that is the expected sum only for a span of exactly 1.

    Parameters
    ----------
    t_min, t_max : (...) float, t_min <= t_max
    n : (...) float >= 0, the number of points (need not be an integer)
    k : int >= 1, basis size (4 for cubics)

    Returns
    -------
    D : (..., k, k), float64, or float32 if the array inputs are float32.
    """
    a = as_float("t_min", t_min, finite=True)
    b_ = as_float("t_max", t_max, finite=True)
    n_ = as_float("n", n, finite=True)
    k = check_int("k", k, lo=1)
    if np.any(a > b_):
        raise ValueError(
            f"t_min, t_max: expected t_min <= t_max, got t_min={describe(a)}, t_max={describe(b_)}; "
            "swap them"
        )
    if np.any(n_ < 0):
        raise ValueError(f"n: expected a non-negative count, got {describe(n_)}")
    dt = result_dtype(t_min, t_max, n)
    a, b_, n_ = np.broadcast_arrays(a.astype(dt), b_.astype(dt), n_.astype(dt))
    pa = [np.ones_like(a)]
    pb = [np.ones_like(b_)]
    for _ in range(2 * k - 2):
        pa.append(pa[-1] * a)
        pb.append(pb[-1] * b_)
    mean = []  # mean of t^m over [a, b]
    for m in range(2 * k - 1):
        h = sum(pa[q] * pb[m - q] for q in range(m + 1))
        mean.append(h / dt.type(m + 1))  # = (b^(m+1) - a^(m+1)) / ((m+1)(b-a))
    M = np.stack(mean, axis=-1)
    idx = np.arange(k)[:, None] + np.arange(k)[None, :]
    return (n_[..., None, None] * M[..., idx]).astype(dt, copy=False)  # sec. 3.2, D (expected sum)
