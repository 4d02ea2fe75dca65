"""X-Toon's one-pass numba shading (``xtoon.shading.shade_rgba``) against the style's numpy
evaluation (``evaluate``: the same formulas through their numpy faces, assembled by numpy code
here: ``toon_lookup`` + ``rgba_from``), on random G-buffers and rendered scenes, for every detail
map, tone, light kind, show view, modulate and the shape / per-vertex paths; the texture corners
against the texture itself; and the same result for 1 and 2 numba threads."""

from __future__ import annotations

import warnings
from types import SimpleNamespace

import numba
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from refnpr.formulas import xtoon as fx
from refnpr.image import srgb_to_linear
from refnpr.raster import Camera, rasterize
from refnpr.scenes import Light, Material, Scene, SceneObject, transform_matrix, uv_sphere
from refnpr.styles._common import rgba_from
from refnpr.styles.base import ShadeContext
from refnpr.styles.xtoon import XToonStyle
from refnpr.styles.xtoon.evaluation import evaluate
from refnpr.styles.xtoon.shading import fused

# ------------------------------------------------------------------ oracle: the numpy shade()


def oracle(style: XToonStyle, ctx: ShadeContext) -> np.ndarray:
    """``XToonStyle.shade`` assembled in numpy from ``evaluate``."""
    ev = evaluate(style._cfg, ctx)
    show = style._cfg.p.show
    if show != "color":
        value = {"detail": ev.detail, "inverse_detail": 1.0 - ev.detail, "tone": ev.tone}
        grey = np.zeros(ev.mask.shape)
        grey[ev.mask] = srgb_to_linear(np.clip(value[show], 0.0, 1.0))
        return rgba_from(grey[..., None], ev.mask)
    rgb = np.zeros(ev.mask.shape + (3,))
    alpha = np.zeros(ev.mask.shape)
    rgba = np.asarray(fx.toon_lookup(style._cfg.texture, ev.tone, ev.detail), dtype=np.float64)
    col = rgba[:, :3]
    if style._cfg.p.modulate:
        col = col * ctx.material_field("diffuse")[ev.mask]
    rgb[ev.mask] = col
    alpha[ev.mask] = rgba[:, 3]
    return rgba_from(rgb, ev.mask, alpha)


