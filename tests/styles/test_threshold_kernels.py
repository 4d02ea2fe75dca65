"""The ``threshold`` style's one-pass numba shading (``refnpr.styles.threshold._kernels``, called
by ``ThresholdStyle.shade``) against an oracle written here: the paper's composition (eq. 1's
terms, their thresholds from each source, T_n, PCF and the analytic filter of sec. 4, the
strength of sec. 5, eq. 2's sums) spelled out in numpy over the covered samples, calling the
public formulas of ``refnpr.formulas`` (each tested against its own oracles in
``tests/formulas``). Exact float32 equality on random G-buffers (hypothesis: random parameters,
normals, uv and derivatives over many octaves, materials, point and directional lights) and on
rendered scenes; the same result for 1 and 2 numba threads; bad input refused."""

from __future__ import annotations

import math
from types import SimpleNamespace

import numba
import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from refnpr.formulas import lighting
from refnpr.formulas import threshold as thr
from refnpr.raster import rasterize
from refnpr.render import as_scene
from refnpr.scenes.scene import Light, Material
from refnpr.styles.base import ShadeContext
from refnpr.styles.threshold import ThresholdStyle
from refnpr.styles.threshold.images import grid_offsets
from refnpr.styles.threshold.noise import value_noise

from ._oracles import light_dirs, view_dir


class _GB(dict):
    """A dict of channels with the G-buffer's ``n`` (samples per pixel per axis)."""

    def __init__(self, channels, n=1):
        super().__init__(channels)
        self.n = n


def _bits_equal(got: np.ndarray, want: np.ndarray) -> None:
    assert got.dtype == np.float32 and got.shape == want.shape
    bad = np.argwhere(np.any(got != want, axis=-1))
    assert bad.size == 0, (
        f"{len(bad)} samples differ (max {np.abs(got - want).max():.3g}), "
        f"first at {bad[:3].tolist()}"
    )


# ------------------------------------------------------------------ the oracle


def _thresholds(style, ctx, mask, fp, k_grid):
    """(M, K) thresholds of the covered samples for the constant, lines and stipple sources."""
    p = style.p
    m = int(mask.sum())
    if p.source == "constant":
        return np.full((m, 1), p.t)
    if p.source == "image":
        return style.image_thresholds(ctx, mask)[0]
    o = grid_offsets(k_grid) / ctx.gb.n
    if p.source == "stipple":
        s_u, s_v = thr.stipple_scales(fp.gx, fp.gy, p.period)  # eq. 5 per axis
        if not p.multiscale:
            s_u, s_v = np.floor(s_u), np.floor(s_v)
        table = style.stipple_tone_table() if p.uniform else None
        kw = {"jitter": p.jitter, "seed": p.noise_seed, "tone_table": table}
        if p.filter != "pcf":
            return thr.stipple_threshold(fp.uv, s_u, s_v, **kw)[:, None]
        return thr.stipple_threshold(fp.offsets_uv(k_grid), s_u[:, None], s_v[:, None], **kw)
    layers = []
    for v, dvx, dvy, s in _layers(style, ctx, mask, fp):
        vk = v[:, None] + o[None, :, 0] * dvx[:, None] + o[None, :, 1] * dvy[:, None]
        layers.append(thr.line_threshold(vk, s[:, None], uniform=p.uniform, noise=_noise(p, fp)))
    if len(layers) == 1:
        return layers[0]
    return thr.combine_thresholds(layers, onsets=p.onsets)


def _noise(p, fp):
    if p.noise == 0.0:
        return None
    return (p.noise * value_noise(fp.uv * p.noise_scale, seed=p.noise_seed))[:, None]


def _layers(style, ctx, mask, fp):
    """Per hatching direction: v, its pixel derivatives and eq. 5's scale, (M,) each."""
    p, gb = style.p, ctx.gb
    channel = style._channel_scale() and "dyadic_scale" in gb
    out = []
    for deg in p.directions:
        a = float(np.radians(deg))
        v, dvx, dvy = (thr.hatch_coordinate(q, a) for q in (fp.uv, fp.gx, fp.gy))
        if deg == 0.0 and channel:  # the G-buffer's eq. 5 for the unscaled v, minus log2(sv)
            s = gb["dyadic_scale"][mask].astype(np.float64) - np.log2(
                style.uv_scales(ctx, mask)[:, 1]
            )
        else:
            s = thr.dyadic_scale_from_gradient(dvx, dvy, p.period)
        out.append((v, dvx, dvy, s if p.multiscale else np.floor(s)))
    return out


