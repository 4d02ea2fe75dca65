"""The ``halftone`` kernel against an independent per-sample oracle (float64 numpy by the book:
GL_REPEAT trilinear and anisotropic lookups, Veryovka eq. 1 with Blinn-Phong, the tangent frame
solved from the derivatives, DOT3 stroke lighting, indication maps, tone LUTs, the thresholds of
sec. 3 and the fwidth slope), over random option sets and scenes; the hot screen lookup against
``device.sampling.probes``; thread-count invariance; input errors; the screen cache."""

from __future__ import annotations

import dataclasses
import functools
import math
from typing import NamedTuple

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from refnpr.device.sampling import probes
from refnpr.image import linear_to_srgb
from refnpr.raster import rasterize
from refnpr.scenes import Light, load_scene
from refnpr.styles import ShadeContext, get_style
from refnpr.styles.halftone import _kernels as K
from refnpr.styles.halftone import screens as HS
from refnpr.texture import build_pyramid

from ._threads import outputs_per_thread_count

LUMA = (0.2126, 0.7152, 0.0722)


# -- the oracle ---------------------------------------------------------------------------------
def _bilinear(level: np.ndarray, u: float, v: float) -> np.ndarray:
    rows, cols = level.shape[:2]
    x = (u - math.floor(u)) * cols - 0.5
    y = (v - math.floor(v)) * rows - 0.5
    i0, j0 = math.floor(x), math.floor(y)
    fx, fy = x - i0, y - j0
    total = 0.0
    for dj, wy in ((0, 1 - fy), (1, fy)):
        for di, wx in ((0, 1 - fx), (1, fx)):
            total = total + wx * wy * level[(j0 + dj) % rows, (i0 + di) % cols].astype(float)
    return total


def _levels(lod: float, n_levels: int) -> tuple[int, int, float]:
    lam = min(max(lod, 0.0), n_levels - 1.0)
    k0 = math.floor(lam)
    return k0, min(k0 + 1, n_levels - 1), lam - k0


def _footprint(dx, dy, rows: int, cols: int, aniso: int):
    px = math.sqrt((dx[0] * cols) ** 2 + (dx[1] * rows) ** 2)
    py = math.sqrt((dy[0] * cols) ** 2 + (dy[1] * rows) ** 2)
    p_max, p_min = max(px, py), min(px, py)
    if aniso == 1:
        return math.log2(max(p_max, 2.0**-64)), [np.zeros(2)]
    n = max(1, min(math.ceil(p_max / max(p_min, 2.0**-64) - 1e-9), aniso))
    axis = np.asarray(dx if px >= py else dy, float)
    return math.log2(max(p_max / n, 2.0**-64)), [axis * ((j + 0.5) / n - 0.5) for j in range(n)]


def _filtered(levels, uv, lod, offsets, k=None):
    """The mean over the probe offsets of the trilinear sample (or of level k's bilinear)."""
    acc = 0.0
    for off in offsets:
        u, v = uv + off
        if k is None:
            k0, k1, w = _levels(lod, len(levels))
            acc = acc + (1 - w) * _bilinear(levels[k0], u, v) + w * _bilinear(levels[k1], u, v)
        else:
            acc = acc + _bilinear(levels[k], u, v)
    return acc / len(offsets)


def _unit(a) -> np.ndarray:
    a = np.asarray(a, float)
    n = np.linalg.norm(a)
    return a / n if n > 0 else a * 0.0


def _tangent_frame(n, dpdx, dpdy, dudx, dudy):
    """(T, B) along +u, +v: dP/du, dP/dv from [dP/dx dP/dy] = [dP/du dP/dv] J, Gram-Schmidt."""
    jac = np.array([[dudx[0], dudy[0]], [dudx[1], dudy[1]]])
    if abs(np.linalg.det(jac)) <= 1e-20:
        return None
    pu, pv = (np.stack([dpdx, dpdy], axis=1) @ np.linalg.inv(jac)).T
    t = pu - (pu @ n) * n
    if np.linalg.norm(t) <= 1e-30:
        return None
    t = t / np.linalg.norm(t)
    b = pv - (pv @ n) * n - (pv @ t) * t
    if np.linalg.norm(b) <= 1e-30:
        return None
    return t, b / np.linalg.norm(b)


