"""numba kernel of the ``threshold`` style's per-sample shading (private; inputs validated and
assembled by :mod:`refnpr.styles.threshold.fast`).

One parallel pass over the samples (a row per task, no reductions across samples, so the result
does not depend on the thread count): per covered sample, Veryovka eq. 1's diffuse and specular
terms, their thresholding T_n (eqs. 3-4) against the sample's threshold texture values (a
constant, a precomputed table of image samples, or evaluated here: the multi-scale lines of
eqs. 5-8, composed for cross-hatching, and the screen-round stipple dots of Fig. 4), the
filtered average of sec. 4 (PCF, or the analytic box filter of the lines), the strength blend
of sec. 5 and eq. 2's sum, stored as float32 straight-alpha RGBA clipped to [0, 1]. float64 arithmetic in
the order of the numpy code (``refnpr.formulas.lighting``, ``refnpr.formulas.threshold``,
``refnpr.styles.threshold.style``), which stays the oracle (``ThresholdStyle._shade_numpy``).
"""

from __future__ import annotations

import math

import numpy as np

from refnpr._jit import banded, njit, specialised

#: ``src`` codes of :func:`shade_threshold_for`.
SRC_CONST = 0
SRC_TABLE = 1
SRC_LINES = 2
SRC_ANALYTIC = 3
SRC_STIPPLE = 4
#: ``light_kind`` codes.
LIGHT_DIRECTIONAL = 0
LIGHT_POINT = 1
#: ``floor_int``'s clip of dyadic levels (``refnpr.formulas._shading_checks.K_MAX``).
K_MAX = 1100
#: The largest float64 below 1.
ONE_BELOW = float(np.nextafter(1.0, 0.0))
#: 2.0 ** k for k in [-POW2_K, POW2_K] (normal floats: v * 2^k is ldexp(v, k), one rounding).
POW2_K = 1000
POW2 = np.array([2.0**k for k in range(-POW2_K, POW2_K + 1)], dtype=np.float64)
#: splitmix64 constants of the stipple hashes (``refnpr.formulas.threshold.stipple``).
_M1 = np.uint64(0x9E3779B97F4A7C15)
_M2 = np.uint64(0xBF58476D1CE4E5B9)
_M3 = np.uint64(0x94D049BB133111EB)
#: Smallest normal float64 (``np.finfo(float).tiny``).
TINY = float(np.finfo(np.float64).tiny)


@njit(inline="always")
def _step_n(x, t, n):
    """T_n(x, t) of eq. 4 as ``threshold.step_n_kernel`` computes it (float64)."""
    xn = x * n
    whole = np.floor(xn)
    levels = whole + (1.0 if xn - whole >= t else 0.0)  # eq. 4: floor(x n) + T(Frac(x n), t)
    top = np.ceil(xn)
    return (levels if levels <= top else top) / n  # eq. 4, divided by n


@njit(inline="always")
def _step(x, t, n):
    """``threshold.step_kernel``: eq. 3 for n == 1, eq. 4 otherwise."""
    if n == 1:
        return 1.0 if x >= t else 0.0  # eq. 3
    return _step_n(x, t, n)


@njit(inline="always")
def _pow(x, p):
    """``x ** p`` as numpy's scalar-exponent fast paths compute it (square, sqrt, identity)."""
    if p == 2.0:
        return x * x
    if p == 1.0:
        return x
    if p == 0.5:
        return math.sqrt(x)
    return x**p


@njit
def _pairwise(a, n):
    """numpy's pairwise sum of ``a[:n]`` (``np.add.reduce`` over a contiguous axis)."""
    if n < 8:
        res = 0.0
        for i in range(n):
            res += a[i]
        return res
    if n <= 128:
        r0 = a[0]
        r1 = a[1]
        r2 = a[2]
        r3 = a[3]
        r4 = a[4]
        r5 = a[5]
        r6 = a[6]
        r7 = a[7]
        i = 8
        while i < n - (n % 8):
            r0 += a[i + 0]
            r1 += a[i + 1]
            r2 += a[i + 2]
            r3 += a[i + 3]
            r4 += a[i + 4]
            r5 += a[i + 5]
            r6 += a[i + 6]
            r7 += a[i + 7]
            i += 8
        res = (r0 + r1) + (r2 + r3) + ((r4 + r5) + (r6 + r7))
        while i < n:
            res += a[i]
            i += 1
        return res
    n2 = n // 2
    n2 -= n2 % 8
    return _pairwise(a[:n2], n2) + _pairwise(a[n2:], n - n2)


@njit(inline="always")
def _frac(x):
    """``_shading_checks.frac``: x - floor(x), at most the largest float below 1."""
    r = x - np.floor(x)
    return r if r < ONE_BELOW else ONE_BELOW