def _analytic(style, ctx, mask, fp, x):
    """Box-filtered T_n(x, F) of the layers: eq. 4 with T(Frac(x n), F) replaced by the product
    of the layers' coverages at their white fractions (sec. 4)."""
    p = style.p
    xn = x * p.n
    base = np.floor(xn)
    r = xn - base
    layers = _layers(style, ctx, mask, fp)
    onsets = p.onsets if p.onsets is not None else (1.0,) * len(layers)
    whites = thr.layer_whites(r, onsets) if len(layers) > 1 else [r]
    z = _noise(p, fp)
    cover = np.ones_like(x)
    for (v, dvx, dvy, s), w in zip(layers, whites, strict=True):
        gx, gy = dvx / ctx.gb.n, dvy / ctx.gb.n

        def cov(level, v=v, s=s, gx=gx, gy=gy):
            return thr.line_coverage(v, s, level, gx, gy, uniform=p.uniform)

        if z is None:
            cover = cover * cov(w)
        else:
            zf = z[:, 0] - np.floor(z[:, 0])
            cover = cover * (cov(w - zf) + cov(w + 1.0 - zf) - cov(1.0 - zf))
    cover = np.where(r >= 1.0, 1.0, np.clip(cover, 0.0, 1.0))
    return np.minimum(base + cover, np.ceil(xn)) / p.n


def oracle(style, ctx) -> np.ndarray:
    """Eq. 2 per covered sample, as the docs spell it (float64, then clipped and float32)."""
    p, gb, scene = style.p, ctx.gb, ctx.scene
    mask = ctx.mask
    fp = style.footprint(ctx, mask)
    k_grid = int(round(p.samples**0.5)) if p.filter == "pcf" else 1
    t = None if p.filter == "analytic" else _thresholds(style, ctx, mask, fp, k_grid)
    w = None
    if p.source == "image":
        w = style.image_thresholds(ctx, mask)[1]

    def tn(x, ts, ws):  # eq. 4 for one threshold, the PCF average of several (sec. 4)
        if ts.shape[1] == 1 and ws is None:
            return thr.step_n(x, ts[:, 0], p.n)
        return thr.pcf_threshold(x, ts, weights=ws, n=p.n)

    n = gb["normal"][mask].astype(np.float64)
    if p.bump is not None:
        dpdx = gb["dposition_dx"][mask].astype(np.float64)
        dpdy = gb["dposition_dy"][mask].astype(np.float64)
        n = style._bump.normals(n, fp.uv, fp.gx, fp.gy, dpdx, dpdy)
    view = view_dir(ctx, mask) if (p.specular or p.facing_fade > 0.0) else None
    st0 = np.full(n.shape[0], p.strength)
    if p.facing_fade > 0.0:
        n_dot_v = np.sum(n * view, axis=-1)
        st0 = p.strength * thr.facing_strength(n_dot_v, p.facing_fade, p.facing_power)
    rgb = ctx.material_field("ambient", mask) * np.asarray(scene.ambient, dtype=np.float64)

    def term(x, ts, ws):
        tx = _analytic(style, ctx, mask, fp, x) if ts is None else tn(x, ts, ws)
        return thr.strength_blend(x, tx, st0 * thr.tone_strength(x, *p.tone_fade))

    m_s = ctx.material_field("specular", mask)
    shininess = ctx.material_field("shininess", mask)
    for l, color in light_dirs(ctx, mask):
        f_d = lighting.diffuse(n, l)  # eq. 1
        rgb = rgb + ctx.material_field("diffuse", mask) * term(f_d, t, w)[:, None] * color
        if not p.specular:
            continue
        f_s = np.zeros(n.shape[0])
        for q in np.unique(shininess):
            sel = shininess == q
            ll = l[sel] if np.ndim(l) > 1 else l
            f_s[sel] = lighting.specular(n[sel], ll, view[sel], shininess=q, normalize=False)
        if isinstance(p.specular_threshold, str):
            tx = term(f_s, t, w)
        else:
            const = np.full((n.shape[0], 1), p.specular_threshold)
            tx = thr.strength_blend(
                f_s, tn(f_s, const, None), st0 * thr.tone_strength(f_s, *p.tone_fade)
            )
        rgb = rgb + np.where((m_s != 0.0).any(axis=1)[:, None], m_s * tx[:, None] * color, 0.0)
    out = np.zeros(mask.shape + (4,), dtype=np.float32)
    out[mask, :3] = np.clip(rgb, 0.0, 1.0)
    out[mask, 3] = 1.0
    return out


