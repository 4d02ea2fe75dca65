"""Every case's derived texts are specifications a backend codes from, never pointers into
refnpr: no source file, module path or private function is named, every refnpr function a
text names it also defines, and every ``params.<key>`` it reads is a key of the case's params.

The texts are built the cheap way (``refnpr.kit.styles.derived_texts``: no texture, no
render) for every case of the suite; one case per distinct set of texts is exported for real
to check that ``export_style`` gives the same texts and that the params keys exist. The last
tests code the threshold texts' value noise, stipple, analytic line filter and layer schedule
from the texts alone (independent oracles) and compare them with refnpr's formulas.
"""

from __future__ import annotations

import functools
import importlib
import math
import pkgutil
import re
import struct

import numpy as np
import pytest

import refnpr
from refnpr.golden import DEFAULT_SUITE, load_suite
from refnpr.kit.derived import channel_derived, generic_derived
from refnpr.kit.export import _style_of
from refnpr.kit.styles import derived_texts, export_style
from refnpr.scenes import load_scene

#: The golden suite installed with refnpr.
SUITE = DEFAULT_SUITE

#: What a pointer into refnpr's source looks like in a text.
POINTERS = {
    "a refnpr path": re.compile(r"refnpr/"),
    "a Python file": re.compile(r"\.py\b"),
    "a refnpr module": re.compile(r"\brefnpr\.[A-Za-z_]"),
    "a docs file": re.compile(r"\bdocs/|\.md\b"),
    "a kernel module": re.compile(r"_kernels"),
    # _name, not a subscript (x_1, uv'_j, Lambda*_d) nor a glTF attribute (_TAM_CHART)
    "a private name": re.compile(r"(?<![A-Za-z0-9_'*])_[a-z][a-z0-9]*(?:_[a-z0-9]+)*\b"),
}
#: The raster_options keys a text may read (docs/kit.md "Style").
RASTER_OPTIONS = {"cull_backfaces", "line_period", "dyadic_coord", "texture_size", "dtype"}


def pointers(text: str) -> list[str]:
    """``"<what>: <match>"`` for every pointer into refnpr's source in ``text``."""
    return [f"{what}: {m.group(0)!r}" for what, rx in POINTERS.items() for m in rx.finditer(text)]


@functools.cache
def refnpr_function_names() -> frozenset[str]:
    """The snake_case names (with an underscore) of refnpr's public functions and classes
    outside the kit: a text naming one without defining it points at refnpr's code."""
    names = set()
    for info in pkgutil.walk_packages(refnpr.__path__, "refnpr."):
        if info.name.startswith(("refnpr.kit", "refnpr.cli")):
            continue
        module = importlib.import_module(info.name)
        for name, value in vars(module).items():
            if name.startswith("_") or "_" not in name or not callable(value):
                continue
            if str(getattr(value, "__module__", "")).startswith("refnpr"):
                names.add(name)
    return frozenset(names)


def undefined_functions(texts: dict[str, str], allowed: set[str]) -> list[str]:
    """refnpr function names the texts use but neither define (``name(...) =`` or ``name =``)
    nor have as a case key (``allowed``: params keys, channels, texture roles, text names)."""
    joined = "\n".join(texts.values())
    words = set(re.findall(r"\b[a-z][a-z0-9]*_[a-z0-9_]*\b", joined))
    out = []
    for name in sorted(words & refnpr_function_names() - allowed):
        defined = re.search(rf"\b{name}\s*(\([^()]*\))?\s*=(?!=)", joined)
        if defined is None:
            out.append(name)
    return out


#: A chain of params keys as the texts write it: params.objects[o].screen.role.
PARAMS_PATH = re.compile(r"\bparams((?:\.[a-z_][a-z0-9_]*(?:\[[^\]]*\])*)+)")


def params_paths(texts: dict[str, str]) -> set[str]:
    """Every key the texts name in a ``params.<key>...`` chain."""
    out = set()
    for chain in PARAMS_PATH.findall("\n".join(texts.values())):
        out |= {re.sub(r"\[.*", "", part) for part in chain.split(".") if part}
    return out


def _keys(value, out: set[str]) -> set[str]:
    if isinstance(value, dict):
        for k, v in value.items():
            out.add(str(k))
            _keys(v, out)
    elif isinstance(value, list):
        for v in value:
            _keys(v, out)
    return out