@njit(inline="always")
def _ldexp(v, k):
    """``np.ldexp(v, k)`` for integer-valued float k: a product by an exact power of two (the
    same correctly rounded result) where 2^k is a normal float, else ``math.ldexp``."""
    if -POW2_K <= k <= POW2_K:
        return v * POW2[int(k) + POW2_K]
    return math.ldexp(v, int(k))


@njit(inline="always")
def _multiscale(vr, t, uniform):
    """``lines.multiscale_kernel``: F(v, t) of eqs. 7-8 for v in [0, 1), in [0, 1)."""
    if uniform:  # the tone-preserving correction (slopes 1, 2, 2, 1)
        a = (1 - t) / (2 * (1 + t))
        b = 1 - a
        if vr < a:
            f = vr
        elif vr < 0.5:
            f = 2 * vr - a
        elif vr < b:
            f = 2 * vr - b
        else:
            f = vr
    else:
        v1 = 2 * vr if vr < 0.5 else 2 * vr - 1  # eq. 7: F(v, 1)
        f = (1 - t) * vr + t * v1  # eq. 8
    if f < 0.0:
        f = 0.0
    return f if f <= ONE_BELOW else ONE_BELOW


@njit(inline="always")
def _line(v, s, uniform, noise, has_noise):
    """``threshold.line_threshold(v, s, uniform=..., noise=...)`` at one sample (eqs. 6-8)."""
    fl = np.floor(s)
    k = fl if fl >= -K_MAX else -K_MAX  # floor_int: floor(s) clipped
    if k > K_MAX:
        k = K_MAX
    t = s - fl
    p = _ldexp(v, k)  # eq. 6: Frac(v 2^floor(s))
    if not math.isfinite(p):
        p = 0.0
    f = _multiscale(_frac(p), t, uniform)  # eqs. 7-8
    if has_noise:
        f = _frac(f + noise)
    return f


@njit(inline="always")
def _darkness(f, lam_bp, lev_bp, i, n_layers):
    """``compose._darkness_of_layer`` of layer ``i`` at one value ``f``."""
    c = f if f > 0.0 else 0.0
    if c > 1.0:
        c = 1.0
    q = -math.log(c) if c > 0.0 else math.inf
    nb = lam_bp.shape[0]
    k = 0  # searchsorted(lev, q, side="right")
    while k < nb and lev_bp[k, i] <= q:
        k += 1
    last = nb - 1
    if k > last:
        return lam_bp[last] + (q - lev_bp[last, i]) * n_layers  # beyond the last breakpoint
    if last >= 1:
        hi = k if k >= 1 else 1
        if hi > last:
            hi = last
    else:
        hi = 0
    lo = hi - 1 if hi >= 1 else 0
    dlev = lev_bp[hi, i] - lev_bp[lo, i]
    safe = dlev if dlev > 0 else 1.0
    return lam_bp[lo] + (q - lev_bp[lo, i]) * (lam_bp[hi] - lam_bp[lo]) / safe


@njit(inline="always")
def _apply(x, tk, wk, kk, has_w, n, hits):
    """``SampledThresholds.apply``: T_n(x, t) (one sample) or the PCF average (sec. 4)."""
    if kk == 1 and not has_w:
        return _step_n(x, tk[0], n)  # eq. 4 (eq. 3 for n = 1)
    for j in range(kk):
        hits[j] = _step(x, tk[j], n)
    if not has_w:
        return _pairwise(hits, kk) / kk  # sec. 4: mean of the thresholding results
    total = _pairwise(wk, kk)
    for j in range(kk):
        hits[j] = hits[j] * wk[j]
    return _pairwise(hits, kk) / total  # sec. 4: weighted


@njit(inline="always")
def _clip(x, lo, hi):
    """``np.clip`` of one value (``minimum(maximum(x, lo), hi)``)."""
    m = x if x >= lo else lo
    return m if m <= hi else hi


@njit(inline="always")
def _h(x, ln):
    """``filtering._h``: running integral of the pulse train, periodic part."""
    f = _frac(x)
    return (f if f <= ln else ln) - ln * f


@njit(inline="always")
def _d2(x, ln):
    """``filtering._d2``: second integral of the pulse train, periodic part."""
    f = _frac(x)
    m = f * f / 2 if f <= ln else ln * f - ln * ln / 2
    return m - ln * f * f / 2 - ln * (1 - ln) / 2 * f