# ------------------------------------------------------------------ random G-buffers

MATERIALS = (
    Material(ambient=(0.1, 0.1, 0.05), diffuse=(0.85, 0.8, 0.7), specular=(0.4, 0.4, 0.5)),
    Material(diffuse=(0.3, 0.6, 0.9), specular=(1.0, 1.0, 1.0), shininess=2.0, uv_scale=(3, 0.5)),
    Material(ambient=(0.3, 0.3, 0.3), specular=(0.0, 0.0, 0.0), shininess=0.5),
    Material(diffuse=(0.9, 0.1, 0.2), specular=(0.3, 0.3, 0.3), shininess=7.3, uv_scale=(8, 8)),
)
LIGHTS = {
    "directional": (Light(direction=(0.4, 0.8, 0.5), color=(1.0, 0.95, 0.9)),),
    "mixed": (
        Light(direction=(-0.3, 0.2, 1.0), color=(0.6, 0.6, 0.6)),
        Light(kind="point", position=(-2.0, 1.0, 1.5), color=(0.5, 0.4, 0.3)),
        Light(kind="point", position=(0.1, -0.2, 0.05), color=(0.3, 0.3, 0.3)),
    ),
}


def random_ctx(
    seed: int, lights: str, *, shape=(23, 31), n: int = 1, channel: bool = True, zero: bool = True
):
    """Random G-buffer: unit float32 normals (some on axes), positions, uv over many periods,
    derivatives over many octaves (some zero), a dyadic_scale channel, mesh ids in [-1, 3]
    and a tri_id covering a few samples mesh_id leaves empty."""
    rng = np.random.default_rng(seed)
    nrm = rng.standard_normal(shape + (3,))
    nrm /= np.linalg.norm(nrm, axis=-1, keepdims=True)
    nrm[::5, ::3] = (0.0, 0.0, 1.0)
    pos = rng.uniform(-1.5, 1.5, shape + (3,))
    pos[2::7, 3::5] = (0.1, -0.2, 0.05)  # on a point light
    mesh_id = rng.integers(-1, len(MATERIALS), shape).astype(np.int32)
    tri = np.where(mesh_id >= 0, rng.integers(0, 100, shape), -1)
    tri[rng.random(shape) < 0.05] = 3
    uv = rng.uniform(-20.0, 20.0, shape + (2,))
    scale = 2.0 ** rng.uniform(-12.0, 2.0, shape + (2, 2))
    duv = rng.standard_normal(shape + (2, 2)) * scale
    if zero:
        duv[1::6, ::4] = 0.0  # zero footprint: s clamped to the tiny gradient
    gb = {
        "normal": nrm.astype(np.float32),
        "position": pos.astype(np.float32),
        "mesh_id": mesh_id,
        "tri_id": tri.astype(np.int32),
        "uv": uv.astype(np.float32),
        "duv_dx": duv[..., 0].astype(np.float32),
        "duv_dy": duv[..., 1].astype(np.float32),
        "dposition_dx": (0.01 * rng.standard_normal(shape + (3,))).astype(np.float32),
        "dposition_dy": (0.01 * rng.standard_normal(shape + (3,))).astype(np.float32),
    }
    if channel:
        gb["dyadic_scale"] = rng.uniform(-6.0, 6.0, shape).astype(np.float32)
    scene = SimpleNamespace(
        objects=[SimpleNamespace(material=m) for m in MATERIALS],
        lights=LIGHTS[lights],
        ambient=(0.9, 1.0, 1.1),
        camera=SimpleNamespace(eye=(0.3, 0.5, 4.0)),
    )
    return ShadeContext(_GB(gb, n), scene)


