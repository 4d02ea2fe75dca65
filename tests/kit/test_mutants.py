"""``refnpr kit mutants``: the port bugs' emulations and the case x bug matrix.

Oracles: the output transforms against the sRGB formula written here; the triangle's own
barycentrics against the rasterizer's ``bary`` channel; repeated textures against the nearest
texel; end to end, a tiny kit of three small cases exported from a suite written here (no golden
files: the exporter renders the expected images), where refnpr's own render must pass and each
mutant of a bug that applies must fail.
"""

from __future__ import annotations

import json
import os
import re

import numpy as np
import pytest

from refnpr.kit.mutant_render import CaseRenderer
from refnpr.kit.mutants import format_markdown, format_text, run_mutants
from refnpr.kit.port_bugs import (
    BUGS,
    NotApplicable,
    ShiftedCamera,
    encode_gamma,
    encode_linear,
    encode_srgb_twice,
    perspective_bary,
    premultiply,
    repeat_texels,
    resolve_in_srgb,
    srgb8,
)

SUITE = """\
[defaults]
width = 48
height = 36

[[case]]
name = "tiny-toon"
scene = "sphere"
style = { name = "toon", n = 3 }
spp = 4

[[case]]
name = "tiny-halftone"
scene = "sphere"
style = { name = "halftone" }

[[case]]
name = "tiny-threshold"
scene = "sphere"
style = { name = "threshold", source = "image", texture = "camera", n = 2, uv_scale = [2.0, 1.0] }

[[case]]
name = "tiny-coplanar"
scene = "coplanar.toml"
style = { name = "smooth" }

[[case]]
name = "tiny-gbuffer"
kind = "gbuffer"
scene = "teapot"
width = 40
height = 30
channels = ["tri_id", "uv", "duv_dx", "duv_dy", "normal", "lod"]
texture_size = [64, 64]
"""

#: Two objects with the same plane mesh: every covered sample is an exact depth tie.
COPLANAR = """\
[camera]
eye = [0.0, 4.0, 3.0]
target = [0.0, 0.0, 0.0]

[[object]]
name = "first"
mesh = "plane"
width = 3.0
depth = 3.0
material = { diffuse = [0.8, 0.1, 0.1] }

[[object]]
name = "second"
mesh = "plane"
width = 3.0
depth = 3.0
material = { diffuse = [0.1, 0.1, 0.8] }
"""

#: Per case, the bugs that must be caught; every other bug must be n/a or without effect, but
#: for MISSED (gamma 2.2 moves lit tones by 2 levels at most, the threshold; the threshold
#: style's small sphere hides its derivative and normal errors within the tolerance)
CAUGHT = {
    "tiny-toon": {*("half_pixel", "srgb_twice", "srgb_never", "y_flip", "srgb_resolve"),
                  *("light_negated", "no_renormalize")},
    "tiny-halftone": {*("half_pixel", "v_flip", "srgb_twice", "srgb_never", "gamma22"),
                      *("y_flip", "light_negated", "quad_derivatives", "quad_derivatives_fine"),
                      *("lod_bias_plus1", "lod_bias_minus1", "nearest")},
    "tiny-threshold": {*("half_pixel", "v_flip", "srgb_twice", "srgb_never", "y_flip"),
                       *("light_negated", "lod_bias_plus1", "lod_bias_minus1", "nearest")},
    "tiny-coplanar": {*("half_pixel", "srgb_twice", "srgb_never", "y_flip", "light_negated"),
                      "depth_le"},
    "tiny-gbuffer": {*("half_pixel", "v_flip", "y_flip", "quad_derivatives", "dfdy_sign"),
                     *("quad_derivatives_fine", "lod_bias_plus1", "lod_bias_minus1"),
                     *("no_renormalize", "no_snap")},
}  # fmt: skip
MISSED = {
    ("tiny-toon", "gamma22"),
    ("tiny-threshold", "gamma22"),
    ("tiny-threshold", "no_renormalize"),
    ("tiny-threshold", "quad_derivatives"),
    ("tiny-threshold", "quad_derivatives_fine"),
}
STYLE = {"tiny-toon": "toon", "tiny-threshold": "threshold"}


def _srgb(x):
    x = np.clip(np.asarray(x, dtype=np.float64), 0, 1)
    return np.where(x <= 0.0031308, 12.92 * x, 1.055 * x ** (1 / 2.4) - 0.055)


# -- output transforms on tiny arrays ---------------------------------------------------------