@njit(inline="always")
def _ramp(start, width, ln, sign):
    """``filtering._ramp``: integral of z 1[Frac(start + sign z) < ln] over [0, width]."""
    total = 0.0
    base = np.floor(start)
    for dn in (-1.0, 0.0, 1.0):
        n = base + dn * sign
        if sign > 0:
            lo = n - start
            hi = n + ln - start
        else:
            lo = start - n - ln
            hi = start - n
        lo = _clip(lo, 0.0, width)
        hi = _clip(hi, 0.0, width)
        total = total + (hi - lo) * (hi + lo) / 2
    return total


@njit
def _pulse_box(u, a, b, ln):
    """``filtering._pulse_box``: E[1[Frac(u + a X + b Y) < ln]], X, Y ~ U(-1/2, 1/2)."""
    u = _frac(u)
    safe_a = a if a > 0 else 1.0
    safe_b = b if b > 0 else 1.0
    if b >= 1:  # closed form
        ha = a / 2
        hb = b / 2
        dd = (
            _d2(u + ha + hb, ln)
            - _d2(u + ha - hb, ln)
            - _d2(u - ha + hb, ln)
            + _d2(u - ha - hb, ln)
        )
        return ln + dd / (safe_a * safe_b)
    half = (a - b) / 2
    plateau = (ln * (a - b) + _h(u + half, ln) - _h(u - half, ln)) / safe_a
    left = _ramp(u - (a + b) / 2, b, ln, 1)
    right = _ramp(u + (a + b) / 2, b, ln, -1)
    ramps = (left + right) / (safe_a * safe_b) if b > 0 else 0.0
    return plateau + ramps


@njit
def _coverage(v, s, x, gx, gy, uniform):
    """``threshold.line_coverage`` at one sample: box filter of the thresholded lines (sec. 4)."""
    fl = np.floor(s)
    k = fl if fl >= -K_MAX else -K_MAX
    if k > K_MAX:
        k = K_MAX
    t = s - fl
    p = _ldexp(v, k)  # eq. 6
    if not math.isfinite(p):
        p = 0.0
    vr = _frac(p)
    ax = abs(gx)
    ay = abs(gy)
    a = _ldexp(ax if ax >= ay else ay, k)  # footprint in line periods
    b = _ldexp(ax if ax <= ay else ay, k)
    point = a < 1e-100
    huge = not (a < 1e15)
    a_ok = 1.0 if (point or huge) else a
    b_ok = 0.0 if (point or huge or b < 1e-200) else b
    cover = 0.0
    tone = 0.0
    if not uniform:  # _pieces: F = (1 + t) v on [0, 1/2), (1 + t) v - t on [1/2, 1)
        ln = _clip(x / (1 + t), 0.0, 0.5)
        cover = cover + _pulse_box(vr - 0.0, a_ok, b_ok, ln)
        tone = tone + ln
        ln = _clip((x + t) / (1 + t) - 0.5, 0.0, 0.5)
        cover = cover + _pulse_box(vr - 0.5, a_ok, b_ok, ln)
        tone = tone + ln
    else:
        ca = (1 - t) / (2 * (1 + t))
        cb = 1 - ca
        ln = _clip(x, 0.0, ca)
        cover = cover + _pulse_box(vr - 0.0, a_ok, b_ok, ln)
        tone = tone + ln
        ln = _clip((x - ca) / 2, 0.0, 0.5 - ca)
        cover = cover + _pulse_box(vr - ca, a_ok, b_ok, ln)
        tone = tone + ln
        ln = _clip((x + cb) / 2 - 0.5, 0.0, cb - 0.5)
        cover = cover + _pulse_box(vr - 0.5, a_ok, b_ok, ln)
        tone = tone + ln
        ln = _clip(x - cb, 0.0, 1 - cb)
        cover = cover + _pulse_box(vr - cb, a_ok, b_ok, ln)
        tone = tone + ln
    if point:
        cover = 1.0 if x >= _multiscale(vr, t, uniform) else 0.0  # the point sample
    elif huge:
        cover = tone
    if x >= 1:
        cover = 1.0
    elif x < 0:
        cover = 0.0
    return _clip(cover, 0.0, 1.0)


@njit(inline="always")
def _interp(x, xp, fp, i):
    """``np.interp(x, xp, fp[:, i])`` (numpy's branches: ends, exact knots, slope form)."""
    nb = xp.shape[0]
    if x < xp[0]:
        return fp[0, i]
    if x > xp[nb - 1]:
        return fp[nb - 1, i]
    j = 0
    while j < nb - 1 and xp[j + 1] <= x:
        j += 1
    if j == nb - 1 or xp[j] == x:
        return fp[j, i]
    slope = (fp[j + 1, i] - fp[j, i]) / (xp[j + 1] - xp[j])
    out = slope * (x - xp[j]) + fp[j, i]
    if out != out:
        out = slope * (x - xp[j + 1]) + fp[j + 1, i]
        if out != out and fp[j, i] == fp[j + 1, i]:
            out = fp[j, i]
    return out