_DIRECTIONS = st.sampled_from(
    [(0.0,), (90.0,), (30.0,), (45.0, -45.0), (0.0, 90.0), (30.0, -60.0, 75.0)]
)


@st.composite
def line_params(draw):
    dirs = draw(_DIRECTIONS)
    p = dict(
        source="lines",
        directions=list(dirs),
        n=draw(st.integers(1, 4)),
        period=draw(st.sampled_from([3.0, 6.0, 8.5])),
        uniform=draw(st.booleans()),
        multiscale=draw(st.booleans()),
        specular=draw(st.booleans()),
        strength=draw(st.sampled_from([1.0, 0.6, 0.0])),
        filter=draw(st.sampled_from(["none", "pcf", "analytic"])),
    )
    if p["filter"] == "pcf":
        p["samples"] = draw(st.sampled_from([1, 4, 9, 16]))
    if draw(st.booleans()):
        p["facing_fade"] = draw(st.sampled_from([0.5, 1.0]))
        p["facing_power"] = draw(st.sampled_from([1.0, 2.0, 0.5, 3.0]))
    if draw(st.booleans()):
        p["tone_fade"] = [draw(st.sampled_from([0.0, 0.2])), draw(st.sampled_from([0.0, 0.3]))]
    if len(dirs) > 1 and draw(st.booleans()):
        p["onsets"] = [1.0] + [draw(st.sampled_from([0.8, 0.5, 0.25])) for _ in dirs[1:]]
    if draw(st.booleans()):
        p["noise"] = draw(st.sampled_from([0.1, 0.3]))
        p["noise_scale"] = 3.0
    if draw(st.booleans()):
        p["uv_scale"] = draw(st.sampled_from([4.0, [2.0, 0.25]]))
    if draw(st.booleans()):
        p["specular_threshold"] = draw(st.sampled_from([0.0, 0.5, 1.0]))
    return p