def _rgba():
    rows = [
        [[0.0, 0.002, 0.5, 1.0], [0.2, 1.0, 0.04, 0.5]],
        [[1.2, -0.1, 0.7, 0.0], [0.01, 0.3, 0.9, 0.25]],
    ]
    return np.array(rows, dtype=np.float32)


def test_output_transforms_follow_their_formulas():
    from refnpr.image import Image

    a = _rgba()
    rgb, alpha = np.clip(a[..., :3].astype(np.float64), 0, 1), np.clip(a[..., 3], 0, 1)
    assert np.array_equal(srgb8(a), Image(a).to_srgb8())
    assert np.array_equal(encode_srgb_twice(a)[..., :3], np.rint(255 * _srgb(_srgb(rgb))))
    assert np.array_equal(encode_linear(a)[..., :3], np.rint(255 * rgb))
    assert np.array_equal(encode_gamma(a, 2.2)[..., :3], np.rint(255 * rgb ** (1 / 2.2)))
    for enc in (encode_srgb_twice, encode_linear, encode_gamma):
        assert np.array_equal(enc(a)[..., 3], np.rint(255 * alpha))  # alpha stays linear
    # one mid grey: 0.5 linear is 188 encoded once, 223 twice, 128 never, 186 with gamma 2.2
    grey = np.full((1, 1, 4), 0.5)
    grey[..., 3] = 1
    assert [srgb8(grey)[0, 0, 0], encode_srgb_twice(grey)[0, 0, 0]] == [188, 223]
    assert [encode_linear(grey)[0, 0, 0], encode_gamma(grey)[0, 0, 0]] == [128, 186]


def test_premultiply_scales_colour_by_alpha_only():
    a = _rgba()
    p = premultiply(a)
    assert p.dtype == np.float32 and np.array_equal(p[..., 3], a[..., 3])
    assert np.allclose(p[..., :3], a[..., :3] * a[..., 3:4])
    assert not np.shares_memory(p, a)


def test_resolve_in_srgb_averages_encoded_values():
    samples = np.zeros((2, 2, 4), dtype=np.float32)
    samples[..., 3] = 1.0
    samples[..., :3] = 1.0
    samples[1, 1, :3] = 0.0  # three white samples and a black one
    got = resolve_in_srgb(samples, 2, (0, 0, 0, 1))
    assert got.shape == (1, 1, 4)
    assert list(got[0, 0]) == [191, 191, 191, 255]  # encoded mean; the linear mean gives 225
    # transparent samples take the background; one sample per pixel is the kit's encoding
    one = _rgba()
    bg = np.array([0.3, 0.6, 0.1, 1.0])
    a = np.clip(one[..., 3:4].astype(np.float64), 0, 1)
    comp = np.concatenate([one[..., :3] * a + bg[:3] * (1 - a), np.ones_like(a)], axis=-1)
    assert np.array_equal(resolve_in_srgb(one, 1, bg), srgb8(comp))
    with pytest.raises(ValueError, match="not a grid of 2 x 2 blocks"):
        resolve_in_srgb(np.zeros((3, 2, 4)), 2, bg)


def test_output_transforms_reject_other_shapes():
    for enc in (srgb8, encode_srgb_twice, encode_linear, encode_gamma):
        with pytest.raises(ValueError, match=r"expected an \(H, W, 4\) array"):
            enc(np.zeros((4, 4, 3)))
    with pytest.raises(ValueError, match=r"expected an \(nH, nW, 4\) array"):
        premultiply(np.zeros(4))


# -- geometry -----------------------------------------------------------------------------------


def test_perspective_bary_matches_the_rasterizer():
    from refnpr.raster import rasterize
    from refnpr.scenes import load_scene

    scene = load_scene("teapot")
    gb = rasterize(scene, scene.camera, 40, 30, ["tri_id", "bary"], 4)
    meshes = scene.world_meshes()
    offsets = np.cumsum([0] + [m.positions.shape[0] for m in meshes])
    positions = np.concatenate([m.positions for m in meshes])
    faces = np.concatenate([m.faces + o for m, o in zip(meshes, offsets[:-1], strict=True)])
    ys, xs = np.nonzero(gb["tri_id"] >= 0)
    b = perspective_bary(
        gb.view_projection, positions, faces, gb["tri_id"][ys, xs], xs, ys, (80, 60)
    )
    assert np.allclose(b.sum(axis=1), 1.0)
    assert np.abs(b - gb["bary"][ys, xs]).max() < 1e-6  # the channel is float32