@njit
def _analytic(x, n, lv, lgx, lgy, ls, n_dirs, uniform, z, has_noise, lam_bp, lev_bp):
    """``AnalyticLines.apply``: box-filtered T_n(x, F) of the hatching layers (sec. 4)."""
    xn = x * n
    base = np.floor(xn)
    r = xn - base  # eq. 4: T_n = (floor(x n) + T(Frac(x n), t)) / n
    cover = 1.0
    lam = 0.0
    if n_dirs > 1:
        c = _clip(r, 0.0, 1.0)
        lam = -math.log(c) if c > 0.0 else math.inf
    nb = lam_bp.shape[0]
    for d in range(n_dirs):
        if n_dirs > 1:  # layer_whites: the layer's white fraction at r
            li = _interp(lam, lam_bp, lev_bp, d)
            if lam > lam_bp[nb - 1]:
                li = lev_bp[nb - 1, d] + (lam - lam_bp[nb - 1]) / n_dirs
            w = math.exp(-li)
        else:
            w = r
        if has_noise:
            c = (
                _coverage(lv[d], ls[d], w - z, lgx[d], lgy[d], uniform)
                + _coverage(lv[d], ls[d], w + 1.0 - z, lgx[d], lgy[d], uniform)
                - _coverage(lv[d], ls[d], 1.0 - z, lgx[d], lgy[d], uniform)
            )
        else:
            c = _coverage(lv[d], ls[d], w, lgx[d], lgy[d], uniform)
        cover = cover * c  # white: F_i <= w_i(x) in every layer
    if r >= 1.0:
        cover = 1.0
    else:
        cover = _clip(cover, 0.0, 1.0)
    top = np.ceil(xn)
    lvl = base + cover
    return (lvl if lvl <= top else top) / n


@njit(inline="always")
def _mix(h):
    """splitmix64 finalizer (uint64, wrapping)."""
    h = h ^ (h >> np.uint64(30))
    h = h * _M2
    h = h ^ (h >> np.uint64(27))
    h = h * _M3
    return h ^ (h >> np.uint64(31))


@njit(inline="always")
def _unit(h):
    return np.float64(h >> np.uint64(11)) / 9007199254740992.0  # / 2^53


@njit(inline="always")
def _bits(x, fbuf, ubuf):
    """float64 bits as uint64, -0.0 folded onto 0.0 (``stipple._bits``)."""
    fbuf[0] = x + 0.0
    return ubuf[0]


@njit(inline="always")
def _quadrant_area(r, x_half, y_half):
    """``stipple._quadrant_area``: area of the quarter tile within distance r of its corner."""
    m = x_half if x_half <= r else r
    q = r * r - y_half * y_half
    xc = math.sqrt(q if q >= 0.0 else 0.0)
    xc = xc if xc <= m else m
    q = r * r - m * m
    root = math.sqrt(q if q >= 0.0 else 0.0)
    pm = 0.5 * (m * root + r * r * math.atan2(m, root))
    q = r * r - xc * xc
    root = math.sqrt(q if q >= 0.0 else 0.0)
    pc = 0.5 * (xc * root + r * r * math.atan2(xc, root))
    return y_half * xc + pm - pc


@njit
def _round_dot(u, v, ku, kv, a_u, a_v, seed, jitter, fbuf, ubuf):
    """``stipple._round_dot``: exactly uniform round dot of one level (tile a_u x a_v)."""
    big_v = _ldexp(v, kv)  # eq. 6 along v
    j = np.floor(big_v + 0.5)
    dv = big_v - j
    v_row = _ldexp(j, -kv)
    phase = 0.0
    if jitter > 0:  # _row_phase
        h = _bits(v_row, fbuf, ubuf) * _M1 + seed * _M3
        phase = _unit(_mix(h))
    big_u = _ldexp(u - phase, ku)  # eq. 6 along u
    i = np.floor(big_u + 0.5)
    du = big_u - i
    ou = 0.0
    ov = 0.0
    if jitter > 0:  # _dot_offsets
        h = _mix(_bits(v_row, fbuf, ubuf) * _M1 + seed * _M3 + np.uint64(1))
        h = _mix(h ^ (_bits(_ldexp(i, -ku), fbuf, ubuf) * _M2))
        g = _mix(h + _M1)
        ou = jitter * (2.0 * _unit(h) - 1.0)
        ov = jitter * (2.0 * _unit(g) - 1.0)
    r = math.hypot((du - ou) * a_u, (dv - ov) * a_v)
    xl = (0.5 + ou) * a_u
    xr = (0.5 - ou) * a_u
    yl = (0.5 + ov) * a_v
    yr = (0.5 - ov) * a_v
    area = (
        _quadrant_area(r, xl, yl)
        + _quadrant_area(r, xr, yl)
        + _quadrant_area(r, xl, yr)
        + _quadrant_area(r, xr, yr)
    )
    return _clip(1.0 - area / (a_u * a_v), 0.0, 1.0)


