"""Fragment gathering and the texture-space TAM ink against a brute-force loop over the lattice."""

from __future__ import annotations

import math

import numpy as np
import pytest

from refnpr.formulas.tamiss.field import KX, hash01, pack_id
from refnpr.raster import Camera, Mesh, rasterize
from refnpr.scenes import Material, Scene, SceneObject, load_scene, teapot, uv_sphere
from refnpr.styles.tamiss.field import (
    SALT_LENGTH,
    SALT_TONE,
    SALT_WIDTH,
    StrokeField,
    stroke_geometry,
)
from refnpr.styles.tamiss.gather import (
    FieldInputs,
    field_inputs,
    gather_fragments,
    layer_scale,
    scene_charts,
    tam_ink,
)

BASE = {(int(KX[r]), r) for r in range(7)}


def random_inputs(n: int, seed: int) -> FieldInputs:
    rng = np.random.default_rng(seed)
    angle = rng.uniform(0, 2 * np.pi, n)
    mag = np.exp2(rng.uniform(-9.5, -3.0, n))  # texture units per pixel: levels -1 .. 6
    aniso = rng.uniform(0.5, 2.0, n)
    duv_dx = np.stack([np.cos(angle), np.sin(angle)], 1) * mag[:, None]
    duv_dy = np.stack([-np.sin(angle), np.cos(angle)], 1) * (mag * aniso)[:, None]
    return FieldInputs(
        sample=np.arange(n, dtype=np.int64),
        uv=rng.uniform(-2.0, 3.0, (n, 2)),
        duv_dx=duv_dx,
        duv_dy=duv_dy,
        uv_scale=np.tile([1.0, 2.0], (n, 1)),
        darkness=rng.uniform(0.0, 1.0, n),
        chart=rng.integers(0, 5, n).astype(np.int64),
        shape=(1, n),
        n=1,
    )


def _layer_frames(inp: FieldInputs, i: int, field: StrokeField):
    """Per layer with ink at sample i, the spec's frame (sec. 3.1, docs/kit.md ``tam-field``):
    ``(layer, rho, p, q, d_p, d_q, L, f, thin)``, in plain Python floats."""
    su, sv = inp.uv_scale[i]
    u, v = inp.uv[i, 0] * su, inp.uv[i, 1] * sv
    ux, vx = inp.duv_dx[i, 0] * su, inp.duv_dx[i, 1] * sv
    uy, vy = inp.duv_dy[i, 0] * su, inp.duv_dy[i, 1] * sv
    for layer, (deg, tone) in enumerate(zip(field.directions, field.layer_tones, strict=True)):
        ca, sa = math.cos(math.radians(deg)), math.sin(math.radians(deg))
        rho = min(max((inp.darkness[i] - tone) / (1 - tone) * field.density, 0.0), 1.0)
        if rho <= 0:
            continue
        p, q = ca * u + sa * v, -sa * u + ca * v
        d_p = 1 / math.hypot(ca * ux + sa * vx, ca * uy + sa * vy)
        d_q = 1 / math.hypot(-sa * ux + ca * vx, -sa * uy + ca * vy)
        s = math.log2(d_q / (7 * field.period))
        big_l, f, thin = math.floor(s), s - math.floor(s), 1.0
        if big_l < 0:
            big_l, f, thin = 0, 0.0, 2.0**s
        if big_l >= field.max_level:
            big_l, f = field.max_level, 0.0
        yield layer, rho, p, q, d_p, d_q, big_l, f, thin


