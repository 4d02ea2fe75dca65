"""toon and smooth shading in one numba pass (``lit.shading.lit_rgba``) against the formulas'
numpy faces assembled in numpy (the oracle): exact float32 equality on random G-buffers with
point and directional lights, several materials, both toon modes, both specular models, and
the same result for 1 and 2 numba threads."""

from __future__ import annotations

import math
from types import SimpleNamespace

import numba
import numpy as np
import pytest

from refnpr.formulas import lighting, threshold
from refnpr.scenes.scene import Light, Material
from refnpr.styles.base import ShadeContext
from refnpr.styles.smooth import SmoothStyle
from refnpr.styles.toon import ToonStyle

from ._oracles import light_dirs, scatter_rgba, specular_field, view_dir

# ------------------------------------------------------------------ oracle: the numpy shade()


def oracle_toon(style: ToonStyle, ctx: ShadeContext) -> np.ndarray:
    mask = ctx.mask
    n = ctx.gb["normal"][mask].astype(np.float64)
    m_d = ctx.material_field("diffuse", mask)
    m_s = ctx.material_field("specular", mask)
    rgb = ctx.material_field("ambient", mask) * np.asarray(ctx.scene.ambient, float)
    if style.mode == "lake":
        bounds = (np.arange(style.n) + style.t) / style.n
        ramp = lighting.toon_ramp_texture(bounds, np.arange(style.n + 1) / style.n, size=1024)
    v = view_dir(ctx, mask) if style.specular else None
    for light_dir, color in light_dirs(ctx, mask):
        f_d = lighting.diffuse(n, light_dir, normalize=False)
        if style.mode == "lake":
            tone = lighting.toon_ramp(f_d, ramp)
        else:
            tone = threshold.step_n(f_d, style.t, style.n)
        rgb = rgb + m_d * tone[:, None] * color
        if style.specular:
            f_s = specular_field(ctx, n, light_dir, v, mask=mask)
            rgb = rgb + m_s * threshold.step_n(f_s, style.t, style.n)[:, None] * color
    return scatter_rgba(rgb, mask)


def oracle_smooth(style: SmoothStyle, ctx: ShadeContext) -> np.ndarray:
    mask = ctx.mask
    n = ctx.gb["normal"][mask].astype(np.float64)
    v = view_dir(ctx, mask) if style.specular else None
    m_d = ctx.material_field("diffuse", mask)
    m_s = ctx.material_field("specular", mask)
    rgb = ctx.material_field("ambient", mask) * np.asarray(ctx.scene.ambient, float)
    for light_dir, color in light_dirs(ctx, mask):
        f_d = lighting.diffuse(n, light_dir, normalize=False)
        rgb = rgb + m_d * f_d[:, None] * color
        if style.specular:
            f_s = specular_field(ctx, n, light_dir, v, style.model, mask)
            rgb = rgb + m_s * f_s[:, None] * color
    return scatter_rgba(rgb, mask)


# ------------------------------------------------------------------ random G-buffers

MATERIALS = (
    Material(
        ambient=(0.12, 0.1, 0.08),
        diffuse=(0.85, 0.8, 0.7),
        specular=(0.4, 0.4, 0.5),
        shininess=40.0,
    ),
    Material(
        ambient=(0.0, 0.05, 0.2), diffuse=(0.3, 0.6, 0.9), specular=(1.0, 1.0, 1.0), shininess=2.0
    ),
    Material(
        ambient=(0.3, 0.3, 0.3), diffuse=(1.0, 1.0, 1.0), specular=(0.6, 0.2, 0.0), shininess=0.5
    ),
    Material(
        ambient=(0.05, 0.0, 0.0), diffuse=(0.9, 0.1, 0.2), specular=(0.3, 0.3, 0.3), shininess=7.3
    ),
    Material(
        ambient=(0.2, 0.2, 0.1), diffuse=(0.5, 0.5, 0.5), specular=(0.8, 0.8, 0.8), shininess=1.0
    ),
)

LIGHTS = {
    "directional": (Light(direction=(0.4, 0.8, 0.5), color=(1.0, 0.95, 0.9)),),
    "point": (Light(kind="point", position=(0.5, 2.0, 3.0), color=(0.9, 0.9, 1.2)),),
    "mixed": (
        Light(direction=(-0.3, 0.2, 1.0), color=(0.6, 0.6, 0.6)),
        Light(kind="point", position=(-2.0, 1.0, 1.5), color=(0.5, 0.4, 0.3)),
        Light(kind="point", position=(0.1, -0.2, 0.05), color=(0.3, 0.3, 0.3)),
    ),
}