@functools.cache
def suite_texts() -> dict[str, tuple]:
    """Per case of the suite: (kind, style or None, scene, derived texts), texts built without
    textures (``derived_texts``) plus the generic and channel texts, as the exporter joins them."""
    out = {}
    for case in load_suite(SUITE):
        scene = load_scene(case.scene)
        if case.kind == "gbuffer":
            texts = {**generic_derived(), **channel_derived(sorted(case.channels))}
            out[case.name] = (case, None, scene, texts)
            continue
        style = _style_of(case, scene)
        size = {"width": case.width, "height": case.height, "spp": case.spp}
        channels = sorted(style.requires(scene))
        texts = {
            **generic_derived(),
            **channel_derived(channels),
            **derived_texts(style, scene, **size),
        }
        out[case.name] = (case, style, scene, texts)
    return out


def test_pointers_are_found():
    """The checks fail on the pointers a text must not hold, and pass a plain formula."""
    bad = [
        "see refnpr/styles/threshold/noise.py",
        "as line_coverage (filtering.py) computes it",
        "refnpr.formulas.threshold.layer_schedule",
        "exactly as _enumerate does",
        "(docs/tamiss.md)",
        "the kernel in _kernels",
    ]
    for text in bad:
        assert pointers(text), text
    good = "T_n(x, t) = min(floor(x n) + (1 if x n - floor(x n) >= t else 0), ceil(x n)) / n"
    assert pointers(good + "; glTF _TAM_SYMMETRY, _UV") == []
    assert undefined_functions({"a": "filtered as combine_thresholds does"}, set()) == [
        "combine_thresholds"
    ]
    assert undefined_functions({"a": "value_noise(p) = O(p) + 1; then value_noise(q)"}, set()) == []
    assert undefined_functions({"a": "the layer_schedule of params"}, {"layer_schedule"}) == []


def test_every_case_has_specifications_not_pointers():
    """No text of any case of the suite names a refnpr file, module or private function, or a
    refnpr function it does not define; every text is a non-empty paragraph."""
    problems = []
    for name, (_, style, _, texts) in suite_texts().items():
        for key, text in texts.items():
            if not isinstance(text, str) or len(text) < 20:
                problems.append(f"{name}: derived[{key!r}] is not a paragraph: {text!r}")
            problems += [f"{name}: derived[{key!r}]: {p}" for p in pointers(text)]
        allowed = set(texts) | {k.removeprefix("channel.") for k in texts}
        allowed |= params_paths(texts)
        if style is not None:
            inner = style.base if style.name == "contoured" else style
            allowed |= set(inner.params())
        problems += [
            f"{name}: names the refnpr function {f!r} without defining it"
            for f in undefined_functions(texts, allowed)
        ]
    assert not problems, "\n".join(problems)


def test_texts_match_the_case():
    """A threshold case carries the texts of what it uses and no other (no stipple text
    without stipple, no analytic filter text without it), and every X-Toon vertex-mode case
    its vertex-mode text."""
    seen = set()
    for name, (_, style, _, texts) in suite_texts().items():
        if style is None:
            continue
        inner = style.base if style.name == "contoured" else style
        if inner.name == "threshold":
            p = inner.p
            assert ("threshold_stipple" in texts) == (p.source == "stipple"), name
            assert ("threshold_lines" in texts) == (p.source == "lines"), name
            assert ("threshold_image" in texts) == (p.source == "image"), name
            assert ("threshold_analytic" in texts) == (p.filter == "analytic"), name
            assert ("threshold_noise" in texts) == (p.source == "lines" and p.noise != 0), name
            assert ("threshold_bump" in texts) == (p.bump is not None), name
            seen.add(p.source)
        if inner.name == "xtoon":
            vertex = inner._cfg.p.detail_mode == "vertex"
            assert ("xtoon-vertex-mode" in texts) == vertex, name
        assert ("contour_drawing" in texts) == (style.name == "contoured"), name
    assert seen == {"constant", "image", "lines", "stipple"}  # the suite covers every source


def _representatives() -> list[str]:
    """One image case per distinct set of texts (the first in suite order)."""
    first: dict[tuple, str] = {}
    for name, (_, style, _, texts) in suite_texts().items():
        if style is not None:
            first.setdefault(tuple(sorted(texts.items())), name)
    return list(first.values())


