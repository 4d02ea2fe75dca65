"""The numba path of the ``halftone`` style against independent oracles: its numpy path
(``HalftoneStyle.shade_numpy``), the formulas of ``refnpr.formulas.halftone``, the texture
samplers, ``np.interp`` and ``unit_vectors``; thread-count invariance; validation."""

from __future__ import annotations

import functools
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from refnpr.formulas import halftone
from refnpr.formulas._shading_checks import unit_vectors
from refnpr.golden import load_suite
from refnpr.raster import rasterize
from refnpr.scenes import load_scene
from refnpr.styles import ShadeContext, get_style, style_from_spec
from refnpr.styles.halftone import _kernels as K
from refnpr.styles.halftone import fused
from refnpr.styles.halftone import screens as HS
from refnpr.texture import build_pyramid, sample_level, sample_trilinear

from ._threads import outputs_per_thread_count

ROOT = Path(__file__).resolve().parents[2]
SUITE = ROOT / "golden" / "suite.toml"


def _base(style):
    return getattr(style, "base", style)


@functools.cache
def _gbuffer(scene_name: str, width: int, height: int, spp: int, channels: tuple[str, ...]):
    scene = load_scene(scene_name)
    return scene, rasterize(scene, scene.camera, width, height, list(channels), spp)


def _both(style, scene_name: str, width: int = 64, height: int = 48, spp: int = 1):
    scene = load_scene(scene_name)
    channels = tuple(sorted(style.requires(scene)))
    scene, gb = _gbuffer(scene_name, width, height, spp, channels)
    ctx = ShadeContext(gb, scene)
    return style.shade(ctx), style.shade_numpy(ctx)