def _indication(imap: np.ndarray, u: float, v: float) -> float:
    rows, cols = imap.shape
    x = min(max(u * cols - 0.5, 0.0), cols - 1.0)
    y = min(max(v * rows - 0.5, 0.0), rows - 1.0)
    x0, y0 = min(math.floor(x), cols - 1), min(math.floor(y), rows - 1)
    x1, y1 = min(x0 + 1, cols - 1), min(y0 + 1, rows - 1)
    fx, fy = x - x0, y - y0
    top = imap[y0, x0] * (1 - fx) + imap[y0, x1] * fx
    bottom = imap[y1, x0] * (1 - fx) + imap[y1, x1] * fx
    return top * (1 - fy) + bottom * fy


def _threshold(p, s: float, x: float, c: float, centred: bool) -> float:
    if p.threshold == "binary":
        return 1.0 if s + x > 1.0 else 0.0
    return min(max((0.5 if centred else 1.0) - c * (1.0 - s - x), 0.0), 1.0)


class Expected(NamedTuple):
    value: np.ndarray  # (3,): linear RGB of show color, else the raw value(s)
    tie: bool  # a binary threshold within rounding of its edge: either output is right


def _oracle(style, scene, gb, y: int, x: int) -> Expected:
    p = style.p
    i = int(gb["mesh_id"][y, x])
    obj = scene.objects[i]
    settings_ = style.objects.get(obj.name, {})
    screen = style.screen_for(style.object_specs(scene)[i], obj.material.texture)
    scale = np.asarray(settings_.get("uv_scale") or style.uv_scale or obj.material.uv_scale)
    uv0 = gb["uv"][y, x].astype(float)
    dx0, dy0 = gb["duv_dx"][y, x].astype(float), gb["duv_dy"][y, x].astype(float)
    uv, dx, dy = uv0 * scale, dx0 * scale, dy0 * scale
    aniso = p.anisotropy
    if screen.direction is not None:  # sec. 4.1: a 1D ramp along t = uv . d
        d = screen.direction
        uv = np.array([uv[0] * d[0] + uv[1] * d[1], 0.5])
        dx = np.array([dx[0] * d[0] + dx[1] * d[1], 0.0])
        dy = np.array([dy[0] * d[0] + dy[1] * d[1], 0.0])
        aniso = 1
    levels = screen.pyramid.levels
    rows, cols = levels[0].shape[:2]
    lod, offsets = _footprint(dx, dy, rows, cols, aniso)
    lod += p.lod_bias - (math.log2(gb.n) if p.sample_lod else 0.0)
    if p.show == "screen":
        return Expected(np.full(3, _filtered(levels, uv, lod, offsets)), False)
    nlevels = None if screen.normals is None else screen.normals.levels
    if p.show == "normals":
        if nlevels is None:
            return Expected(np.array([0.5, 0.5, 1.0]), False)
        return Expected(_filtered(nlevels, uv, lod, offsets), False)
    # the target intensity (Veryovka eq. 1, Rec. 709 luminance)
    m = obj.material
    n_raw = gb["normal"][y, x].astype(float)
    n = _unit(n_raw)
    pos = gb["position"][y, x].astype(float) if "position" in gb else np.zeros(3)
    frame = None
    if nlevels is not None:
        frame = _tangent_frame(
            n_raw,
            gb["dposition_dx"][y, x].astype(float),
            gb["dposition_dy"][y, x].astype(float),
            dx0,
            dy0,
        )
    rgb = np.asarray(m.ambient, float) * np.asarray(scene.ambient, float)
    for light in scene.lights:
        if light.kind == "point":
            l_dir = _unit(np.asarray(light.position, float) - pos)
        else:
            l_dir = _unit(light.direction)
        n_dot_l = float(n @ l_dir)
        f_d = min(max(n_dot_l, 0.0), 1.0)
        if frame is not None:  # sec. 5.2: DOT3 of the normal map in the tangent frame
            t, b = frame
            nm = _unit(2.0 * _filtered(nlevels, uv, lod, offsets) - 1.0)
            l_t = _unit([l_dir @ t, l_dir @ b, l_dir @ n_raw])
            f_d = min(max(float(nm @ l_t), 0.0), 1.0)
        rgb = rgb + np.asarray(m.diffuse, float) * f_d * np.asarray(light.color, float)
        if p.specular and m.shininess > 0 and n_dot_l > 0:
            h = _unit(l_dir + _unit(np.asarray(scene.camera.eye, float) - pos))
            f_s = min(max(float(n @ h), 0.0), 1.0) ** m.shininess
            rgb = rgb + np.asarray(m.specular, float) * f_s * np.asarray(light.color, float)
    inten = min(max(float(rgb @ np.array(LUMA)), 0.0), 1.0)
    imap = settings_.get("indication", style.indication)
    if imap is not None:  # sec. 5.1
        iscale = settings_.get("indication_scale") or (1.0, 1.0)
        inten = min(max(inten + _indication(imap, uv0[0] * iscale[0], uv0[1] * iscale[1]), 0), 1)
    if p.show == "intensity":
        return Expected(np.full(3, inten), False)
    c, centred = (p.c, p.centred) if p.c != "auto" else (None, True)
    if c is None:  # 1 / fwidth: central differences over one sample step
        fw = 0.0
        for d in (dx / gb.n, dy / gb.n):
            plus = _filtered(levels, uv + d, lod, offsets)
            minus = _filtered(levels, uv - d, lod, offsets)
            fw += abs(plus - minus) / 2
        c = 1.0 / max(fw, 1e-6)
    equalize = p.tone_correct and screen.kind != "strokes"
    tie = False
    if p.mip == "trilinear" and not equalize:
        s = _filtered(levels, uv, lod, offsets)
        tie = abs(s + inten - 1.0) < 1e-9
        value = _threshold(p, s, inten, c, centred)
    else:
        k0, k1, w1 = _levels(lod, len(levels))
        out = []
        for k in (k0, k1):
            s = _filtered(levels, uv, lod, offsets, k)
            if equalize:
                luts = style._luts(screen)
                s = float(np.interp(s, np.linspace(0, 1, luts.shape[1]), luts[k]))
            tie = tie or abs(s + inten - 1.0) < 1e-9
            out.append(_threshold(p, s, inten, c, centred))
        value = (1 - w1) * out[0] + w1 * out[1]
    rgb_out = value * np.asarray(p.paper) + (1 - value) * np.asarray(p.ink)
    return Expected(np.clip(rgb_out, 0.0, 1.0), tie and p.threshold == "binary")