def assert_same(got: np.ndarray, want: np.ndarray) -> None:
    """float32 equality; libm's log/pow (kernel) and numpy's SIMD ones may differ by an ulp in
    float64, which can move a float32 result by one ulp at most: allowed on < 0.1 % of samples."""
    assert got.dtype == np.float32 and got.shape == want.shape
    diff = np.abs(got.astype(np.float64) - want)
    ulp = np.spacing(np.maximum(np.abs(want), np.abs(got)).astype(np.float32)).astype(np.float64)
    assert np.all(diff <= ulp), f"max difference {diff.max()} (beyond one float32 ulp)"
    n_diff = int(np.count_nonzero(np.any(got != want, axis=-1)))
    assert n_diff <= max(1, got[..., 0].size // 1000), f"{n_diff} samples differ by an ulp"


# ------------------------------------------------------------------ random G-buffers

CAMERA = Camera.look_at((0.3, 0.5, 4.0), (0.0, 0.0, 0.0), (0.0, 1.0, 0.0), 45.0, 0.1, 50.0)
MATERIALS = (
    Material(diffuse=(0.85, 0.8, 0.7)),
    Material(diffuse=(0.3, 0.6, 0.9)),
    Material(diffuse=(1.0, 0.2, 0.0)),
)
LIGHTS = {
    "directional": Light(direction=(0.4, 0.8, 0.5)),
    "point": Light(kind="point", position=(0.5, 2.0, 3.0)),
}


class _GB(dict):
    """A dict of channels with the G-buffer attributes ``evaluate`` reads."""

    def __init__(self, channels, n=1):
        super().__init__(channels)
        nh, nw = channels["mesh_id"].shape
        self.n, self.sample_shape = n, (nh, nw)
        self.height, self.width = nh // n, nw // n


def random_ctx(seed: int, light: str, shape=(41, 57)) -> ShadeContext:
    """Unit float32 normals (some exact axes, some zero), positions in front of the camera,
    view-axis depths, mesh ids in [-1, 2]."""
    rng = np.random.default_rng(seed)
    n = rng.standard_normal(shape + (3,))
    n /= np.linalg.norm(n, axis=-1, keepdims=True)
    n[::7, ::5] = (0.0, 0.0, 1.0)
    n[1::9, ::4] = (0.0, 0.0, 0.0)  # a zero normal: tone 0 (unit_rows keeps it zero)
    pos = rng.uniform(-1.5, 1.5, shape + (3,))
    pos[2::11, 3::13] = LIGHTS["point"].position  # on the point light: zero direction
    v = CAMERA.view_matrix()
    depth = -(pos @ v[2, :3] + v[2, 3])
    mesh_id = rng.integers(-1, len(MATERIALS), shape).astype(np.int32)
    gb = _GB(
        {
            "normal": n.astype(np.float32),
            "position": pos.astype(np.float32),
            "depth": depth.astype(np.float32),
            "mesh_id": mesh_id,
        }
    )
    scene = SimpleNamespace(
        objects=[SimpleNamespace(material=m, name=f"o{i}") for i, m in enumerate(MATERIALS)],
        lights=(LIGHTS[light],),
        ambient=(0.0, 0.0, 0.0),
        camera=CAMERA,
        bounds=lambda: (np.full(3, -1.5), np.full(3, 1.5)),
        world_meshes=lambda: [],
    )
    return ShadeContext(gb, scene)


FUSED = [
    dict(detail="depth"),
    dict(detail="depth", distance="eye", z_min=2.0, r=3.0, tone="half_lambert"),
    dict(detail="focus", focus_point=(0.0, 0.0, 0.0)),
    dict(detail="focus", focus_point=(0.2, 0.1, 0.5), distance="axis", z_min=0.5, r=2.5),
    dict(detail="orientation", texture="silhouette_fade"),
    dict(detail="orientation", r=2.7, modulate=True),
    dict(detail="highlight", texture="plastic", s=16.0),
    dict(detail="highlight", texture="metal", s=7.5, one_sided=True, tone="half_lambert"),
    dict(detail="none", texture="aerial_blue", modulate=True),
    dict(detail="depth", show="detail"),
    dict(detail="focus", focus_point=(0.0, 0.0, 0.0), show="inverse_detail"),
    dict(detail="highlight", show="tone"),
    dict(detail="depth", texture=np.random.default_rng(9).random((3, 1, 2))),  # 1 column
    dict(detail="orientation", texture=np.random.default_rng(8).random((1, 5, 4))),  # 1 row
]


@pytest.mark.parametrize("light", sorted(LIGHTS))
@pytest.mark.parametrize("params", FUSED, ids=lambda p: "-".join(f"{v}" for v in p.values())[:60])
def test_fused_kernel_equals_numpy_oracle(params, light):
    style = XToonStyle(**params)
    assert fused(style._cfg)
    for seed in (0, 1):
        ctx = random_ctx(seed, light)
        assert_same(style.shade(ctx), oracle(style, ctx))


@settings(max_examples=25, deadline=None)
@given(
    seed=st.integers(0, 2**31),
    detail=st.sampled_from(["depth", "orientation", "highlight"]),
    rows=st.integers(1, 9),
    cols=st.integers(1, 9),
    half=st.booleans(),
)
def test_random_textures_and_buffers(seed, detail, rows, cols, half):
    tex = np.random.default_rng(seed).random((rows, cols, 4))
    style = XToonStyle(texture=tex, detail=detail, tone="half_lambert" if half else "clamped")
    ctx = random_ctx(seed % 1000, "point", shape=(13, 17))
    assert_same(style.shade(ctx), oracle(style, ctx))


def test_same_result_for_one_and_two_threads():
    ctx = random_ctx(3, "point", shape=(97, 131))
    styles = [XToonStyle(detail="highlight", texture="plastic"), XToonStyle(detail="depth")]
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


def test_nan_depth_is_refused():
    """As the numpy code (``detail_depth`` refuses NaN distances); a NaN normal, like a zero
    one, gives tone 0 in both (``unit_rows``)."""
    ctx = random_ctx(4, "directional", shape=(6, 7))
    ctx.gb["mesh_id"][2, 3] = 0
    ctx.gb["depth"][2, 3] = np.nan
    style = XToonStyle(detail="depth")
    with pytest.raises(ValueError, match="NaN at a covered sample of row 2"):
        style.shade(ctx)
    with pytest.raises(ValueError, match="NaN"):
        oracle(style, ctx)
    ctx = random_ctx(4, "directional", shape=(6, 7))
    ctx.gb["mesh_id"][2, 3] = 0
    ctx.gb["normal"][2, 3] = np.nan
    assert_same(style.shade(ctx), oracle(style, ctx))


def test_inconsistent_gbuffer_is_refused():
    ctx = random_ctx(5, "directional", shape=(6, 7))
    ctx.gb["depth"] = ctx.gb["depth"][:, :5]
    with pytest.raises(ValueError, match=r"channel 'depth': expected shape \(6, 7\)"):
        XToonStyle(detail="depth").shade(ctx)
    ctx = random_ctx(5, "directional", shape=(6, 7))
    ctx.gb["mesh_id"][0, 0] = len(MATERIALS)
    with pytest.raises(ValueError, match="'mesh_id': got object index 3 but the scene has 3"):
        XToonStyle(detail="depth").shade(ctx)


# ------------------------------------------------------------------ rendered scenes, every path


def two_spheres(light: Light) -> Scene:
    cam = Camera.look_at((0.5, 0.8, 5.0), (0.0, 0.0, 0.0), (0.0, 1.0, 0.0), 40.0, 0.5, 20.0)
    objs = (
        SceneObject(uv_sphere(1.0, 32, 16), transform_matrix(translate=(-0.8, 0, 0)), name="a"),
        SceneObject(
            uv_sphere(0.7, 24, 12),
            transform_matrix(translate=(1.0, 0.2, -1.0)),
            Material(diffuse=(0.2, 0.5, 0.9)),
            name="b",
        ),
    )
    return Scene(objs, cam, lights=(light,), name="two")


PREV = {"eye": [0.7, 0.8, 5.0], "target": [0.1, 0.0, 0.0]}
GENERAL = [
    dict(detail="depth"),
    dict(detail="highlight", texture="plastic", modulate=True),
    dict(detail="focus", focus_point=(0.0, 0.0, 0.0), show="detail"),
    dict(detail="depth", detail_mode="vertex"),
    dict(detail="orientation", detail_mode="vertex", show="inverse_detail"),
    dict(detail="flow", prev_camera=PREV, flow_max=8.0),
    dict(detail="flow", prev_camera=PREV, flow_max=8.0, detail_mode="vertex", show="tone"),
    dict(detail="map", detail_map=np.linspace(0, 1, 48 * 64).reshape(48, 64)),
    dict(detail="depth", shape="sphere", shape_weight=0.5),
    dict(detail="orientation", shape="ellipsoid", shape_weight=1.0, shape_blend="pixel"),
    dict(detail="depth", shape="sphere", shape_weight="detail", modulate=True),
]


@pytest.mark.parametrize("light", ["directional", "point"])
@pytest.mark.parametrize("params", GENERAL, ids=lambda p: "-".join(f"{v}" for v in p.values())[:60])
def test_every_path_equals_numpy_oracle_on_renders(params, light):
    lt = (
        Light(direction=(-0.5, 0.8, 0.6))
        if light == "directional"
        else Light(kind="point", position=(-2.0, 3.0, 3.0))
    )
    scene = two_spheres(lt)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        style = XToonStyle(**params)
    for spp in (1, 4):
        gb = rasterize(scene, scene.camera, 64, 48, style.requires(scene), spp)
        if params.get("detail") == "map" and spp == 4:
            continue  # the map is per pixel: same path as spp 1
        ctx = ShadeContext(gb, scene)
        assert_same(style.shade(ctx), oracle(style, ctx))


def test_texture_lookup_corners_are_exact():
    """Independent of the numpy code: tone 0 / D 0 reads the first texel, tone 1 / D 1 the last
    (texel-centre convention of X-Toon's OpenGL lookup)."""
    tex = np.random.default_rng(2).random((4, 6, 4)).astype(np.float32)
    ctx = random_ctx(6, "directional", shape=(4, 4))
    ctx.gb["mesh_id"][:] = 0
    ctx.gb["normal"][:] = 0.0  # tone 0
    style = XToonStyle(texture=tex, detail="none")  # D = 1: last row
    rgba = style.shade(ctx)
    assert np.array_equal(rgba[0, 0], tex[-1, 0])
    ctx.gb["normal"][:] = LIGHTS["directional"].direction  # tone 1
    rgba = style.shade(ctx)
    assert np.array_equal(rgba[0, 0], tex[-1, -1])
    assert fx.toon_lookup(tex, 1.0, 1.0).tolist() == rgba[0, 0].tolist()