def _assert_same(fast: np.ndarray, ref: np.ndarray) -> None:
    """Equal float32 RGBA, but for rare samples on a threshold tie (the kernel's log2 and pow
    are libm's, numpy's may be its SIMD ones, an ulp apart)."""
    assert fast.shape == ref.shape and fast.dtype == ref.dtype == np.float32
    d = np.abs(fast.astype(np.float64) - ref)
    far = np.count_nonzero(d > 1e-6)
    assert far <= max(1, d.size // 20000), (far, d.max())
    near = d[d <= 1e-6]
    assert near.size == 0 or near.max() <= 1e-6


# -- every golden case of the style, at a small size ------------------------------------------
GOLDEN = [c for c in load_suite(SUITE) if c.name.startswith("halftone-")]


@pytest.mark.parametrize("case", GOLDEN, ids=[c.name for c in GOLDEN])
def test_golden_cases_take_the_kernel_path_and_match_numpy(case):
    scene = load_scene(case.scene)
    style = _base(style_from_spec(case.style if case.style is not None else scene.style))
    assert style.uses_kernels()
    fast, ref = _both(style, case.scene, 72, 54, 1)
    _assert_same(fast, ref)
    assert np.count_nonzero(fast[..., 3]) > 0  # the object is in view


@pytest.mark.parametrize("spp", [4, 9])
def test_supersampled_room_matches_numpy(spp):
    style = get_style(
        "halftone",
        screen="hatching",
        anisotropy=8,
        sample_lod=True,
        objects={"back_wall": {"screen": "bricks", "uv_scale": [8.0, 8.0]}},
    )
    _assert_same(*_both(style, "halftone_room", 40, 30, spp))


@pytest.mark.parametrize("spp", [1, 4])
def test_mixed_lights_with_specular_match_numpy(spp):
    """Directional lights take the row pass (unit N, V, H and N.H per row span), point lights
    the per-sample path: both, with specular, in one multi-object scene."""
    import dataclasses

    from refnpr.scenes import Light

    scene = load_scene("halftone_room")
    lights = (
        Light("directional", direction=(0.3, 1.0, 0.6), color=(0.7, 0.6, 0.5)),
        Light("point", position=(0.5, 1.5, 2.0), color=(0.4, 0.4, 0.5)),
        Light("directional", direction=(-1.0, 0.2, 0.4), color=(0.2, 0.3, 0.2)),
    )
    objects = tuple(
        dataclasses.replace(
            o, material=dataclasses.replace(o.material, specular=(0.6, 0.5, 0.4), shininess=12.0)
        )
        for o in scene.objects
    )  # the room's materials have no specular term
    scene = dataclasses.replace(scene, lights=lights, objects=objects)
    style = get_style("halftone", specular=True, screen="hatching")
    gb = rasterize(scene, scene.camera, 48, 36, sorted(style.requires(scene)), spp)
    ctx = ShadeContext(gb, scene)
    fast = style.shade(ctx)
    assert style.uses_kernels()
    _assert_same(fast, style.shade_numpy(ctx))
    assert np.count_nonzero(fast[..., 3]) > 0


# -- random option combinations ---------------------------------------------------------------
OPTIONS = st.fixed_dictionaries(
    {
        "threshold": st.sampled_from(["smooth", "binary"]),
        "screen": st.sampled_from(
            [
                "hatching",
                "bricks",
                "engraving",
                "brick",
                {"kind": "engraving", "profile": "ramp", "angle": 33.0},
                {"kind": "strokes", "set": "bricks", "lighting": False},
            ]
        ),
        "mip": st.sampled_from(["trilinear", "per_level"]),
        "tone_correct": st.booleans(),
        "anisotropy": st.sampled_from([1, 2, 5, 16]),
        "lod_bias": st.floats(-2.0, 2.0),
        "specular": st.booleans(),
        "show": st.sampled_from(["color", "color", "screen", "normals", "intensity"]),
        "uv_scale": st.sampled_from([None, [3.0, 2.0], [0.7, 5.5]]),
        "indication": st.sampled_from([None, [[0.3, -0.2], [-0.5, 0.1]]]),
        "ink": st.sampled_from([(0.0, 0.0, 0.0), (0.2, 0.1, 0.4)]),
    }
)


@settings(max_examples=25, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(
    opts=OPTIONS,
    c=st.floats(0.5, 40.0),
    centred=st.booleans(),
    scene=st.sampled_from(["halftone_sphere", "halftone_room", "halftone_torus_knot"]),
)
def test_random_options_match_the_numpy_path(opts, c, centred, scene):
    if opts["threshold"] == "smooth":
        opts = {**opts, "c": c, "centred": centred}
    style = get_style("halftone", **opts)
    _assert_same(*_both(style, scene, 40, 30, 1))


def test_c_auto_keeps_the_numpy_path():
    style = get_style("halftone", c="auto")
    assert not style.uses_kernels()
    scene = load_scene("halftone_sphere")
    gb = rasterize(scene, scene.camera, 24, 24, sorted(style.requires(scene)))
    out = style.shade(ShadeContext(gb, scene))
    np.testing.assert_array_equal(out, style.shade_numpy(ShadeContext(gb, scene)))


# -- kernel helpers against the formulas ------------------------------------------------------
finite = st.floats(-1.5, 2.5, allow_nan=False)


@given(
    s=st.lists(st.floats(0.0, 1.0), min_size=1, max_size=30),
    x=finite,
    c=st.floats(0.01, 100.0),
    centred=st.booleans(),
)
def test_threshold_helper_is_the_papers_mux_and_ramp(s, x, c, centred):
    scr = np.array(s)
    got_b = np.array([K._threshold(v, x, K.THRESHOLD_BINARY, c, 1.0) for v in scr])
    np.testing.assert_array_equal(got_b, halftone.binary_threshold(scr, x))  # sec. 3.1
    top = 0.5 if centred else 1.0
    got_s = np.array([K._threshold(v, x, K.THRESHOLD_SMOOTH, c, top) for v in scr])
    np.testing.assert_array_equal(got_s, halftone.smooth_threshold(scr, x, c, centred=centred))


@given(v=st.lists(st.floats(-1e3, 1e3), min_size=3, max_size=3))
def test_unit_helper_is_unit_vectors(v):
    np.testing.assert_array_equal(np.array(K._unit(*v)), unit_vectors(np.array(v)))


@given(
    values=st.lists(st.floats(-0.2, 1.2), min_size=1, max_size=40),
    seed=st.integers(0, 2**16),
    bins=st.sampled_from([2, 3, 17, 2048]),
)
def test_interp_helper_is_np_interp(values, seed, bins):
    xp = np.linspace(0.0, 1.0, bins)
    fp = np.sort(np.random.default_rng(seed).random(bins))
    got = np.array([K._interp(v, xp, fp) for v in values])
    np.testing.assert_array_equal(got, np.interp(np.array(values), xp, fp))


def test_interp_helper_at_every_knot():
    xp = np.linspace(0.0, 1.0, 2048)
    fp = np.sort(np.random.default_rng(3).random(2048))
    got = np.array([K._interp(v, xp, fp) for v in xp])
    np.testing.assert_array_equal(got, np.interp(xp, xp, fp))


def test_samplers_equal_the_texture_kernels():
    rng = np.random.default_rng(7)
    pyr = build_pyramid(rng.random((37, 64, 3)).astype(np.float32))
    texels, offsets, shapes = pyr.packed()
    uv = rng.uniform(-3, 3, (500, 2))
    # edges of the GL_REPEAT wrap (_taps' compare-and-subtract path and its modulo fallback):
    # texel centres and borders, a period, just below 1, -0.0, huge coordinates
    edge = [0.0, -0.0, 0.5 / 64, 1.0 / 64, 1.0, 1.0 - 2**-53, -1.0 + 2**-53, 2.0**60, -1e300]
    uv[: len(edge) ** 2] = np.array([(a, b) for a in edge for b in edge])
    lod = rng.uniform(-1, 8, 500)
    level = rng.integers(-1, 9, 500)
    tri = sample_trilinear(pyr, uv, lod, dtype=np.float64)
    lev = sample_level(pyr, uv, level, dtype=np.float64)
    for p in range(500):
        for ch in range(3):
            t = K._trilinear(texels, offsets, shapes, uv[p, 0], uv[p, 1], lod[p], ch)
            assert t == tri[p, ch]
        got = K._level(texels, offsets, shapes, level[p], uv[p, 0], uv[p, 1], 0)
        assert got == lev[p, 0]


def test_anisotropic_probes_equal_sample_screen():
    rng = np.random.default_rng(11)
    pyr = build_pyramid(rng.random((64, 64)).astype(np.float32))
    texels, offsets, shapes = pyr.packed()
    n = 300
    coords = rng.uniform(0, 4, (n, 2))
    dx = rng.normal(0, 0.05, (n, 2))
    dy = rng.normal(0, 0.005, (n, 2))
    lod, fp = HS.screen_footprint(pyr, dx, dy, 8)
    ref = HS.sample_screen(pyr, coords, lod, fp)
    for p in range(n):
        got = K._filtered(
            texels, offsets, shapes, coords[p, 0], coords[p, 1], lod[p], fp.probes[p],
            fp.axis[p, 0], fp.axis[p, 1], 0,
        )  # fmt: skip
        assert got == ref[p]


# -- thread count, validation, the screen cache -----------------------------------------------
_THREADS_SCRIPT = """
import hashlib, numpy as np
from refnpr.raster import rasterize
from refnpr.scenes import load_scene
from refnpr.styles import ShadeContext, get_style
scene = load_scene("halftone_room")
style = get_style("halftone", anisotropy=16, mip="per_level", tone_correct=True,
                  objects={"back_wall": {"screen": "bricks", "indication": [[0.2, -0.3]]}})
gb = rasterize(scene, scene.camera, 96, 72, sorted(style.requires(scene)), 4)
print('"' + hashlib.sha256(style.shade(ShadeContext(gb, scene)).tobytes()).hexdigest() + '"')
"""


def test_output_is_the_same_for_any_thread_count():
    one, two = outputs_per_thread_count(_THREADS_SCRIPT)
    assert one == two and len(one) == 64


def _call(**overrides):
    scene, gb = _gbuffer(
        "halftone_sphere", 16, 16, 1, ("duv_dx", "duv_dy", "mesh_id", "normal", "uv")
    )
    screen = HS.cached_screen(HS.normalize_spec("hatching"), None)
    shape = gb["mesh_id"].shape
    args = dict(
        obj=0,
        mesh_id=gb["mesh_id"],
        mask=gb["mesh_id"] >= 0,
        channels={k: gb[k] for k in ("normal", "uv", "duv_dx", "duv_dy")},
        scale=(1.0, 1.0),
        screen=screen,
        luts=None,
        per_level=False,
        indication=None,
        indication_scale=(1.0, 1.0),
        ambient=(0.1, 0.1, 0.1),
        diffuse=(0.9, 0.9, 0.9),
        specular_color=(0.0, 0.0, 0.0),
        shininess=0.0,
        specular=False,
        lights=[(K.LIGHT_DIRECTIONAL, np.array([0.0, 0.0, 1.0]), np.ones(3))],
        eye=(0.0, 0.0, 5.0),
        anisotropy=1,
        lod_offset=0.0,
        threshold="smooth",
        c=4.0,
        centred=False,
        show="color",
        ink=(0.0, 0.0, 0.0),
        paper=(1.0, 1.0, 1.0),
    )
    out = overrides.pop("out", np.zeros(shape + (4,), np.float32))
    args.update(overrides)
    fused.shade_object_into(out, None, **args)
    return out


@pytest.mark.parametrize(
    ("overrides", "match"),
    [
        ({"threshold": "soft"}, "threshold"),
        ({"show": "edges"}, "show"),
        ({"c": 0.0}, "c:"),
        ({"anisotropy": 17}, "anisotropy"),
        ({"out": np.zeros((16, 16, 4), np.float64)}, "out:"),
        ({"out": np.zeros((8, 16, 4), np.float32)}, "out:"),
        ({"scale": (1.0, np.nan)}, "scale"),
        ({"show": "screen"}, "raw"),
    ],
)
def test_bad_kernel_inputs_are_named(overrides, match):
    with pytest.raises(ValueError, match=match):
        _call(**overrides)


def test_valid_call_writes_the_covered_samples():
    out = _call()
    _, gb = _gbuffer("halftone_sphere", 16, 16, 1, ("duv_dx", "duv_dy", "mesh_id", "normal", "uv"))
    np.testing.assert_array_equal(out[..., 3], (gb["mesh_id"] >= 0).astype(np.float32))


def test_prepare_fills_empty_samples_and_finds_the_objects_in_view():
    mesh_id = np.array([[-1, -1, 0], [2, 2, -1]], dtype=np.int32)
    mask = np.array([[True, False, True], [True, True, False]])
    out = np.full((2, 3, 4), 7.0, np.float32)
    present = fused.prepare_into(out, mesh_id, mask, (0.25, 0.5, 1.0), 4)
    np.testing.assert_array_equal(present, [True, False, True, False])
    np.testing.assert_array_equal(out[0, 0], [0.25, 0.5, 1.0, 1.0])  # covered, no object
    np.testing.assert_array_equal(out[0, 1], 0.0)  # empty
    np.testing.assert_array_equal(out[1, 2], 0.0)
    np.testing.assert_array_equal(out[0, 2], 7.0)  # an object's samples: left to its kernel
    np.testing.assert_array_equal(out[1, :2], 7.0)


def test_prepare_rejects_a_wrong_buffer():
    with pytest.raises(ValueError, match="out:"):
        fused.prepare_into(
            np.zeros((2, 2, 4)), np.zeros((2, 2), np.int32), np.ones((2, 2), bool), (1, 1, 1), 1
        )


def test_built_in_screens_are_shared_and_file_screens_rebuilt(tmp_path):
    spec = HS.normalize_spec("hatching")
    assert HS.cached_screen(spec, None) is HS.cached_screen(dict(spec), None)
    img = (np.random.default_rng(0).random((16, 16)) * 255).astype(np.uint8)
    path = tmp_path / "noise.png"
    import imageio.v3 as iio

    iio.imwrite(path, img)
    file_spec = HS.normalize_spec(str(path))
    a = HS.cached_screen(file_spec, None)
    assert HS.cached_screen(file_spec, None) is not a