def oracle(inp: FieldInputs, i: int, field: StrokeField, hw: float, tam_width=None, fade=None):
    """Strokes over sample i by brute force: [(id, t, coverage)] (coverage for TAM only)."""
    out = []
    for layer, rho, p, q, d_p, d_q, big_l, f, thin in _layer_frames(inp, i, field):
        top = big_l + 1 if f > 0 else big_l
        for lev in range(top + 1):
            gain = thin if lev <= big_l else 2.0**f - 1
            sc = 2**lev
            for gx in range(math.floor(p * sc) - 3, math.floor(p * sc) + 4):
                for gy in range(math.floor(q * sc) - 2, math.floor(q * sc) + 3):
                    for r in range(7):
                        X, Y = 7 * gx + int(KX[r]), 7 * gy + r
                        if lev > 0 and X % 2 == 0 and Y % 2 == 0:
                            if ((X // 2) % 7, (Y // 2) % 7) in BASE:
                                continue  # a seed of the coarser level
                        dist = abs(q - Y / (7 * sc)) * d_q
                        if dist > hw:
                            continue
                        sid = int(pack_id(inp.chart[i], layer, lev, gx, gy, r))
                        h = hash01(sid, SALT_LENGTH)[0]
                        length = field.length * (1 + field.length_jitter * (2 * h - 1)) / sc
                        t = (p - (X / (7 * sc) - length / 2)) / length
                        tau = hash01(sid, SALT_TONE)[0]
                        if tam_width is None:
                            if dist <= hw and 0 <= t <= 1 and tau < rho * gain:
                                out.append((sid, t, 1.0))
                        else:
                            opacity = min(max((rho * gain - tau) / fade, 0.0), 1.0)
                            wf = 1 + field.width_jitter * (2 * hash01(sid, SALT_WIDTH)[0] - 1)
                            beyond = max(-t, t - 1) * length * d_p  # signed, < 0 inside
                            cov = min(max(tam_width * wf / 2 - dist + 0.5, 0.0), 1.0)
                            cov *= min(max(0.5 - beyond, 0.0), 1.0)
                            if cov * opacity > 0:
                                out.append((sid, t, cov * opacity))
    return out


@pytest.mark.parametrize("seed", [0, 1])
def test_gathered_fragments_match_brute_force(seed):
    inp = random_inputs(150, seed)
    field = StrokeField.from_params(directions=["u", 30.0], layer_tones=[0.0, 0.3], period=3.0)
    frags = gather_fragments(inp, field, gather_width=2.0)
    got = {}
    for s, sid, t in zip(frags.sample, frags.id, frags.t, strict=True):
        got.setdefault(int(s), []).append((int(sid), float(t)))
    total = 0
    for i in range(inp.sample.size):
        want = sorted((sid, t) for sid, t, _ in oracle(inp, i, field, 1.0))
        have = sorted(got.get(i, []))
        assert [a for a, _ in have] == [a for a, _ in want], f"sample {i}"
        np.testing.assert_allclose([b for _, b in have], [b for _, b in want], atol=1e-12)
        total += len(want)
    assert total > 50  # the comparison is not vacuous
    assert np.all((frags.t >= 0) & (frags.t <= 1))


def test_tam_ink_matches_brute_force():
    inp = random_inputs(150, 7)
    field = StrokeField.from_params(directions=["v", -20.0], period=2.5, width_jitter=0.3)
    ink = tam_ink(inp, field, width=1.7, density_mode="fade", fade=0.2)[0]
    expected = []
    for i in range(inp.sample.size):
        a = 0.0
        for _, _, c in oracle(inp, i, field, 1.7 * 1.3 / 2 + 0.5, tam_width=1.7, fade=0.2):
            a = a + c * (1 - a)
        expected.append(a)
    np.testing.assert_allclose(ink, expected, atol=1e-12)
    assert np.count_nonzero(ink) > 20
    # a stroke covers fully from half a pixel inside its ends (it was capped at one half)
    full = [
        c
        for i in range(inp.sample.size)
        for _, _, c in oracle(inp, i, field, 1.7 * 1.3 / 2 + 0.5, tam_width=1.7, fade=0.2)
    ]
    assert max(full) == 1.0
    clip = tam_ink(inp, field, width=1.7, density_mode="clip")[0]
    assert set(np.unique(clip > 0)) <= {False, True} and np.all(clip <= 1.0)


def test_fragments_lie_on_their_strokes():
    inp = random_inputs(400, 11)
    field = StrokeField.from_params(directions=[45.0], period=3.0)
    frags = gather_fragments(inp, field, gather_width=1.0)
    g = stroke_geometry(frags.id, field)
    i = frags.sample
    su, sv = inp.uv_scale[i].T
    u, v = inp.uv[i, 0] * su, inp.uv[i, 1] * sv
    c = s = math.sqrt(0.5)
    p, q = c * u + s * v, -s * u + c * v
    np.testing.assert_allclose(p, g.p_start + frags.t * g.length, rtol=0, atol=1e-9)
    gq = np.hypot(-s * inp.duv_dx[i, 0] * su + c * inp.duv_dx[i, 1] * sv,
                  -s * inp.duv_dy[i, 0] * su + c * inp.duv_dy[i, 1] * sv)  # fmt: skip
    assert np.all(np.abs(q - g.q) / gq <= 0.5 + 1e-12)  # within half the band, in pixels
    assert np.all(g.chart == inp.chart[i])


def test_charts_are_uv_components():
    assert scene_charts(load_scene("tamiss_sphere")).max() == 0  # one chart
    tp = teapot(level=4)
    sc = Scene(
        objects=(SceneObject(uv_sphere(1.0, 8, 4)), SceneObject(tp)),
        camera=Camera.look_at((0, 0, 5), (0, 0, 0), (0, 1, 0), 40, 0.1, 50),
    )
    charts = scene_charts(sc)
    n_sphere = uv_sphere(1.0, 8, 4).faces.shape[0]
    assert np.all(charts[:n_sphere] == 0)
    assert np.unique(charts[n_sphere:]).tolist() == list(range(1, 33))  # 32 Bezier patches
    # brute force: faces of one chart share no vertex with another chart
    f = tp.faces
    lab = charts[n_sphere:]
    owner = {}
    for face, c in zip(f, lab, strict=True):
        for vtx in face:
            assert owner.setdefault(int(vtx), c) == c


def test_uv_range_error():
    pos = np.array([[-1, -1, 0], [1, -1, 0], [1, 1, 0.0]])
    mesh = Mesh(
        pos,
        np.array([[0, 1, 2]]),
        np.tile([0, 0, 1.0], (3, 1)),
        np.array([[0, 0], [1, 0], [1, 1.0]]),
    )
    sc = Scene(
        objects=(SceneObject(mesh, material=Material(uv_scale=600.0)),),
        camera=Camera.look_at((0, 0, 3), (0, 0, 0), (0, 1, 0), 60, 0.1, 10),
    )
    gb = rasterize(sc, None, 16, 16, ["uv", "duv_dx", "duv_dy", "tri_id", "mesh_id", "normal"])
    with pytest.raises(ValueError, match="uv: scaled texture coordinates reach .* tiles"):
        field_inputs(gb, sc, derivatives="flat")


def test_level_scale_is_the_dyadic_scale_of_q():
    sc = load_scene("sphere")  # uv_scale 1: for strokes along u, q = v
    chans = ["uv", "duv_dx", "duv_dy", "tri_id", "mesh_id", "normal", "dyadic_scale"]
    gb = rasterize(sc, None, 64, 48, chans, line_period=7 * 3.0, dtype=np.float64)
    inp = field_inputs(gb, sc, derivatives="flat")  # the rasterizer's per-triangle values
    field = StrokeField.from_params(directions=["u", "v"], period=3.0)
    s = layer_scale(inp, field)
    ref = gb["dyadic_scale"][gb["tri_id"] >= 0]
    ok = np.isfinite(ref)
    np.testing.assert_allclose(s[ok, 0], ref[ok], rtol=0, atol=1e-9)
    # strokes along v: q = -u, the dyadic scale of u
    gu = rasterize(sc, None, 64, 48, chans, line_period=21.0, dyadic_coord="u", dtype=np.float64)
    ref_u = gu["dyadic_scale"][gu["tri_id"] >= 0]
    ok = np.isfinite(ref_u)
    np.testing.assert_allclose(s[ok, 1], ref_u[ok], rtol=0, atol=1e-9)


def _capped_ink(inp: FieldInputs, i: int, field: StrokeField, width: float, fade: float, cap: int):
    """TAM ink of sample i as docs/kit.md's ``tam-field`` spells it: the candidates in the
    enumeration order (level, row, cell), at most ``cap`` kept per layer. Also returns the most
    candidates any layer had before the cap."""
    hw_px, end_px = width * (1 + field.width_jitter) / 2 + 0.5, 0.5
    ink, most = 0.0, 0
    for layer, rho, p, q, d_p, d_q, big_l, f, thin in _layer_frames(inp, i, field):
        cands = []
        for lev in range(big_l + (2 if f > 0 else 1)):
            gain = thin if lev <= big_l else 2.0**f - 1
            if gain * rho <= 0:
                continue
            rows = 7 * 2**lev
            for ry in range(
                math.floor((q - hw_px / d_q) * rows), math.floor((q + hw_px / d_q) * rows) + 2
            ):
                dist = abs(q - ry / rows) * d_q
                if dist > hw_px:
                    continue
                gy, r = ry // 7, ry % 7
                kx = int(KX[r])
                ps = p * 2**lev - kx / 7
                h = field.length * (1 + field.length_jitter) / 2 + end_px / d_p * 2**lev
                for gx in range(math.floor(ps - h), math.floor(ps + h) + 2):
                    if lev > 0 and gx % 2 == kx % 2 and gy % 2 == r % 2:
                        continue
                    sid = int(pack_id(inp.chart[i], layer, lev, gx, gy, r))
                    lam = (
                        field.length
                        * (1 + field.length_jitter * (2 * hash01(sid, SALT_LENGTH)[0] - 1))
                        / 2**lev
                    )
                    t = (p - ((gx + kx / 7) / 2**lev - lam / 2)) / lam
                    beyond = max(-t, t - 1) * lam * d_p
                    if beyond <= end_px:
                        cands.append((sid, dist, beyond, rho * gain))
        most = max(most, len(cands))
        for sid, dist, beyond, limit in cands[:cap]:
            opacity = min(max((limit - hash01(sid, SALT_TONE)[0]) / fade, 0.0), 1.0)
            if opacity <= 0:
                continue
            wf = 1 + field.width_jitter * (2 * hash01(sid, SALT_WIDTH)[0] - 1)
            a = min(max(width * wf / 2 - dist + 0.5, 0.0), 1.0) * min(max(0.5 - beyond, 0.0), 1.0)
            ink = ink + a * opacity * (1 - ink)
    return ink, most


def test_tam_ink_keeps_the_candidate_cap_for_wide_strokes():
    """Strokes 48 px wide over 1 px rows, faint (opacity at most ~0.1, so the ink does not
    saturate): some samples have more candidates than the kernel's cap, and there the capped
    enumeration's ink differs from the uncapped one. The kernel must give the capped ink there
    (the fused fast path hands those samples over to it) and the same ink elsewhere (fast path),
    both against the spec's loop."""
    from dataclasses import replace

    from refnpr.styles.tamiss._kernels import _CAP

    n = 40
    inp = replace(random_inputs(n, 3), darkness=np.full(n, 0.1))
    field = StrokeField.from_params(
        directions=["u", 60.0], period=1.0, length=2.0, width_jitter=0.3
    )
    got = tam_ink(inp, field, width=48.0, density_mode="fade", fade=1.0)[0]
    most, differs = [], 0
    for i in range(n):
        want, m = _capped_ink(inp, i, field, 48.0, 1.0, _CAP)
        most.append(m)
        assert abs(got[i] - want) <= 1e-12, f"sample {i}: {got[i]} vs {want} ({m} candidates)"
        differs += abs(want - _capped_ink(inp, i, field, 48.0, 1.0, 10**9)[0]) > 1e-9
    assert max(most) > _CAP and min(most) <= _CAP  # both paths were taken
    assert differs >= 10  # and the cap changes the ink there