def _gbuffer_case(**extra):
    from refnpr.golden import GoldenCase

    params = {"kind": "gbuffer", "width": 40, "height": 30, "spp": 1, "texture_size": [64, 64],
              "channels": ["tri_id", "uv", "duv_dx", "duv_dy", "lod"], **extra}  # fmt: skip
    return CaseRenderer(GoldenCase("g", "teapot", params))


def test_quad_derivatives_are_finite_differences_of_the_own_triangle():
    r = _gbuffer_case()
    exact = r.correct()
    coarse, fine = r.mutant("quad_derivatives"), r.mutant("quad_derivatives_fine")
    tri = exact["tri_id"]
    h, w = tri.shape[0] // 2, tri.shape[1] // 2

    def quads(a):  # (h, w, 2, 2, C): the 2 x 2 quads
        a = a[: 2 * h, : 2 * w].reshape(h, 2, w, 2, -1)
        return a.transpose(0, 2, 1, 3, 4)

    t = quads(tri[..., None])[..., 0]
    whole = (t == t[:, :, :1, :1]).all(axis=(2, 3)) & (t[:, :, 0, 0] >= 0)  # one triangle
    for name in ("duv_dx", "duv_dy"):
        a, c, f = (quads(x[name])[whole] for x in (exact, coarse, fine))  # (K, 2, 2, 2)
        assert np.array_equal(c, np.broadcast_to(c[:, :1, :1], c.shape))  # one per quad
        assert not np.array_equal(f, np.broadcast_to(f[:, :1, :1], f.shape))
        rel = np.abs(c - a).max(axis=-1) / np.maximum(np.abs(a).max(axis=-1), 1e-6)
        assert whole.sum() > 50 and np.median(rel) < 0.05  # close to the analytic values
        assert (rel > 1e-4).mean() > 0.25  # ... and not equal to them
    assert np.array_equal(coarse["uv"], exact["uv"]) and np.array_equal(coarse["tri_id"], tri)
    assert not np.array_equal(coarse["lod"], exact["lod"])  # recomputed from the new duv


def test_shifted_camera_moves_ndc_by_half_a_sample_pixel():
    from refnpr.raster import Camera

    cam = Camera.look_at((0, 0, 5), (0, 0, 0), fov_y=40.0)
    shifted = ShiftedCamera.of(cam, n=2)
    p = np.array([0.3, -0.2, 0.1, 1.0])

    def ndc(c):
        clip = c.view_projection(40, 30) @ p
        return clip[:2] / clip[3]

    # half a sample-grid pixel of an 80 x 60 grid is 1/80 and 1/60 in NDC; y points up in NDC
    assert np.allclose(ndc(shifted) - ndc(cam), [1 / 80, -1 / 60])
    assert isinstance(shifted, Camera) and np.array_equal(shifted.view_matrix(), cam.view_matrix())


def test_repeated_texels_sample_as_the_nearest_texel():
    from refnpr.texture import MipPyramid, sample_level

    rng = np.random.default_rng(3)
    level = rng.random((4, 6)).astype(np.float32)
    k = 8
    pyr = MipPyramid((repeat_texels(level, k),))
    uv = rng.random((2000, 2))
    texel = np.stack([uv[:, 0] * 6, uv[:, 1] * 4], axis=1)
    edge = np.abs(texel - np.rint(texel)).min(axis=1)
    far = edge > 1 / (2 * k)  # outside the blend band at texel edges
    got = sample_level(pyr, uv, 0, dtype=np.float64)
    nearest = level[np.floor(texel[:, 1]).astype(int), np.floor(texel[:, 0]).astype(int)]
    assert far.sum() > 1000
    assert np.allclose(got[far], nearest[far], atol=1e-6)
    plain = sample_level(MipPyramid((level,)), uv, 0, dtype=np.float64)
    assert np.abs(plain[far] - nearest[far]).max() > 0.1  # linear filtering differs there


def test_unknown_bug_and_inapplicable_bugs():
    from refnpr.golden import GoldenCase

    case = GoldenCase(
        "t", "sphere", {"kind": "image", "width": 16, "height": 12, "spp": 1,
                        "style": {"name": "toon", "n": 2}},
    )  # fmt: skip
    r = CaseRenderer(case)
    with pytest.raises(ValueError, match="unknown bug 'nope'"):
        r.mutant("nope")
    for bug, why in [
        ("quad_derivatives", "no screen-space derivatives"),
        ("lod_bias_minus1", "no mip-mapped texture"),
        ("nearest", "no texture with linear filtering"),
        ("srgb_resolve", "one sample per pixel"),
    ]:
        with pytest.raises(NotApplicable, match=why):
            r.mutant(bug)