@pytest.mark.parametrize("name", _representatives())
def test_exported_texts_read_existing_params(name, tmp_path):
    """``export_style`` gives the texts ``derived_texts`` gives, and every ``params.<key>``
    and ``raster_options.<key>`` a text reads exists in the exported case."""
    case, style, scene, texts = suite_texts()[name]
    size = {"width": case.width, "height": case.height, "spp": case.spp}
    exported = export_style(style, scene, tmp_path, **size)
    joined = "\n".join(texts.values())
    assert exported.derived.items() <= texts.items()
    keys = _keys(exported.params, set())
    missing = sorted(params_paths(texts) - keys)
    assert not missing, f"{name}: texts read params keys the case lacks: {missing}"
    options = set(re.findall(r"\braster_options\.([a-z_]+)", joined))
    assert options <= RASTER_OPTIONS, f"{name}: unknown raster_options {options - RASTER_OPTIONS}"
    roles = set(re.findall(r"texture role '([a-z0-9_-]+)'", joined))
    assert roles <= set(exported.textures), f"{name}: texts name missing roles {roles}"


# ---------------------------------------------------------------------------------------------
# The formulas the threshold texts state, coded from the texts alone, against refnpr's own.

_MASK64 = (1 << 64) - 1
_M1, _M2, _M3 = 0x9E3779B97F4A7C15, 0xBF58476D1CE4E5B9, 0x94D049BB133111EB
_ONE_BELOW = math.nextafter(1.0, 0.0)


def _frac(x: float) -> float:
    return min(x - math.floor(x), _ONE_BELOW)


def _mix(h: int) -> int:
    h ^= h >> 30
    h = h * _M2 & _MASK64
    h ^= h >> 27
    h = h * _M3 & _MASK64
    return h ^ (h >> 31)


def _noise(p: tuple[float, float], e: int) -> float:
    """threshold_noise's N(p) with seed e."""

    def hash_ij(i: int, j: int, seed: int) -> float:
        h = (i & _MASK64) * _M1 & _MASK64
        h ^= ((j & _MASK64) * _M2 + (seed & 0xFFFFFFFF) * _M3) & _MASK64
        return (_mix(h) >> 11) / 2.0**53

    def octave(x: float, y: float, seed: int) -> float:
        i, j = math.floor(x), math.floor(y)
        fade = [f * f * f * (f * (6 * f - 15) + 10) for f in (x - i, y - j)]
        h00, h10 = hash_ij(i, j, seed), hash_ij(i + 1, j, seed)
        h01, h11 = hash_ij(i, j + 1, seed), hash_ij(i + 1, j + 1, seed)
        top = h00 + fade[0] * (h10 - h00)
        bottom = h01 + fade[0] * (h11 - h01)
        return top + fade[1] * (bottom - top)

    o = octave(p[0], p[1], e) + 0.5 * octave(2 * p[0] + 17, 2 * p[1] + 17, e + 1)
    return (o / 1.5) * 2 - 1


def test_value_noise_text_is_refnpr_value_noise():
    """threshold_noise: the lattice hash, the quintic fade and the two octaves, bit for bit."""
    from refnpr.styles.threshold.noise import value_noise

    rng = np.random.default_rng(1)
    p = rng.uniform(-40.0, 40.0, (300, 2))
    for seed in (0, 9, -3):
        ours = np.array([_noise((x, y), seed) for x, y in p])
        np.testing.assert_array_equal(ours, value_noise(p, seed=seed))