@functools.cache
def _scene(name: str):
    if name != "mixed":
        return load_scene(name)
    scene = load_scene("halftone_room")  # directional and point lights, with specular terms
    lights = (
        Light("directional", direction=(0.3, 1.0, 0.6), color=(0.7, 0.6, 0.5)),
        Light("point", position=(0.5, 1.5, 2.0), color=(0.4, 0.4, 0.5)),
        Light("directional", direction=(-1.0, 0.2, 0.4), color=(0.2, 0.3, 0.2)),
    )
    mats = [
        dataclasses.replace(o.material, specular=(0.6, 0.5, 0.4), shininess=12.0)
        for o in scene.objects
    ]
    objects = tuple(
        dataclasses.replace(o, material=m) for o, m in zip(scene.objects, mats, strict=True)
    )
    return dataclasses.replace(scene, lights=lights, objects=objects)


def _check(style, scene_name: str, width=40, height=30, spp=1, count=60, seed=0) -> None:
    scene = _scene(scene_name)
    gb = rasterize(scene, scene.camera, width, height, sorted(style.requires(scene)), spp)
    out = style.shade(ShadeContext(gb, scene))
    covered = np.argwhere(gb["mesh_id"] >= 0)
    rng = np.random.default_rng(seed)
    got_any = False
    for y, x in covered[rng.choice(len(covered), size=min(count, len(covered)), replace=False)]:
        want = _oracle(style, scene, gb, int(y), int(x))
        got = out[y, x, :3].astype(float)
        if style.p.show != "color":  # raw values are stored as the linear grey of their sRGB
            got = linear_to_srgb(got)
        if want.tie:
            continue
        np.testing.assert_allclose(got, want.value, atol=2e-5, err_msg=f"sample {(y, x)}")
        assert out[y, x, 3] == 1.0
        got_any = True
    assert got_any


