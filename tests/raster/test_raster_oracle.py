"""rasterize() against the independent float64 ray-cast oracle: ids, values and derivatives."""

from __future__ import annotations

import numpy as np
import pytest

from refnpr.raster import rasterize

from .meshes import concat
from .oracle import View, cast, derivatives, pixel_centres, surface
from .scenes import BUILTIN_CHANNELS, HEAT_CHANNELS, SCENES

TEXTURE_SIZE = (256, 64)
LINE_PERIOD = 3.0
ALL_CHANNELS = tuple(c for c in BUILTIN_CHANNELS if c != "coverage_count") + HEAT_CHANNELS
#: Relative tolerance of values at sample centres (float64 buffers).
RTOL64 = 1e-6
#: float32 buffers: the float64 result rounded once (half an ulp) plus the float64 error.
RTOL32 = 2.0**-23


def _oracle(scene, n: int = 1):
    """Oracle hits at every sample centre, plus values and per-pixel derivatives where covered."""
    view = View.of(scene.camera, scene.width, scene.height)
    pos, faces, data = concat(scene.meshes)
    px, py = pixel_centres(scene.width, scene.height, n)
    hits = cast(view, pos, faces, px, py)
    assert not hits.inconsistent.any(), "the oracle's two inside tests disagree"
    covered = hits.tri >= 0
    tri, qx, qy = hits.tri[covered], px.ravel()[covered], py.ravel()[covered]
    values = surface(view, pos, faces, tri, qx, qy, data)
    ders = derivatives(view, pos, faces, tri, qx, qy, {**data, "position": pos})
    return hits, covered, values, ders


def _err_report(err, bound, name):
    worst = int(np.argmax(err / bound))
    return f"{name}: {int(np.sum(err > bound))} samples out of tolerance; worst err {err[worst]:.3g} > {bound[worst]:.3g}"


def _check(name, got, expect, rtol, floor):
    """|got - expect| <= rtol * max(|expect|, floor), vectors by their Euclidean norm."""
    expect = np.asarray(expect, dtype=np.float64)
    expect = expect.reshape(expect.shape[0], -1)
    got = np.asarray(got, dtype=np.float64).reshape(expect.shape)
    err = np.linalg.norm(got - expect, axis=-1)
    bound = rtol * np.maximum(np.linalg.norm(expect, axis=-1), floor) + np.zeros(len(err))
    assert np.all(err <= bound), _err_report(err, bound, name)
    return float(np.max(err / np.maximum(np.linalg.norm(expect, axis=-1), floor)))


def _check_abs(name, got, expect, atol):
    """|got - expect| <= atol elementwise (scalar channels)."""
    err = np.abs(np.asarray(got, dtype=np.float64).ravel() - expect)
    bound = atol + np.zeros(len(err))
    assert np.all(err <= bound), _err_report(err, bound, name)


def _lod(dx, dy, size):
    tw, th = size
    rho = np.maximum(np.hypot(dx[:, 0] * tw, dx[:, 1] * th), np.hypot(dy[:, 0] * tw, dy[:, 1] * th))
    return np.log2(rho)  # OpenGL 4.x sec. 8.14


def _dyadic(dx, dy, k, period):
    return np.log2(1.0 / np.hypot(dx[:, k], dy[:, k]) / period)  # Veryovka eq. 5


@pytest.fixture(scope="module", params=sorted(SCENES))
def scene_and_oracle(request):
    scene = SCENES[request.param]()
    return scene, _oracle(scene)