def _stipple(u: float, v: float, s: tuple[float, float], e: int, jitter: float, cdf=None):
    """threshold_stipple's threshold at (u, v) for the scales s = (s_u, s_v)."""

    def bits(x: float) -> int:
        return struct.unpack("<Q", struct.pack("<d", x + 0.0))[0]

    def unit(h: int) -> float:
        return (h >> 11) / 2.0**53

    def quadrant(r: float, x_half: float, y_half: float) -> float:
        def prim(x: float) -> float:
            root = math.sqrt(max(r * r - x * x, 0.0))
            return (x * root + r * r * math.atan2(x, root)) / 2

        m = min(x_half, r)
        xc = min(math.sqrt(max(r * r - y_half * y_half, 0.0)), m)
        return y_half * xc + prim(m) - prim(xc)

    def dot(ku: float, kv: float, au: float, av: float) -> float:
        big_v = v * 2.0**kv
        j = math.floor(big_v + 0.5)
        v_row = j * 2.0**-kv
        phase = unit(_mix((bits(v_row) * _M1 + e * _M3) & _MASK64)) if jitter > 0 else 0.0
        big_u = (u - phase) * 2.0**ku
        i = math.floor(big_u + 0.5)
        ou = ov = 0.0
        if jitter > 0:
            h = _mix((bits(v_row) * _M1 + e * _M3 + 1) & _MASK64)
            h = _mix(h ^ (bits(i * 2.0**-ku) * _M2 & _MASK64))
            g = _mix((h + _M1) & _MASK64)
            ou, ov = jitter * (2 * unit(h) - 1), jitter * (2 * unit(g) - 1)
        r = math.hypot((big_u - i - ou) * au, (big_v - j - ov) * av)
        xl, xr, yl, yr = (0.5 + ou) * au, (0.5 - ou) * au, (0.5 + ov) * av, (0.5 - ov) * av
        area = quadrant(r, xl, yl) + quadrant(r, xr, yl) + quadrant(r, xl, yr)
        area += quadrant(r, xr, yr)
        return min(max(1 - area / (au * av), 0.0), 1.0)

    def weight(b: int, t: float) -> float:
        return t if b else 1 - t

    k = [min(max(math.floor(x), -1100), 1100) for x in s]
    t = [x - math.floor(x) for x in s]
    a = [2.0 ** t[0], 2.0 ** t[1]]
    f = 0.0
    for bu in (0, 1):
        for bv in (0, 1):
            d = dot(k[0] + bu, k[1] + bv, a[0] / (1 + bu), a[1] / (1 + bv))
            f = f + weight(bu, t[0]) * weight(bv, t[1]) * d
    if cdf is not None:

        def split(x: float, n: int) -> tuple[int, float]:
            c = min(max(x, 0.0), 1.0) * n
            i = min(max(math.floor(c), 0), n - 1)
            return int(i), c - i

        (ia, fa), (ib, fb) = split(t[0], cdf.shape[0] - 1), split(t[1], cdf.shape[0] - 1)
        iy, fy = split(f, cdf.shape[2] - 1)
        out = 0.0
        for da in (0, 1):
            for db in (0, 1):
                row = cdf[ia + da, ib + db]
                g = row[iy] * (1 - fy) + row[iy + 1] * fy
                out = out + weight(da, fa) * weight(db, fb) * g
        f = out
    return min(max(f, 0.0), 1.0)


def test_stipple_text_is_refnpr_stipple():
    """threshold_stipple: per-axis scales, the tensor blend, the row-phase and offset hashes,
    the dot's area and the tone table, to a float64 rounding."""
    from refnpr.formulas import threshold as thr

    rng = np.random.default_rng(2)
    uv = rng.uniform(-5.0, 5.0, (200, 2))
    s_u, s_v = rng.uniform(-3.0, 4.0, (2, 200))
    table = thr.stipple_tone_table(jitter=0.2)
    for seed, jitter, tab in ((0, 0.2, None), (4242, 0.35, None), (0, 0.0, None), (7, 0.2, table)):
        ref = thr.stipple_threshold(uv, s_u, s_v, jitter=jitter, seed=seed, tone_table=tab)
        cdf = None if tab is None else tab.cdf
        ours = [
            _stipple(u, v, (a, b), seed & 0xFFFFFFFF, jitter, cdf)
            for (u, v), a, b in zip(uv, s_u, s_v, strict=True)
        ]
        np.testing.assert_allclose(ours, ref, rtol=0, atol=1e-14)