def random_ctx(seed: int, lights: str, *, shape=(61, 83), tri_id: bool = True) -> ShadeContext:
    """A ShadeContext over a random G-buffer: unit float32 normals (a few rounded to N.L = 0 and
    N.L = 1 cases), float32 positions near the origin, mesh ids in [-1, 4], and tri_id covering
    some samples mesh_id leaves empty (material 0 there, as material_field clamps)."""
    rng = np.random.default_rng(seed)
    n = rng.standard_normal(shape + (3,))
    n /= np.linalg.norm(n, axis=-1, keepdims=True)
    n[::7, ::5] = (0.0, 0.0, 1.0)  # exact axis normals: N.L, N.H on level boundaries
    n[1::9, ::4] = (1.0, 0.0, 0.0)
    pos = rng.uniform(-1.5, 1.5, shape + (3,))
    pos[2::11, 3::13] = (0.1, -0.2, 0.05)  # on a point light: zero direction
    mesh_id = rng.integers(-1, len(MATERIALS), shape).astype(np.int32)
    gb = {"normal": n.astype(np.float32), "position": pos.astype(np.float32), "mesh_id": mesh_id}
    if tri_id:
        tri = np.where(mesh_id >= 0, rng.integers(0, 1000, shape), -1)
        tri[rng.random(shape) < 0.05] = 7  # covered per tri_id, empty per mesh_id
        gb["tri_id"] = tri.astype(np.int32)
    scene = SimpleNamespace(
        objects=[SimpleNamespace(material=m) for m in MATERIALS],
        lights=LIGHTS[lights],
        ambient=(0.9, 1.0, 1.1),
        camera=SimpleNamespace(eye=(0.3, 0.5, 4.0)),
    )
    return ShadeContext(gb, scene)


STYLES = [
    ToonStyle(n=2),
    ToonStyle(n=3, t=0.25),
    ToonStyle(n=1, t=0.0),
    ToonStyle(n=5, t=1.0, specular=False),
    ToonStyle(n=3, mode="lake"),
    ToonStyle(n=4, t=0.7, mode="lake"),
    SmoothStyle(),
    SmoothStyle(model="phong"),
    SmoothStyle(specular=False),
]


def oracle(style, ctx):
    return oracle_toon(style, ctx) if isinstance(style, ToonStyle) else oracle_smooth(style, ctx)


@pytest.mark.parametrize("lights", sorted(LIGHTS))
@pytest.mark.parametrize("style", STYLES, ids=repr)
def test_kernel_equals_numpy_oracle(style, lights):
    for seed, tri_id in ((0, True), (1, False)):
        ctx = random_ctx(seed, lights, tri_id=tri_id)
        got = style.shade(ctx)
        want = oracle(style, ctx)
        assert got.dtype == np.float32 and got.shape == want.shape
        bad = np.argwhere(np.any(got.view(np.uint32) != want.view(np.uint32), axis=-1))
        assert bad.size == 0, f"{len(bad)} samples differ, first at {bad[:3].tolist()}"


def test_same_result_for_one_and_two_threads():
    ctx = random_ctx(3, "mixed", shape=(97, 131))
    saved = numba.get_num_threads()
    try:
        results = []
        for threads in (1, min(2, numba.config.NUMBA_NUM_THREADS)):
            numba.set_num_threads(threads)
            results.append([s.shade(ctx) for s in (ToonStyle(n=3), SmoothStyle(model="phong"))])
    finally:
        numba.set_num_threads(saved)
    for a, b in zip(*results, strict=True):
        assert np.array_equal(a.view(np.uint32), b.view(np.uint32))


def test_empty_and_full_coverage():
    ctx = random_ctx(4, "directional", shape=(5, 6), tri_id=False)
    ctx.gb["mesh_id"][:] = -1
    assert not np.any(SmoothStyle().shade(ctx))
    ctx.gb["mesh_id"][:] = 2
    rgba = ToonStyle(n=2).shade(ctx)
    assert np.all(rgba[..., 3] == 1.0) and np.array_equal(rgba, oracle_toon(ToonStyle(n=2), ctx))