# -- the matrix on a tiny kit ------------------------------------------------------------------


@pytest.fixture(scope="module")
def tiny(tmp_path_factory):
    from refnpr.kit import export_kit

    root = tmp_path_factory.mktemp("mutants")
    suite = root / "suite.toml"
    suite.write_text(SUITE)
    (root / "coplanar.toml").write_text(COPLANAR)
    kit = root / "kit"
    export_kit(kit, suite=suite)
    report = run_mutants(kit, suite=suite)
    return kit, suite, report


def test_controls_pass_and_every_applicable_bug_is_caught(tiny):
    _, _, report = tiny
    names = ["tiny-coplanar", "tiny-gbuffer", "tiny-halftone", "tiny-threshold", "tiny-toon"]
    assert [c.name for c in report.cases] == names and report.bugs == list(BUGS)
    for c in report.cases:
        assert c.control == "pass", (c.name, c.control_message)
        for bug in BUGS:
            r = c.results[bug]
            if bug in CAUGHT[c.name]:
                assert r["verdict"] == "caught", (c.name, bug, r)
            elif (c.name, bug) in MISSED:
                assert r["verdict"] == "missed", (c.name, bug, r)
            else:
                assert r["verdict"] in ("n/a", "no_effect"), (c.name, bug, r)
    by = {c.name: c.results for c in report.cases}
    assert by["tiny-toon"]["quad_derivatives"]["verdict"] == "n/a"
    assert by["tiny-toon"]["premultiplied"]["verdict"] == "no_effect"  # opaque samples
    assert by["tiny-halftone"]["depth_le"]["verdict"] == "no_effect"  # no exact depth ties
    assert by["tiny-gbuffer"]["srgb_twice"]["verdict"] == "n/a"
    assert by["tiny-gbuffer"]["quad_derivatives"]["metrics"]["frac_bad"] > 0


def test_summary_text_markdown_and_json(tiny):
    kit, _, report = tiny
    s = report.summary()
    assert s["toon"]["light_negated"] == {
        "caught": 1, "missed": 0, "no_effect": 0, "n/a": 0, "error": 0, "shown": 1,
    }  # fmt: skip
    assert s["toon"]["gamma22"]["missed"] == 1 and s["gbuffer"]["light_negated"]["n/a"] == 1
    assert set(report.uncaught()) == {(bug, STYLE[case]) for case, bug in MISSED}
    assert report.controls_pass
    text = format_text(report)
    assert "light_negated          caught by 1 of the 1 case(s) it changes" in text
    assert "gamma22                caught by 0 of the 1 case(s) it changes  <- NOT CAUGHT" in text
    assert "target NOT met: 5 (bug, style) pair(s) uncaught, 0 control(s) failing" in text
    md = format_markdown(report)
    assert "| toon | 1 |" in md and "| tiny-gbuffer | gbuffer | pass |" in md
    assert all(f"`{b}`" in md for b in BUGS) and "`gamma22` (toon)" in md
    data = report.to_json()
    json.dumps(data, allow_nan=False)
    assert not data["target"]["met"] and data["target"]["controls_pass"]
    assert {"bug": "gamma22", "style": "toon"} in data["target"]["uncaught"]
    assert [b["name"] for b in data["bugs"]] == list(BUGS)
    assert data["cases"][1]["results"]["y_flip"]["verdict"] == "caught"


def test_target_met_once_every_changed_style_catches(tiny):
    import copy

    _, _, report = tiny
    better = copy.deepcopy(report)
    cases = {c.name: c for c in better.cases}
    for case, bug in MISSED:
        cases[case].results[bug]["verdict"] = "caught"
    toon = cases["tiny-toon"]
    assert better.uncaught() == [] and "target met" in format_text(better)
    assert better.to_json()["target"]["met"]
    toon.control = "fail"
    assert not better.to_json()["target"]["met"]
    assert "1 control(s) failing" in format_text(better)