def _coverage(v: float, s: float, y: float, gx: float, gy: float, uniform: bool) -> float:
    """threshold_analytic's C(y): the exact fraction of the square footprint where F <= y."""
    k = min(max(math.floor(s), -1100), 1100)
    t = s - math.floor(s)
    u0 = _frac(v * 2.0**k)
    a, b = max(abs(gx), abs(gy)) * 2.0**k, min(abs(gx), abs(gy)) * 2.0**k
    if not uniform:
        pieces = [(0.0, min(max(y / (1 + t), 0), 0.5))]
        pieces.append((0.5, min(max((y + t) / (1 + t) - 0.5, 0), 0.5)))
    else:
        ca = (1 - t) / (2 * (1 + t))
        cb = 1 - ca
        pieces = [
            (0.0, min(max(y, 0), ca)),
            (ca, min(max((y - ca) / 2, 0), 0.5 - ca)),
            (0.5, min(max((y + cb) / 2 - 0.5, 0), cb - 0.5)),
            (cb, min(max(y - cb, 0), 1 - cb)),
        ]
    if y >= 1:
        return 1.0
    if y < 0:
        return 0.0
    if a < 1e-100:
        r1 = 2 * u0 if u0 < 0.5 else 2 * u0 - 1
        if uniform:
            ca = (1 - t) / (2 * (1 + t))
            cb = 1 - ca
            f = u0 if u0 < ca else 2 * u0 - ca if u0 < 0.5 else 2 * u0 - cb if u0 < cb else u0
        else:
            f = (1 - t) * u0 + t * r1
        return 1.0 if y >= min(max(f, 0.0), _ONE_BELOW) else 0.0
    b = 0.0 if b < 1e-200 else b
    total = 0.0
    for c, length in pieces:
        z = u0 - c

        def j_(x: float, ln: float = length) -> float:
            return min(_frac(x), ln) - ln * _frac(x)

        def d_(x: float, ln: float = length) -> float:
            f = _frac(x)
            m = f * f / 2 if f <= ln else ln * f - ln * ln / 2
            return m - ln * f * f / 2 - ln * (1 - ln) * f / 2

        def ramp(z0: float, sg: int, ln: float = length) -> float:
            out = 0.0
            for m in range(math.floor(z0) - 3, math.floor(z0) + 4):
                g, h = (m - z0, m + ln - z0) if sg > 0 else (z0 - m - ln, z0 - m)
                g, h = min(max(g, 0.0), b), min(max(h, 0.0), b)
                out += (h - g) * (h + g) / 2
            return out

        if b == 0:
            total += length + (j_(z + a / 2) - j_(z - a / 2)) / a
        elif b >= 1:
            dd = d_(z + (a + b) / 2) - d_(z + (a - b) / 2) - d_(z - (a - b) / 2)
            total += length + (dd + d_(z - (a + b) / 2)) / (a * b)
        else:
            plateau = (length * (a - b) + j_(z + (a - b) / 2) - j_(z - (a - b) / 2)) / a
            total += plateau + (ramp(z - (a + b) / 2, 1) + ramp(z + (a + b) / 2, -1)) / (a * b)
    return min(max(total, 0.0), 1.0)


def test_analytic_line_filter_text_is_refnpr_line_coverage():
    """threshold_analytic: the trapezoid of the square footprint projected on v, integrated
    against the white intervals of both line functions."""
    from refnpr.formulas import threshold as thr

    rng = np.random.default_rng(3)
    n = 400
    v, s, y = rng.uniform(-2, 2, n), rng.uniform(-2, 5, n), rng.uniform(-0.1, 1.1, n)
    g = rng.uniform(-1, 1, (n, 2)) * 10.0 ** rng.uniform(-4, 1, (n, 1))
    g[:20, 1] = 0.0
    g[20:30] = 0.0
    for uniform in (False, True):
        ref = thr.line_coverage(v, s, y, g[:, 0], g[:, 1], uniform=uniform)
        ours = [_coverage(*args, uniform) for args in zip(v, s, y, g[:, 0], g[:, 1], strict=True)]
        np.testing.assert_allclose(ours, ref, rtol=0, atol=1e-11)


def test_layer_schedule_text_is_refnpr_composition():
    """threshold_layers: the white fractions from {lam, levels} and the combined threshold."""
    from refnpr.formulas import threshold as thr

    rng = np.random.default_rng(4)
    for onsets in ([1.0, 1.0], [1.0, 0.5], [0.4, 1.0, 0.7, 0.2]):
        lam, levels = thr.layer_schedule(onsets)
        b, d = levels.shape
        x = rng.uniform(-0.05, 1.05, 200)
        for layer in range(d):
            ours = []
            for xi in x:
                c = min(max(xi, 0.0), 1.0)
                big = -math.log(c) if c > 0 else math.inf
                li = np.interp(big, lam, levels[:, layer])
                if big > lam[-1]:
                    li = levels[-1, layer] + (big - lam[-1]) / d
                ours.append(math.exp(-li))
            np.testing.assert_array_equal(ours, thr.layer_whites(x, onsets)[layer])
        fs = rng.uniform(0.0, 1.0, (d, 200))
        fs[:, :5] = 0.0
        ours = []
        for col in fs.T:
            best = math.inf
            for layer, f in enumerate(col):
                q = -math.log(f) if f > 0 else math.inf
                count = int(np.sum(levels[:, layer] <= q))
                if count == b:
                    best = min(best, lam[-1] + (q - levels[-1, layer]) * d)
                    continue
                hi = 0 if b == 1 else min(max(count, 1), b - 1)
                lo = max(hi - 1, 0)
                gap = levels[hi, layer] - levels[lo, layer]
                gap = gap if gap > 0 else 1.0
                best = min(best, lam[lo] + (q - levels[lo, layer]) * (lam[hi] - lam[lo]) / gap)
            ours.append(min(max(math.exp(-best), 0.0), _ONE_BELOW))
        np.testing.assert_array_equal(ours, thr.combine_thresholds(list(fs), onsets=onsets))