@pytest.mark.parametrize("dtype", [np.float64, np.float32])
def test_channels_match_the_oracle_at_pixel_centres(scene_and_oracle, dtype):
    scene, (hits, covered, ref, ders) = scene_and_oracle
    gb = rasterize(
        scene.meshes,
        scene.camera,
        scene.width,
        scene.height,
        ALL_CHANNELS,
        texture_size=TEXTURE_SIZE,
        line_period=LINE_PERIOD,
        dtype=dtype,
    )
    # --- visibility: exact agreement away from edges, ids in range everywhere
    tri_id = gb["tri_id"].ravel()
    n_tris = sum(m.n_faces for m in scene.meshes)
    assert gb["tri_id"].dtype == np.int32 and tri_id.min() >= -1 and tri_id.max() < n_tris
    clear = hits.clear
    assert clear.mean() > 0.8, "the oracle excludes too much of the image to be a useful test"
    assert 0.2 < covered.mean(), "scene should cover a good part of the image"
    bad = np.flatnonzero(clear & (tri_id != hits.tri))
    assert bad.size == 0, (
        f"tri_id differs from the oracle at {bad.size} samples away from edges, e.g. sample "
        f"{np.unravel_index(bad[0], gb['tri_id'].shape)}: expected {hits.tri[bad[0]]}, got {tri_id[bad[0]]}"
    )
    first = np.cumsum([0] + [m.n_faces for m in scene.meshes])
    mesh_expect = np.where(hits.tri >= 0, np.searchsorted(first, hits.tri, side="right") - 1, -1)
    np.testing.assert_array_equal(gb["mesh_id"].ravel()[clear], mesh_expect[clear])
    cov = gb["coverage"].ravel()
    np.testing.assert_array_equal(cov[clear], (hits.tri[clear] >= 0).astype(cov.dtype))
    assert np.all(np.isinf(gb["depth"].ravel()[tri_id < 0]))

    # --- values where the ids agree and the pixel is covered
    for key in ALL_CHANNELS:
        if key not in ("tri_id", "mesh_id"):
            assert gb[key].dtype == dtype, key
    sel = (clear & (tri_id >= 0))[covered]  # index into the oracle's covered arrays
    pick = np.flatnonzero(covered)[sel]
    flat = {k: gb[k].reshape(tri_id.size, -1) for k in gb if k not in ("tri_id", "mesh_id")}
    r = RTOL64 if dtype == np.float64 else RTOL32
    depth = ref["depth"][sel]
    # value channels: rtol relative to the value's magnitude (with a natural floor for each)
    _check("depth", flat["depth"][pick], depth, r, 0.0)
    _check("ndc_z", flat["ndc_z"][pick], ref["ndc_z"][sel], r, 1.0)
    _check("position", flat["position"][pick], ref["position"][sel], r, depth)
    _check("bary", flat["bary"][pick], ref["bary"][sel], r, 1.0)
    _check("normal", flat["normal"][pick], ref["normal"][sel], r, 1.0)
    _check("uv", flat["uv"][pick], ref["uv"][sel], r, 1.0)
    _check("heat", flat["heat"][pick], ref["heat"][sel], r, 1.0)
    # derivatives: relative to the size of the attribute's whole screen Jacobian at the pixel
    # (the oracle's central differences are good to ~1e-9 of it)
    for base in ("uv", "position", "heat"):
        dx, dy = (a[sel] for a in ders[base])
        jac = np.linalg.norm(np.concatenate([dx, dy], -1), axis=-1)
        _check(f"d{base}_dx", flat[f"d{base}_dx"][pick], dx, 2 * r, jac)
        _check(f"d{base}_dy", flat[f"d{base}_dy"][pick], dy, 2 * r, jac)
    dx, dy = (a[sel] for a in ders["uv"])
    # log2 of the derivatives: 1e-6 relative in rho is 1.4e-6 in lod; float32 channels hold
    # log2 of float32-rounded derivatives (2e-7), then rounded themselves (half an ulp)
    lod, s = _lod(dx, dy, TEXTURE_SIZE), _dyadic(dx, dy, 1, LINE_PERIOD)
    slack = 1.5 * RTOL64 if dtype == np.float64 else 2e-7
    _check_abs("lod", flat["lod"][pick], lod, slack + r * np.abs(lod))
    _check_abs("dyadic_scale", flat["dyadic_scale"][pick], s, slack + r * np.abs(s))