# -- the kernel against the oracle --------------------------------------------------------------
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
        "sample_lod": st.booleans(),
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
    c=st.one_of(st.floats(0.5, 40.0), st.just("auto")),
    centred=st.booleans(),
    scene=st.sampled_from(["halftone_sphere", "halftone_room", "halftone_torus_knot", "mixed"]),
    spp=st.sampled_from([1, 4]),
)
def test_random_options_match_the_oracle(opts, c, centred, scene, spp):
    if opts["threshold"] == "smooth":
        opts = {**opts, "c": c, "centred": centred and c != "auto"}
    _check(get_style("halftone", **opts), scene, spp=spp, count=25)


@pytest.mark.parametrize(
    "scene, opts",
    [
        ("halftone_teapot", {}),  # the benchmark's style: engraving, specular, one light
        ("mixed", {"screen": "bricks", "specular": True}),  # stroke lighting, point light
        ("halftone_room", {"threshold": "binary", "anisotropy": 8, "sample_lod": True}),
        ("halftone_sphere", {"c": "auto", "screen": "grass", "mip": "per_level"}),
        ("halftone_sphere", {"screen": "brick", "tone_correct": True, "threshold": "binary"}),
    ],
)
def test_cases_match_the_oracle(scene, opts):
    _check(get_style("halftone", **opts), scene, 48, 36, spp=4, count=80)


def test_screen_value_is_device_probes():
    """The kernel's hot lookup sums the same bilinear samples as ``device.sampling.probes``."""
    rng = np.random.default_rng(7)
    pyr = build_pyramid(rng.random((37, 64)).astype(np.float32)).packed()
    for _ in range(400):
        uv = tuple(rng.uniform(-3, 3, 2))
        lod = float(rng.uniform(-1, 8))
        n = int(rng.integers(0, 6))
        axis = tuple(rng.normal(0, 0.05, 2)) if n else (0.0, 0.0)
        want = probes(pyr, uv[0], uv[1], lod, n, axis, 0)
        assert K.screen_value(*pyr, uv, lod, n, axis) == want


# -- thread count, input errors, the screen cache -----------------------------------------------
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


def test_bad_g_buffers_are_named():
    scene = load_scene("halftone_sphere")
    style = get_style("halftone", specular=False)
    gb = rasterize(scene, scene.camera, 16, 12, sorted(style.requires(scene)))
    gb.channels["normal"] = gb["normal"][:8]
    with pytest.raises(ValueError, match=r"G-buffer channel 'normal': expected shape"):
        style.shade(ShadeContext(gb, scene))
    gb = rasterize(scene, scene.camera, 16, 12, sorted(style.requires(scene)))
    gb.channels["mesh_id"] = np.where(gb["mesh_id"] >= 0, 3, -1).astype(gb["mesh_id"].dtype)
    with pytest.raises(ValueError, match=r"got object index 3 but the scene has 1 objects"):
        style.shade(ShadeContext(gb, scene))


class _Cover(NamedTuple):
    mesh_id: np.ndarray
    cover: np.ndarray


def test_prepare_fills_empty_samples_and_finds_the_objects_in_view():
    mesh_id = np.array([[-1, -1, 0], [2, 2, -1]], dtype=np.int32)
    cover = np.array([[0, -1, 0], [1, 1, -1]], dtype=np.int32)  # covered where >= 0
    out = np.full((2, 3, 4), 7.0, np.float32)
    rows = np.empty((2, 4), dtype=np.int64)
    K.prepare(_Cover(mesh_id, cover), np.array([0.25, 0.5, 1.0]), rows, out)
    np.testing.assert_array_equal(rows.sum(axis=0) > 0, [True, False, True, False])
    np.testing.assert_array_equal(out[0, 0], [0.25, 0.5, 1.0, 1.0])  # covered, no object
    np.testing.assert_array_equal(out[0, 1], 0.0)  # empty
    np.testing.assert_array_equal(out[1, 2], 0.0)
    np.testing.assert_array_equal(out[0, 2], 7.0)  # an object's samples: left to its kernel
    np.testing.assert_array_equal(out[1, :2], 7.0)


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