def test_rows_shaded_over_their_covered_span_only():
    """The row passes run over each row's covered span (``_covered_span``) and skip empty rows:
    a disc of coverage (empty rows above and below, spans of every width, a hole) shades as the
    numpy formulas do, for every style (the scratch rows keep the values of the rows before)."""
    ctx = random_ctx(6, "mixed", shape=(47, 59))
    yy, xx = np.mgrid[:47, :59]
    r2 = (yy - 23) ** 2 + (xx - 29) ** 2
    outside = (r2 > 18**2) | (r2 < 3**2)
    for key in ("mesh_id", "tri_id"):
        ctx.gb[key][outside] = -1
    assert np.any(np.all(outside, axis=1)) and not np.all(outside[23])
    for style in STYLES:
        got = style.shade(ctx)
        want = oracle(style, ctx)
        bad = np.argwhere(np.any(got.view(np.uint32) != want.view(np.uint32), axis=-1))
        assert bad.size == 0, f"{style!r}: {len(bad)} samples differ, first {bad[:3].tolist()}"
        assert not np.any(got[outside])


def test_inconsistent_gbuffer_is_refused():
    ctx = random_ctx(5, "point", shape=(6, 7))
    ctx.gb["normal"] = ctx.gb["normal"][:, :5]
    with pytest.raises(ValueError, match=r"channel 'normal': expected shape \(6, 7, 3\)"):
        SmoothStyle().shade(ctx)
    ctx = random_ctx(5, "point", shape=(6, 7))
    ctx.gb["mesh_id"][0, 0] = len(MATERIALS)
    with pytest.raises(ValueError, match="'mesh_id': got object index 5 but the scene has 5"):
        ToonStyle().shade(ctx)


def test_toon_checks_its_mode():
    with pytest.raises(ValueError, match=r"mode: expected one of \['step', 'lake'\], got 'flat'"):
        ToonStyle(mode="flat")


# ------------------------------------------------------------------ float64: the order of operations

_libm_pow = np.frompyfunc(math.pow, 2, 1)


def _specular_libm(ctx, n, light_dir, v, model, mask):
    """``specular_field`` (``lighting.specular`` with ``normalize=False``) with C's pow in place
    of numpy's (numpy's SIMD pow can differ from it by an ulp; the kernel calls C's)."""
    from refnpr.formulas._shading_checks import unit_vectors

    shininess = ctx.material_field("shininess", mask)
    n_dot_l = np.sum(n * light_dir, axis=-1)
    if model == "phong":
        base = np.sum((2 * n_dot_l[..., None] * n - light_dir) * v, axis=-1)
    else:
        base = np.sum(n * unit_vectors(light_dir + v), axis=-1)
    base = np.maximum(base, 0)
    powered = _libm_pow(base, shininess).astype(np.float64)
    return np.where((n_dot_l > 0) & (shininess > 0), powered, 0.0)


def oracle_float64(style, ctx) -> np.ndarray:
    """The oracle's rgb before the float32 cast: (nH, nW, 4) float64, C's pow."""
    toon = isinstance(style, ToonStyle)
    mode = style.mode if toon else "smooth"
    model = "blinn-phong" if toon else style.model
    mask = ctx.mask
    n = ctx.gb["normal"][mask].astype(np.float64)
    m_d = ctx.material_field("diffuse", mask)
    m_s = ctx.material_field("specular", mask)
    rgb = ctx.material_field("ambient", mask) * np.asarray(ctx.scene.ambient, float)
    if mode == "lake":
        bounds = (np.arange(style.n) + style.t) / style.n
        ramp = lighting.toon_ramp_texture(bounds, np.arange(style.n + 1) / style.n, size=1024)
    v = view_dir(ctx, mask) if style.specular else None
    for light_dir, color in light_dirs(ctx, mask):
        f_d = lighting.diffuse(n, light_dir, normalize=False)
        if mode == "lake":
            f_d = lighting.toon_ramp(f_d, ramp)
        elif mode == "step":
            f_d = threshold.step_n(f_d, style.t, style.n)
        rgb = rgb + m_d * f_d[:, None] * color
        if style.specular:
            f_s = _specular_libm(ctx, n, light_dir, v, model, mask)
            if mode == "step":
                f_s = threshold.step_n(f_s, style.t, style.n)
            rgb = rgb + m_s * f_s[:, None] * color
    out = np.zeros(mask.shape + (4,))
    out[mask, :3] = np.clip(rgb, 0.0, 1.0)
    out[mask, 3] = 1.0
    return out


@pytest.mark.parametrize("lights", sorted(LIGHTS))
@pytest.mark.parametrize("style", STYLES, ids=repr)
def test_kernel_float64_arithmetic_equals_the_formulas(style, lights):
    """Every float64 operation in the formulas' order: equal bits before the float32 cast."""
    ctx = random_ctx(2, lights)
    out = np.full(ctx.mask.shape + (4,), np.nan)
    got = style.shade(ctx, out=out)
    assert got is out
    want = oracle_float64(style, ctx)
    bad = np.argwhere(np.any(got.view(np.uint64) != want.view(np.uint64), axis=-1))
    assert bad.size == 0, f"{len(bad)} samples differ, first at {bad[:3].tolist()}"


