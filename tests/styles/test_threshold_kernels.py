"""The ``threshold`` style's one-pass numba shading (``refnpr.styles.threshold._kernels``, called
by ``ThresholdStyle.shade``) against the numpy path it replaced (``ThresholdStyle._shade_numpy``,
whole-array calls of the formula functions of ``refnpr.formulas.threshold``): exact float32
equality on random G-buffers (hypothesis: random parameters, normals, uv and derivatives,
materials, point and directional lights) and on rendered scenes for every threshold source,
filter and option; the same result for 1 and 2 numba threads; bad input refused."""

from __future__ import annotations

from types import SimpleNamespace

import numba
import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from refnpr.raster import rasterize
from refnpr.render import as_scene
from refnpr.scenes.scene import Light, Material
from refnpr.styles.base import ShadeContext
from refnpr.styles.threshold import ThresholdStyle


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


# ------------------------------------------------------------------ random parameters

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


@settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(
    params=line_params(),
    seed=st.integers(0, 2**16),
    lights=st.sampled_from(sorted(LIGHTS)),
    n=st.sampled_from([1, 2]),
    channel=st.booleans(),
)
def test_lines_kernel_equals_numpy(params, seed, lights, n, channel):
    style = ThresholdStyle(**params)
    ctx = random_ctx(seed, lights, n=n, channel=channel)
    _bits_equal(style.shade(ctx), style._shade_numpy(ctx))


@settings(max_examples=30, deadline=None)
@given(
    n=st.integers(1, 5),
    t=st.sampled_from([0.0, 0.25, 0.5, 1.0]),
    seed=st.integers(0, 2**16),
    lights=st.sampled_from(sorted(LIGHTS)),
    spec_t=st.sampled_from(["texture", 0.0, 0.7]),
    fade=st.sampled_from([0.0, 1.0]),
)
def test_constant_kernel_equals_numpy(n, t, seed, lights, spec_t, fade):
    style = ThresholdStyle(
        source="constant", n=n, t=t, specular_threshold=spec_t, facing_fade=fade, tone_fade=[0.1, 0]
    )
    ctx = random_ctx(seed, lights)
    _bits_equal(style.shade(ctx), style._shade_numpy(ctx))


@pytest.mark.parametrize("filt, samples", [("none", 1), ("pcf", 1), ("pcf", 4), ("pcf", 64)])
def test_stipple_kernel_equals_numpy(filt, samples):
    kw = {"samples": samples} if filt == "pcf" else {}
    style = ThresholdStyle(source="stipple", period=5.0, filter=filt, n=2, **kw)
    ctx = random_ctx(samples, "mixed", n=2, zero=False)  # stipple: NaN at zero footprints
    _bits_equal(style.shade(ctx), style._shade_numpy(ctx))


# ------------------------------------------------------------------ rendered scenes

SCENE_CASES = [
    ("teapot", dict(source="constant", n=2, t=0.5), 1),
    ("sphere", dict(source="image", texture="camera", n=2, filter="pcf", samples=1), 4),
    ("sphere", dict(source="image", texture="camera", filter="pcf", samples=4, mip="trilinear"), 1),
    ("veryovka_room", dict(source="image", filter="none"), 1),
    ("veryovka_room", dict(source="image", filter="pcf", samples=4, tone_correct=True), 1),
    ("veryovka_room", dict(source="image", clahe_levels="base", filter="pcf", samples=1), 1),
    ("veryovka_room", dict(source="image", clahe_levels="none", tiling="periodic"), 1),
    ("sphere", dict(source="constant", bump="gravel", bump_height=0.01, uv_scale=[4.0, 2.0]), 4),
    ("sphere", dict(source="lines", bump="gravel", period=6.0, uv_scale=4.0), 1),
    ("sphere", dict(source="lines", period=6.0, uv_scale=4.0, uniform=True), 1),
    ("sphere", dict(source="lines", directions=[30.0, -60.0], onsets=[1.0, 0.75]), 1),
    ("sphere", dict(source="lines", uniform=True, noise=0.25, noise_scale=3.0), 4),
    ("sphere", dict(source="stipple", period=5.0, uv_scale=8.0, uniform=True), 1),
    ("sphere", dict(source="stipple", period=5.0, jitter=0.0, filter="pcf", samples=4), 1),
    (
        "teapot",
        dict(source="lines", directions=[0.0, 90.0], facing_fade=1.0, tone_fade=[0.2, 0.3]),
        1,
    ),
    ("vase", dict(source="lines", period=6.0, uniform=True, directions=[45.0, -45.0]), 4),
    ("torus_knot", dict(source="lines", period=4.0, filter="pcf", samples=9, multiscale=False), 1),
    ("teapot", dict(source="lines", uniform=True, directions=[0.0, 90.0], filter="analytic"), 4),
    ("vase", dict(source="lines", directions=[45.0, -45.0], onsets=[1, 0.5], filter="analytic"), 1),
    ("sphere", dict(source="lines", noise=0.3, filter="analytic", multiscale=False, n=3), 4),
    ("veryovka_materials", dict(), 4),
    ("veryovka_plane", dict(), 1),
    ("veryovka_plane", dict(scale=2.0), 4),
]


@pytest.mark.parametrize("scene_name, params, spp", SCENE_CASES, ids=lambda v: repr(v)[:60])
def test_scene_kernel_equals_numpy(scene_name, params, spp):
    scene = as_scene(scene_name)
    if scene_name == "veryovka_materials" and not params:
        params = {k: v for k, v in scene.style.items() if k not in ("name", "contours")}
    with pytest.warns(DeprecationWarning) if "scale" in params else _nothing():
        style = ThresholdStyle(**params)
    gb = rasterize(
        scene, scene.camera, 48, 40, sorted(style.requires(scene)), spp,
        **style.raster_options(scene),
    )  # fmt: skip
    ctx = ShadeContext(gb, scene)
    _bits_equal(style.shade(ctx), style._shade_numpy(ctx))


class _nothing:
    def __enter__(self):
        return self

    def __exit__(self, *exc):
        return False


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


@pytest.mark.parametrize("k", [1, 2, 7, 8, 9, 16, 31, 64, 127, 128, 129, 256, 257, 512])
def test_pairwise_sum_is_numpys(k):
    """The PCF average sums in numpy's order (pairwise, 8 accumulators), K up to 2 x 256."""
    from refnpr.styles.threshold._kernels import _pairwise

    a = np.random.default_rng(k).standard_normal((20, k))
    got = np.array([_pairwise(np.ascontiguousarray(row), k) for row in a])
    assert np.array_equal(got, np.sum(a, axis=-1))
    assert np.array_equal(got / k, np.mean(a, axis=-1))