@settings(max_examples=40, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(
    params=line_params(),
    seed=st.integers(0, 2**16),
    lights=st.sampled_from(sorted(LIGHTS)),
    n=st.sampled_from([1, 2]),
    channel=st.booleans(),
)
def test_lines_kernel_equals_the_oracle(params, seed, lights, n, channel):
    style = ThresholdStyle(**params)
    ctx = random_ctx(seed, lights, n=n, channel=channel)
    _bits_equal(style.shade(ctx), oracle(style, ctx))


@settings(max_examples=20, deadline=None)
@given(
    n=st.integers(1, 5),
    t=st.sampled_from([0.0, 0.25, 0.5, 1.0]),
    seed=st.integers(0, 2**16),
    lights=st.sampled_from(sorted(LIGHTS)),
    spec_t=st.sampled_from(["texture", 0.0, 0.7]),
    fade=st.sampled_from([0.0, 1.0]),
    bump=st.booleans(),
)
def test_constant_kernel_equals_the_oracle(n, t, seed, lights, spec_t, fade, bump):
    style = ThresholdStyle(
        source="constant", n=n, t=t, specular_threshold=spec_t, facing_fade=fade,
        tone_fade=[0.1, 0], bump="gravel" if bump else None,
    )  # fmt: skip
    ctx = random_ctx(seed, lights)
    _bits_equal(style.shade(ctx), oracle(style, ctx))


@pytest.mark.parametrize("filt, samples", [("none", 1), ("pcf", 1), ("pcf", 4), ("pcf", 64)])
@pytest.mark.parametrize("uniform", [False, True])
def test_stipple_kernel_equals_the_oracle(filt, samples, uniform):
    kw = {"samples": samples} if filt == "pcf" else {}
    style = ThresholdStyle(source="stipple", period=5.0, filter=filt, n=2, uniform=uniform, **kw)
    ctx = random_ctx(samples, "mixed", n=2, zero=False)  # stipple: NaN at zero footprints
    _bits_equal(style.shade(ctx), oracle(style, ctx))


# ------------------------------------------------------------------ rendered scenes

SCENE_CASES = [
    ("teapot", dict(source="constant", n=2, t=0.5), 1),
    ("sphere", dict(source="image", texture="camera", n=2, filter="pcf", samples=1), 4),
    ("sphere", dict(source="image", texture="camera", filter="pcf", samples=4, mip="trilinear"), 1),
    ("veryovka_room", dict(source="image", filter="none"), 1),
    ("veryovka_room", dict(source="image", filter="pcf", samples=4, tone_correct=True), 1),
    ("sphere", dict(source="constant", bump="gravel", bump_height=0.01, uv_scale=[4.0, 2.0]), 4),
    ("sphere", dict(source="lines", bump="gravel", period=6.0, uv_scale=4.0), 1),
    ("sphere", dict(source="lines", directions=[30.0, -60.0], onsets=[1.0, 0.75]), 1),
    ("sphere", dict(source="lines", uniform=True, noise=0.25, noise_scale=3.0), 4),
    ("sphere", dict(source="stipple", period=5.0, uv_scale=8.0, uniform=True), 1),
    (
        "teapot",
        dict(source="lines", directions=[0.0, 90.0], facing_fade=1.0, tone_fade=[0.2, 0.3]),
        1,
    ),
    ("torus_knot", dict(source="lines", period=4.0, filter="pcf", samples=9, multiscale=False), 1),
    ("teapot", dict(source="lines", uniform=True, directions=[0.0, 90.0], filter="analytic"), 4),
    ("sphere", dict(source="lines", noise=0.3, filter="analytic", multiscale=False, n=3), 4),
    ("veryovka_materials", None, 4),
    ("veryovka_plane", dict(), 1),
]


@pytest.mark.parametrize("scene_name, params, spp", SCENE_CASES, ids=lambda v: repr(v)[:60])
def test_scene_kernel_equals_the_oracle(scene_name, params, spp):
    scene = as_scene(scene_name)
    if params is None:  # the scene's own style
        params = {k: v for k, v in scene.style.items() if k not in ("name", "contours")}
    style = ThresholdStyle(**params)
    gb = rasterize(
        scene, scene.camera, 48, 40, sorted(style.requires(scene)), spp,
        **style.raster_options(scene),
    )  # fmt: skip
    ctx = ShadeContext(gb, scene)
    _bits_equal(style.shade(ctx), oracle(style, ctx))


def test_deprecated_scale_multiplies_the_materials_uv_scale():
    scene = as_scene("veryovka_plane")
    with pytest.warns(DeprecationWarning):
        style = ThresholdStyle(scale=2.0)
    gb = rasterize(scene, scene.camera, 48, 40, sorted(style.requires(scene)), 4)
    ctx = ShadeContext(gb, scene)
    assert np.all(style.uv_scales(ctx, ctx.mask) == 2.0)
    _bits_equal(style.shade(ctx), oracle(style, ctx))


# ------------------------------------------------------------------ threads, dispatch, input


def test_same_result_for_one_and_two_threads():
    ctx = random_ctx(7, "mixed", shape=(67, 53), n=2, zero=False)
    styles = [
        ThresholdStyle(source="lines", directions=[30.0, -60.0], filter="pcf", noise=0.2),
        ThresholdStyle(source="lines", directions=[0.0, 90.0], filter="analytic", uniform=True),
        ThresholdStyle(source="stipple", filter="pcf", samples=4, uniform=True),
        ThresholdStyle(source="constant", n=3, facing_fade=0.5),
    ]
    saved = numba.get_num_threads()
    try:
        results = []
        for threads in (1, min(2, numba.config.NUMBA_NUM_THREADS)):
            numba.set_num_threads(threads)
            results.append([s.shade(ctx) for s in styles])
    finally:
        numba.set_num_threads(saved)
    for a, b in zip(*results, strict=True):
        assert np.array_equal(a.view(np.uint32), b.view(np.uint32))


def test_empty_coverage():
    ctx = random_ctx(8, "directional", shape=(5, 6))
    ctx.gb["mesh_id"][:] = -1
    ctx.gb["tri_id"][:] = -1
    for style in (ThresholdStyle(), ThresholdStyle(filter="analytic", directions=[0.0, 90.0])):
        assert not np.any(style.shade(ctx))


def test_inconsistent_gbuffer_is_refused():
    ctx = random_ctx(10, "directional", shape=(6, 7))
    ctx.gb["mesh_id"][0, 0] = len(MATERIALS)
    with pytest.raises(ValueError, match="'mesh_id': got object index 4 but the scene has 4"):
        ThresholdStyle().shade(ctx)


def test_kernel_compiles_only_the_frames_modes():
    """One kernel per (source, cross-hatching, filtered), built on first use
    (refnpr._jit.specialised)."""
    from refnpr.styles.threshold import _kernels as K

    ctx = random_ctx(3, "directional", shape=(4, 5))
    ThresholdStyle(source="lines", directions=[0.0, 90.0], filter="analytic").shade(ctx)
    ThresholdStyle(source="constant").shade(ctx)
    ThresholdStyle(source="lines", filter="pcf", samples=4).shade(ctx)
    want = {(K.ANALYTIC, True, False), (K.CONSTANT, False, False), (K.LINES, False, True)}
    assert want <= set(K.shade_threshold_for.kernels)
    assert math.isfinite(K.ANALYTIC) and K.ANALYTIC not in (K.CONSTANT, K.LINES, K.IMAGE)


def test_stipple_with_and_without_tone_table_shares_one_compiled_scalar(monkeypatch):
    """numba types an array's writability: ``NO_TABLE`` and a tone table's ``cdf`` are both
    read-only, so the stipple scalar is compiled for one ``cdf`` type, by the face and the
    kernel alike. The arrays each path hands on are captured and typed (a kernel loaded from
    numba's disk cache compiles nothing, so its callee's signatures would say nothing)."""
    import numba

    from refnpr.formulas.threshold import stipple as S
    from refnpr.styles.threshold import _kernels as K

    seen = []
    face_elementwise, kernel_for = S.elementwise, K.shade_threshold_for

    def elementwise(scalar, dtype, *args, **kw):
        if scalar is thr.stipple_threshold.scalar:
            seen.append(("face", args[-1].value))
        return face_elementwise(scalar, dtype, *args, **kw)

    def shade_threshold_for(*case):
        kernel = kernel_for(*case)

        def run(frame, record, tables, out, kept):
            seen.append(("kernel", tables.cdf))
            return kernel(frame, record, tables, out, kept)

        return run

    monkeypatch.setattr(S, "elementwise", elementwise)
    monkeypatch.setattr(K, "shade_threshold_for", shade_threshold_for)
    ctx = random_ctx(5, "directional", shape=(4, 5))
    uv = np.random.default_rng(0).uniform(0.0, 4.0, (20, 2))
    table = thr.stipple_tone_table(n_t=3, n_y=5, samples=16)
    thr.stipple_threshold(uv, 1.3, 2.2)
    thr.stipple_threshold(uv, 1.3, 2.2, tone_table=table)
    ThresholdStyle(source="stipple").shade(ctx)
    ThresholdStyle(source="stipple", uniform=True).shade(ctx)
    # without and with a tone table, through the face (building a table calls it too) and the
    # kernel (uniform=True reads the style's table)
    assert {(w, c.size > 0) for w, c in seen} == {
        ("face", False),
        ("face", True),
        ("kernel", False),
        ("kernel", True),
    }
    cdf_types = {numba.typeof(c) for _, c in seen}
    assert len(cdf_types) == 1 and not next(iter(cdf_types)).mutable, cdf_types


@pytest.mark.parametrize("source", ["lines", "image"])
def test_a_read_only_gbuffer_is_shaded_by_the_same_compiled_kernel(source):
    """numba types an array's writability; the frame record and the tables are built read-only,
    so a G-buffer loaded read-only (a kit's) and one rasterized here share one compiled
    kernel, with the same result."""
    from refnpr.styles.threshold import _kernels as K

    ctx = random_ctx(7, "directional", shape=(4, 5))
    style = ThresholdStyle(source=source)
    want = style.shade(ctx)
    kernels = set(K.shade_threshold_for.kernels.values())
    counts = {k: len(k.body.signatures) for k in kernels}
    frozen_gb = _GB({k: v.copy() for k, v in ctx.gb.items()}, ctx.gb.n)
    for a in frozen_gb.values():
        a.flags.writeable = False
    got = style.shade(ShadeContext(frozen_gb, ctx.scene))
    assert set(K.shade_threshold_for.kernels.values()) == kernels
    assert {k: len(k.body.signatures) for k in kernels} == counts
    _bits_equal(got, want)