def test_out_is_checked():
    ctx = random_ctx(7, "point", shape=(4, 5))
    with pytest.raises(ValueError, match=r"out: expected a writable C-contiguous \(4, 5, 4\)"):
        SmoothStyle().shade(ctx, out=np.zeros((4, 5, 3), np.float32))


@pytest.mark.parametrize(("n", "t"), [(1, 0.0), (2, 0.5), (3, 0.25), (4, 1.0), (7, 0.6180339887)])
def test_step_edges_give_the_tone_of_pow_near_every_breakpoint(n, t):
    """Where the table answers (the kernel's lookup, emulated), it equals T_n(pow(base, p))
    for bases crowding each breakpoint, each widened edge and their float neighbours."""
    from refnpr.styles.lit.shading import _step_edges

    shininess = np.array([40.0, 2.0, 0.5, 1.0, 7.3, 1e-3, 1e-5, 300.0])
    edge_lo, edge_hi, tones = _step_edges(shininess, n, t)
    rng = np.random.default_rng(n)
    answered = 0
    for m, p in enumerate(shininess):
        lo, hi = edge_lo[m], edge_hi[m]
        finite = np.concatenate([lo[np.isfinite(lo)], hi[np.isfinite(hi)]])
        base = np.concatenate([finite, lo[np.isfinite(lo)] ** 0, rng.random(400)])
        base = np.concatenate([np.nextafter(base, -1), base, np.nextafter(base, 2)])
        base = np.clip(np.concatenate([base, base * (1 + 2e-8), base * (1 - 2e-8)]), 0, 1.0)
        for b in base:
            j = 0
            while j < lo.size and b >= hi[j]:
                j += 1
            if (j < lo.size and b > lo[j]) or tones[j] < 0:
                continue  # the kernel evaluates pow here
            want = threshold.step_n(np.float64(math.pow(b, p)), t, n)
            assert tones[j] == want, (p, b, j)
            answered += 1
    # the table answers most bases (for n = 1, t = 0 only f_s >= 1 would be certain: none)
    if (n, t) != (1, 0.0):
        assert answered > 1000


def test_objects_without_a_specular_colour_skip_the_term_with_the_same_bits():
    """The kernels skip m_s f_s l_i where m_s or the light's colour is zero in every channel
    (``lit._kernels._spec_term``): the numpy formulas add that signed zero, which changes a
    sum only where the sum is itself -0 (here from -0 ambient and diffuse colours): exact."""
    mats = (
        Material(ambient=(0.1, 0.1, 0.1), diffuse=(0.8, 0.7, 0.6), specular=(0.0, 0.0, 0.0)),
        Material(ambient=(-0.0, 0.0, 0.2), diffuse=(-0.0, 0.5, 0.0), specular=(0.0, 0.0, 0.0)),
        Material(ambient=(0.0, 0.0, 0.0), diffuse=(-0.0, -0.0, -0.0), specular=(0.0, 0.0, 0.7)),
        MATERIALS[0],
    )
    lights = (
        Light(direction=(0.4, 0.8, 0.5), color=(1.0, 0.9, 0.0)),  # no blue: m_s of mats[2] off
        Light(kind="point", position=(0.5, 2.0, 3.0), color=(0.9, 0.9, 1.2)),
    )
    for seed in (4, 5):
        ctx = random_ctx(seed, "mixed")
        mesh_id = np.asarray(ctx.gb["mesh_id"]) % (len(mats) + 1) - 1
        gb = {**ctx.gb, "mesh_id": mesh_id.astype(np.int32)}
        gb["tri_id"] = np.where(mesh_id >= 0, 1, -1).astype(np.int32)
        scene = SimpleNamespace(
            objects=[SimpleNamespace(material=m) for m in mats],
            lights=lights,
            ambient=(0.9, 1.0, 1.1),
            camera=ctx.scene.camera,
        )
        ctx = ShadeContext(gb, scene)
        for style in STYLES:
            got = style.shade(ctx)
            want = oracle(style, ctx)
            bad = np.argwhere(np.any(got.view(np.uint32) != want.view(np.uint32), axis=-1))
            assert bad.size == 0, f"{style!r}: {len(bad)} samples differ, first {bad[:3].tolist()}"