@njit(inline="always")
def _split(x, n):
    c = _clip(x, 0.0, 1.0) * n
    i = np.floor(c)
    i = _clip(i, 0.0, n - 1.0)
    return int(i), c - i


@njit
def _stipple(u, v, s_u, s_v, seed, jitter, cdf, has_table, fbuf, ubuf):
    """``threshold.stipple_threshold`` at one point: tensor eq. 8 of round dots, tone table."""
    fu = np.floor(s_u)
    ku = _clip(fu, -K_MAX, K_MAX)
    tu = s_u - fu
    fv = np.floor(s_v)
    kv = _clip(fv, -K_MAX, K_MAX)
    tv = s_v - fv
    a_u = np.exp2(tu)
    a_v = np.exp2(tv)
    f = 0.0
    for bu in range(2):
        wu = tu if bu else 1.0 - tu  # eq. 8 along u
        for bv in range(2):
            wv = tv if bv else 1.0 - tv  # eq. 8 along v
            d = _round_dot(
                u, v, ku + bu, kv + bv, a_u / (1 + bu), a_v / (1 + bv), seed, jitter, fbuf, ubuf
            )
            f = f + wu * wv * d
    if has_table:  # stipple._apply: trilinear G(f | t_u, t_v)
        nt = cdf.shape[0] - 1
        ny = cdf.shape[2] - 1
        a, fa = _split(tu, float(nt))
        b, fb = _split(tv, float(nt))
        i, fi = _split(f, float(ny))
        out = 0.0
        for da in range(2):
            wa = fa if da else 1 - fa
            for db in range(2):
                wb = fb if db else 1 - fb
                g = cdf[a + da, b + db, i] * (1 - fi) + cdf[a + da, b + db, i + 1] * fi
                out = out + wa * wb * g
        f = out
    return _clip(f, 0.0, 1.0)


@njit(inline="always")
def _smoothstep(x):
    c = x if x > 0.0 else 0.0
    if c > 1.0:
        c = 1.0
    return c * c * (3.0 - 2.0 * c)


@njit(inline="always")
def _blend(x, tx, st0, dark, bright):
    """``ThresholdStyle._term``: eq. 2's thresholded term T(x) blended by the strength (sec. 5)."""
    ts = 1.0
    if dark > 0.0:
        ts = ts * _smoothstep(x / dark)
    if bright > 0.0:
        ts = ts * _smoothstep((1.0 - x) / bright)
    st = st0 * ts
    return x + st * (tx - x)


@njit(inline="always")
def _unit3(x, y, z):
    """``_shading_checks.unit_vectors`` of one 3-vector (max-scaled, zero stays zero)."""
    m = max(abs(x), abs(y), abs(z))
    if m > 0.0:
        x = x / m
        y = y / m
        z = z / m
    length = math.sqrt(x * x + y * y + z * z)
    if length > 0.0:
        x = x / length
        y = y / length
        z = z / length
    return x, y, z