def test_cli_json_markdown_and_errors(tiny, tmp_path, capsys):
    from refnpr.cli import main

    kit, suite, _ = tiny
    out = tmp_path / "m.json"
    # the CLI renders from the installed suite, which has no "tiny-*" case: an error per case
    rc = main(["kit", "mutants", str(kit), "--only", "tiny-gbuffer", "--bugs", "v_flip",
               "--json", str(out), "--markdown"])  # fmt: skip
    printed = capsys.readouterr().out
    assert rc == 1
    data = json.loads(out.read_text())
    assert data["cases"][0]["control"] == "error"
    assert "the suite has no case 'tiny-gbuffer'" in data["cases"][0]["control_message"]
    assert "| tiny-gbuffer | gbuffer | error | err |" in printed
    with pytest.raises(
        ValueError, match=r"bugs: unknown name\(s\) \['v_flp'\].*did you mean \['v_flip'"
    ):
        run_mutants(kit, bugs=["v_flp"], suite=suite)
    with pytest.raises(ValueError, match=r"only: unknown name\(s\) \['tiny'\]"):
        run_mutants(kit, only=["tiny"], suite=suite)
    with pytest.raises(ValueError, match="is not a directory"):
        run_mutants(tmp_path / "nope", suite=suite)
    (tmp_path / "bad").mkdir()
    (tmp_path / "bad" / "index.json").write_text("{")
    with pytest.raises(ValueError, match=r"kit_dir: kit file 'index\.json': not valid JSON"):
        run_mutants(tmp_path / "bad", suite=suite)


# -- a hostile kit -------------------------------------------------------------------------------
# index.json and case.json are read as `kit check` reads them: inside the kit, regular files
# (a FIFO would block the read, a link to /dev/zero never end) of a bounded size, bounded JSON.

ONE_CASE = (
    '[[case]]\nname = "c"\nscene = "sphere"\nstyle = { name = "toon" }\nwidth = 8\nheight = 6\n'
)
INDEX = '{"cases": [{"name": "c", "kind": "image", "style": "toon"}]}'


def _hostile_kit(tmp_path):
    kit = tmp_path / "kit"
    (kit / "c").mkdir(parents=True)
    (tmp_path / "suite.toml").write_text(ONE_CASE)
    (tmp_path / "outside.json").write_text(INDEX)
    return kit, tmp_path / "suite.toml"


@pytest.mark.parametrize(
    "label, make, message",
    [
        (
            "link out of the kit",
            lambda kit: (kit / "index.json").symlink_to(kit.parent / "outside.json"),
            r"kit_dir: kit file 'index\.json': 'index\.json' leads outside the kit",
        ),
        (
            "fifo",
            lambda kit: os.mkfifo(kit / "index.json"),
            r"kit_dir: kit file 'index\.json' is not a regular file",
        ),
        (  # Python parses at most 4300 digits: a ValueError that named no file
            "5000 digits",
            lambda kit: (kit / "index.json").write_text('{"cases": [' + "1" * 5000 + "]}"),
            r"kit_dir: kit file 'index\.json': not valid JSON: Exceeds the limit",
        ),
        (
            "above the JSON cap",
            lambda kit: (kit / "index.json").write_text(INDEX + " " * 9000),
            r"kit_dir: kit file 'index\.json' has 9\d+ bytes, more than the 8000 bytes allowed",
        ),
    ],
)
def test_a_hostile_index_is_refused_naming_the_file(tmp_path, monkeypatch, label, make, message):
    from refnpr.kit import limits

    monkeypatch.setattr(limits, "MAX_JSON_BYTES", 8000)
    kit, suite = _hostile_kit(tmp_path)
    make(kit)
    with pytest.raises(ValueError, match=message):
        run_mutants(kit, suite=suite, bugs=["v_flip"])


@pytest.mark.parametrize(
    "label, make, message",
    [
        (
            "link out of the kit",
            lambda kit: (kit / "c" / "case.json").symlink_to(kit.parent / "outside.json"),
            r"kit file 'c/case\.json': 'c/case\.json' leads outside the kit",
        ),
        (
            "link to /dev/zero",  # read whole, it exhausted memory (a MemoryError, not caught)
            lambda kit: (kit / "c" / "case.json").symlink_to("/dev/zero"),
            r"kit file 'c/case\.json': 'c/case\.json' leads outside the kit",
        ),
        (
            "fifo",
            lambda kit: os.mkfifo(kit / "c" / "case.json"),
            r"kit file 'c/case\.json' is not a regular file",
        ),
    ],
)
def test_a_hostile_case_file_is_an_error_of_its_case(tmp_path, label, make, message):
    kit, suite = _hostile_kit(tmp_path)
    (kit / "index.json").write_text(INDEX)
    (tmp_path / "outside.json").write_text('{"width": 9, "height": 6, "spp": 1}')
    make(kit)
    report = run_mutants(kit, suite=suite, bugs=["v_flip"])
    (case,) = report.cases
    assert case.control == "error"
    assert re.search("cannot render the case: " + message, case.control_message)