def test_dyadic_scale_of_u_and_lod_of_square_textures(scene_and_oracle):
    """dyadic_coord='u' measures the iso-lines of u; an int texture_size means a square texture."""
    scene, (hits, covered, ref, ders) = scene_and_oracle
    gb = rasterize(
        scene.meshes,
        scene.camera,
        scene.width,
        scene.height,
        ("tri_id", "dyadic_scale", "lod"),
        texture_size=512,
        dyadic_coord="u",
        line_period=0.5,
        dtype=np.float64,
    )
    tri_id = gb["tri_id"].ravel()
    sel = (hits.clear & (tri_id >= 0))[covered]
    pick = np.flatnonzero(covered)[sel]
    dx, dy = (a[sel] for a in ders["uv"])
    np.testing.assert_allclose(gb["dyadic_scale"].ravel()[pick], _dyadic(dx, dy, 0, 0.5), atol=1e-7)
    np.testing.assert_allclose(gb["lod"].ravel()[pick], _lod(dx, dy, (512, 512)), atol=1e-7)


@pytest.mark.parametrize("n", [2, 3])
def test_supersampled_samples_match_the_oracle(n):
    """spp = n^2: every sample against the oracle at its own position; derivatives stay per
    pixel; coverage is the mean of the sample grid."""
    scene = SCENES["mixed"]()
    hits, covered, ref, ders = _oracle(scene, n)
    gb = rasterize(
        scene.meshes,
        scene.camera,
        scene.width,
        scene.height,
        ("tri_id", "uv", "duv_dx", "duv_dy", "depth", "coverage"),
        spp=n * n,
        dtype=np.float64,
    )
    tri_id = gb["tri_id"]
    assert tri_id.shape == (n * scene.height, n * scene.width)
    assert gb["coverage"].shape == (scene.height, scene.width)
    flat_id = tri_id.ravel()
    clear = hits.clear
    assert clear.mean() > 0.8
    np.testing.assert_array_equal(flat_id[clear], hits.tri[clear])
    # coverage is the oracle's covered fraction wherever all of a pixel's samples are clear
    frac = (hits.tri >= 0).reshape(scene.height, n, scene.width, n).mean(axis=(1, 3))
    all_clear = clear.reshape(scene.height, n, scene.width, n).all(axis=(1, 3))
    assert np.any((frac > 0) & (frac < 1) & all_clear)
    np.testing.assert_allclose(gb["coverage"][all_clear], frac[all_clear], rtol=0, atol=1e-15)
    sel = (clear & (flat_id >= 0))[covered]
    pick = np.flatnonzero(covered)[sel]
    _check("uv", gb["uv"].reshape(-1, 2)[pick], ref["uv"][sel], RTOL64, 1.0)
    _check("depth", gb["depth"].ravel()[pick], ref["depth"][sel], RTOL64, 0.0)
    dx, dy = (a[sel] for a in ders["uv"])
    jac = np.linalg.norm(np.concatenate([dx, dy], -1), axis=-1)
    _check("duv_dx", gb["duv_dx"].reshape(-1, 2)[pick], dx, 2e-6, jac)
    _check("duv_dy", gb["duv_dy"].reshape(-1, 2)[pick], dy, 2e-6, jac)


def test_spp9_centre_samples_equal_spp1_pixels():
    """With spp = 9 the middle sample of each pixel sits on the pixel centre: its values and its
    (per pixel) derivatives equal the spp = 1 buffers there."""
    scene = SCENES["close_sphere"]()
    chans = ("tri_id", "uv", "duv_dx", "duv_dy", "depth", "normal")
    one = rasterize(scene.meshes, scene.camera, scene.width, scene.height, chans, dtype=np.float64)
    nine = rasterize(
        scene.meshes, scene.camera, scene.width, scene.height, chans, spp=9, dtype=np.float64
    )
    view = View.of(scene.camera, scene.width, scene.height)
    pos, faces, _ = concat(scene.meshes)
    px, py = pixel_centres(scene.width, scene.height)
    clear = cast(view, pos, faces, px, py).clear.reshape(scene.height, scene.width)
    mid = {k: v[1::3, 1::3] for k, v in nine.channels.items()}
    assert clear.mean() > 0.8
    np.testing.assert_array_equal(mid["tri_id"][clear], one["tri_id"][clear])
    ok = clear & (one["tri_id"] >= 0)
    for k in ("uv", "duv_dx", "duv_dy", "depth", "normal"):
        scale = np.abs(one[k][ok]).max()
        np.testing.assert_allclose(mid[k][ok], one[k][ok], rtol=1e-9, atol=1e-9 * scale, err_msg=k)