@specialised
def shade_threshold_for(src, cross):
    """:func:`shade_threshold` for one threshold source ``src`` (SRC_CONST, SRC_TABLE,
    SRC_LINES, SRC_ANALYTIC, SRC_STIPPLE) and ``cross`` (more than one hatching direction:
    ``dir_sin.shape[0] > 1``, the layers composed by ``lam_bp``, ``lev_bp``). numba prunes the
    other sources' branches, and the layer composition of a single direction, before typing
    them, so a frame compiles only what it uses (:func:`refnpr._jit.specialised`; the line
    source of one direction alone compiles in about half the time of the all-source kernel)."""

    @banded("cover")
    def shade_threshold(
        lo,
        hi,
        cover,
        mesh_id,
        row_start,
        normal,
        normal_tab,
        position,
        m_ambient,
        m_diffuse,
        m_specular,
        spec_on,
        shininess,
        light_kind,
        light_vec,
        light_unit,
        light_color,
        eye,
        steps,
        strength,
        facing_fade,
        facing_power,
        dark,
        bright,
        specular,
        spec_const,
        t_const,
        t_tab,
        w_tab,
        uv,
        duv_dx,
        duv_dy,
        dyadic,
        has_grad,
        has_channel,
        uv_scale,
        log2_sv,
        dir_sin,
        dir_cos,
        dir_zero,
        log2_w,
        multiscale,
        uniform,
        offsets,
        noise_tab,
        lam_bp,
        lev_bp,
        n_sub,
        stipple_seed,
        jitter,
        cdf,
        out,
    ):
        """Shade every sample of ``out (nH, nW, 4) float32`` (written in full; zero where empty).

        Banded over the rows (``lo``, ``hi``: a band, given by :func:`refnpr._jit.banded`).

        cover, mesh_id (nH, nW) int: covered where ``cover >= 0``; object index (clamped >= 0).
        row_start (nH,) int64: index of each row's first covered sample in row-major mask order
        (the order of ``t_tab``, ``w_tab``, ``noise_tab``). normal (nH, nW, 3) float: shading
        normals (not renormalized for f_s and n.v, as in the numpy path), or ``normal_tab (M, 3)``
        float64 in mask order where it has rows (bump-mapped normals); position (nH, nW, 3)
        float, any shape when unused. m_ambient (O, 3) float64 = m_a l_a; m_diffuse, m_specular
        (O, 3); shininess (O,). light_kind (L,) int64; light_vec (L, 3): d / |d| of directional
        lights, positions of point lights; light_unit (L, 3): unit_vectors(light_vec) (directional);
        light_color (L, 3); eye (3,). steps: n of eq. 4; strength, facing_fade, facing_power, dark,
        bright: sec. 5 (facing_fade 0: no orientation fade). specular: add the specular terms;
        spec_const: the specular threshold (< 0: the texture's).

        src (the factory's): SRC_CONST (``t_const`` everywhere), SRC_TABLE (``t_tab (M, K)``
        with ``w_tab (M, K)`` weights, or ``w_tab`` of shape (1, 0) for none), SRC_LINES (eqs. 5-8 here, one threshold per
        row of ``offsets (K, 2)`` pixel offsets): uv, duv_dx, duv_dy (nH, nW, 2) float; has_grad:
        whether duv_* are read (else 0); dyadic (nH, nW): the G-buffer's eq. 5 scale, read for
        directions with ``dir_zero`` when ``has_channel``, minus log2_sv (O,); uv_scale (O, 2);
        dir_sin, dir_cos (D,) of the hatching angles; log2_w = log2(period); multiscale, uniform;
        noise_tab (M,) phase noise in line periods or shape (0,); lam_bp (B,), lev_bp (B, D): the
        layer schedule composing D > 1 layers (``combine_thresholds``). SRC_ANALYTIC: the same
        layers box-filtered over the sample's footprint (``AnalyticLines``; the derivatives divided
        by ``n_sub``, the samples per pixel per axis), ``offsets`` unused. SRC_STIPPLE: the
        screen-round jittered dots (``stipple_threshold``) at each row of ``offsets`` (pcf) or at
        uv itself (shape (0, 2): filter "none"), with ``stipple_seed`` (uint64, 32 bits),
        ``jitter`` and the tone table ``cdf (n_t, n_t, n_y)`` (shape (0, 0, 0) for none).
        """
        nh, nw = cover.shape
        n_lights = light_kind.shape[0]
        if src == SRC_TABLE:
            kk = t_tab.shape[1]
        elif src == SRC_LINES:
            kk = offsets.shape[0]
        elif src == SRC_ANALYTIC:
            kk = 0
        elif src == SRC_STIPPLE:
            kk = max(offsets.shape[0], 1)
        else:
            kk = 1
        has_w = src == SRC_TABLE and w_tab.shape[1] > 0
        n_dirs = dir_sin.shape[0]
        has_noise = noise_tab.shape[0] > 0
        for y in range(lo, hi):
            tk = np.empty(kk)
            wk = np.empty(kk)
            hits = np.empty(kk)
            one = np.empty(1)
            none = np.empty(1)
            lv = np.empty(n_dirs)
            lgx = np.empty(n_dirs)
            lgy = np.empty(n_dirs)
            ls = np.empty(n_dirs)
            z = 0.0
            s_uv = np.empty(2)
            fbuf = np.empty(1)
            ubuf = fbuf.view(np.uint64)
            has_table = cdf.shape[0] > 0
            idx = row_start[y]
            for x in range(nw):
                if cover[y, x] < 0:
                    out[y, x, 0] = 0.0
                    out[y, x, 1] = 0.0
                    out[y, x, 2] = 0.0
                    out[y, x, 3] = 0.0
                    continue
                mi = max(mesh_id[y, x], 0)
                # ---- thresholds of this sample (taken once, used by every term)
                if src == SRC_CONST:
                    tk[0] = t_const
                elif src == SRC_TABLE:
                    for j in range(kk):
                        tk[j] = t_tab[idx, j]
                    if has_w:
                        for j in range(kk):
                            wk[j] = w_tab[idx, j]
                elif src == SRC_STIPPLE:
                    su = uv_scale[mi, 0]
                    sv = uv_scale[mi, 1]
                    u0 = np.float64(uv[y, x, 0]) * su
                    v0 = np.float64(uv[y, x, 1]) * sv
                    gxu = np.float64(duv_dx[y, x, 0]) * su
                    gxv = np.float64(duv_dx[y, x, 1]) * sv
                    gyu = np.float64(duv_dy[y, x, 0]) * su
                    gyv = np.float64(duv_dy[y, x, 1]) * sv
                    for axis in range(2):  # stipple_scales: eq. 5 per texture axis
                        g = math.hypot(gxu, gyu) if axis == 0 else math.hypot(gxv, gyv)
                        if not g >= TINY:
                            g = TINY if g == g else g
                        s = -(math.log2(g) + log2_w)
                        s_uv[axis] = np.floor(s) if not multiscale else s
                    if offsets.shape[0] == 0:
                        tk[0] = _stipple(
                            u0,
                            v0,
                            s_uv[0],
                            s_uv[1],
                            stipple_seed,
                            jitter,
                            cdf,
                            has_table,
                            fbuf,
                            ubuf,
                        )
                    else:
                        for j in range(kk):
                            uj = u0 + offsets[j, 0] * gxu + offsets[j, 1] * gyu
                            vj = v0 + offsets[j, 0] * gxv + offsets[j, 1] * gyv
                            tk[j] = _stipple(
                                uj,
                                vj,
                                s_uv[0],
                                s_uv[1],
                                stipple_seed,
                                jitter,
                                cdf,
                                has_table,
                                fbuf,
                                ubuf,
                            )
                else:
                    su = uv_scale[mi, 0]
                    sv = uv_scale[mi, 1]
                    u0 = np.float64(uv[y, x, 0]) * su
                    v0 = np.float64(uv[y, x, 1]) * sv
                    gxu = 0.0
                    gxv = 0.0
                    gyu = 0.0
                    gyv = 0.0
                    if has_grad:
                        gxu = np.float64(duv_dx[y, x, 0]) * su
                        gxv = np.float64(duv_dx[y, x, 1]) * sv
                        gyu = np.float64(duv_dy[y, x, 0]) * su
                        gyv = np.float64(duv_dy[y, x, 1]) * sv
                    nz = noise_tab[idx] if has_noise else 0.0
                    z = nz - np.floor(nz)
                    for j in range(kk):
                        tk[j] = math.inf
                    for d in range(n_dirs):
                        sa = dir_sin[d]
                        ca = dir_cos[d]
                        v = -u0 * sa + v0 * ca  # hatch_coordinate
                        dvx = -gxu * sa + gxv * ca
                        dvy = -gyu * sa + gyv * ca
                        if dir_zero[d] and has_channel:
                            s = np.float64(dyadic[y, x]) - log2_sv[mi]  # eq. 5 (G-buffer)
                        else:
                            g = math.hypot(dvx, dvy)
                            if not g >= TINY:
                                g = TINY if g == g else g
                            s = -(math.log2(g) + log2_w)  # eq. 5, d = 1 / |grad v|
                        if not multiscale:
                            s = np.floor(s)  # eq. 6 alone
                        lv[d] = v
                        lgx[d] = dvx / n_sub
                        lgy[d] = dvy / n_sub
                        ls[d] = s
                        for j in range(kk):
                            vj = v + offsets[j, 0] * dvx + offsets[j, 1] * dvy
                            f = _line(vj, s, uniform, nz, has_noise)  # eqs. 6-8
                            if not cross:
                                tk[j] = f
                            else:
                                li = _darkness(f, lam_bp, lev_bp, d, n_dirs)
                                tk[j] = li if li < tk[j] else tk[j]  # white in every layer
                    if cross and kk > 0:
                        for j in range(kk):
                            t = math.exp(-tk[j])  # union of the dark lines: max_i h_i(F_i)
                            if t < 0.0:
                                t = 0.0
                            tk[j] = t if t < ONE_BELOW else ONE_BELOW
                # ---- eq. 1's vectors
                if normal_tab.shape[0] > 0:
                    nx = normal_tab[idx, 0]
                    ny = normal_tab[idx, 1]
                    nz3 = normal_tab[idx, 2]
                else:
                    nx = np.float64(normal[y, x, 0])
                    ny = np.float64(normal[y, x, 1])
                    nz3 = np.float64(normal[y, x, 2])
                ux, uy, uz = _unit3(nx, ny, nz3)  # lighting.diffuse normalizes N
                vx = 0.0
                vy = 0.0
                vz = 0.0
                if (specular and spec_on[mi]) or facing_fade > 0.0:  # ShadeContext.view_dir
                    vx = eye[0] - np.float64(position[y, x, 0])
                    vy = eye[1] - np.float64(position[y, x, 1])
                    vz = eye[2] - np.float64(position[y, x, 2])
                    length = math.sqrt(vx * vx + vy * vy + vz * vz)
                    if length > 0.0:
                        vx = vx / length
                        vy = vy / length
                        vz = vz / length
                    else:
                        vx = 0.0
                        vy = 0.0
                        vz = 0.0
                st0 = strength * 1.0
                if facing_fade > 0.0:  # sec. 5: 1 - fade |n.v|^power
                    ndv = nx * vx + ny * vy + nz3 * vz
                    st0 = strength * (1.0 - facing_fade * _pow(abs(ndv), facing_power))
                r = m_ambient[mi, 0]  # eq. 2: m_a l_a kept
                g_ = m_ambient[mi, 1]
                b = m_ambient[mi, 2]
                p = shininess[mi]
                for i in range(n_lights):
                    lx = light_vec[i, 0]
                    ly = light_vec[i, 1]
                    lz = light_vec[i, 2]
                    if light_kind[i] == LIGHT_POINT:  # ShadeContext.light_dirs
                        lx = lx - np.float64(position[y, x, 0])
                        ly = ly - np.float64(position[y, x, 1])
                        lz = lz - np.float64(position[y, x, 2])
                        length = math.sqrt(lx * lx + ly * ly + lz * lz)
                        if length > 0.0:
                            lx = lx / length
                            ly = ly / length
                            lz = lz / length
                        else:
                            lx = 0.0
                            ly = 0.0
                            lz = 0.0
                        qx, qy, qz = _unit3(lx, ly, lz)
                    else:
                        qx = light_unit[i, 0]
                        qy = light_unit[i, 1]
                        qz = light_unit[i, 2]
                    f_d = ux * qx + uy * qy + uz * qz
                    f_d = f_d if f_d >= 0.0 else 0.0  # eq. 1: f_d = max(N.L, 0), <= 1
                    f_d = f_d if f_d <= 1.0 else 1.0
                    if src == SRC_ANALYTIC:
                        tx = _analytic(
                            f_d,
                            steps,
                            lv,
                            lgx,
                            lgy,
                            ls,
                            n_dirs,
                            uniform,
                            z,
                            has_noise,
                            lam_bp,
                            lev_bp,
                        )
                    else:
                        tx = _apply(f_d, tk, wk, kk, has_w, steps, hits)  # eq. 4, sec. 4
                    term = _blend(f_d, tx, st0, dark, bright)  # eq. 2, sec. 5
                    r = r + m_diffuse[mi, 0] * term * light_color[i, 0]
                    g_ = g_ + m_diffuse[mi, 1] * term * light_color[i, 1]
                    b = b + m_diffuse[mi, 2] * term * light_color[i, 2]
                    if specular and spec_on[mi]:
                        f_s = 0.0
                        if p > 0.0:  # Blinn-Phong, unnormalized N (specular_field)
                            n_dot_l = nx * lx + ny * ly + nz3 * lz
                            hx, hy, hz = _unit3(lx + vx, ly + vy, lz + vz)
                            base = nx * hx + ny * hy + nz3 * hz
                            base = base if base >= 0.0 else 0.0
                            f_s = _pow(base, p) if n_dot_l > 0.0 else 0.0  # eq. 1: f_s
                        if spec_const >= 0.0:
                            one[0] = spec_const
                            tx = _apply(f_s, one, none, 1, False, steps, hits)
                        elif src == SRC_ANALYTIC:
                            tx = _analytic(
                                f_s,
                                steps,
                                lv,
                                lgx,
                                lgy,
                                ls,
                                n_dirs,
                                uniform,
                                z,
                                has_noise,
                                lam_bp,
                                lev_bp,
                            )
                        else:
                            tx = _apply(f_s, tk, wk, kk, has_w, steps, hits)
                        term = _blend(f_s, tx, st0, dark, bright)
                        r = r + m_specular[mi, 0] * term * light_color[i, 0]  # eq. 2
                        g_ = g_ + m_specular[mi, 1] * term * light_color[i, 1]
                        b = b + m_specular[mi, 2] * term * light_color[i, 2]
                out[y, x, 0] = min(max(r, 0.0), 1.0)
                out[y, x, 1] = min(max(g_, 0.0), 1.0)
                out[y, x, 2] = min(max(b, 0.0), 1.0)
                out[y, x, 3] = 1.0
                idx += 1

    return shade_threshold
