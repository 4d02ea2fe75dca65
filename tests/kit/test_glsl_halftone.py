"""The GLSL halftone pass (backends/glsl/refnpr_glsl/styles/halftone.py) against refnpr's
HalftoneStyle (Freudenberg, Masuch, Strothotte 2002).

Two levels:

* ``test_shade_matches_refnpr_per_sample``: every golden case whose style is ``halftone`` (by
  the case's table or its scene's), at half size, with refnpr's own G-buffer uploaded as
  textures and the case's style exported by ``refnpr.kit.styles.export_style`` into a
  ``case.json`` read by ``refnpr_glsl.kit_io.Case``: the GLSL ``shade`` is compared per sample
  with ``HalftoneStyle.shade`` on the same G-buffer (isolates the shading from rasterization).
  Variants the goldens do not cover (c = "auto", mip = "per_level", lod_bias, sample_lod,
  anisotropic dither, ink/paper colours) run the same way.
* ``test_kit_cases``: the exported kit cases rendered by the backend driver (``python -m
  refnpr_glsl``) and compared by refnpr's kit checker with each case's own tolerance;
  ``KNOWN_FAILURES`` lists the cases that do not pass, with the reason.
"""

from __future__ import annotations

import dataclasses
from types import SimpleNamespace

import numpy as np
import pytest

moderngl = pytest.importorskip("moderngl")

from refnpr.scenes import load_scene  # noqa: E402
from refnpr.styles import style_from_spec  # noqa: E402

from ._harness import (  # noqa: E402
    assert_passed,
    case_params,
    export_cases,
    isolated,
    render_and_check,
    style_cases,
    write_case,
)

STYLE = "halftone"

#: Per-sample agreement of the isolated pass on linear RGBA: samples over 2/255. With float32
#: arithmetic the binary threshold may flip a sample where screen + I - 1 is within float32
#: rounding of 0 (the Fig. 2 chart puts a diagonal of samples there: 0.13% flip); everything
#: else agrees to ~1e-4 (smooth ramps scale the rounding by c), float64 to ~1e-6.
THRESHOLD = 2.0 / 255.0
MAX_FRAC_OVER = 0.002

#: Kit cases (refnpr kit check, own tolerance) known not to pass, with the reason.
KNOWN_FAILURES: dict[str, str] = {}

CASES = style_cases(STYLE)
NAMES = [c.name for c in CASES]


def _base_style(case, overrides: dict | None = None):
    scene = load_scene(case.scene)
    spec = case.style if case.style is not None else scene.style
    spec = dict(spec) if isinstance(spec, dict) else {"name": spec}
    spec.pop("contours", None)  # the contour layer is the driver's, not this pass
    spec.update(overrides or {})
    return scene, style_from_spec(spec)


def _isolated(gl, tmp_path, case, overrides=None, *, scale: float = 0.5, edit=None):
    """(GLSL shade, refnpr shade) per sample, (nH, nW, 4) float32, on refnpr's G-buffer."""
    from refnpr_glsl.styles import halftone as glsl_halftone

    scene, style = _base_style(case, overrides)
    w, h = max(8, int(case.width * scale)), max(8, int(case.height * scale))
    one = SimpleNamespace(name=case.name, scene=scene, style=style)
    return isolated(gl, one, tmp_path, w, h, case.spp, glsl_halftone, edit)


def _frac_over(got: np.ndarray, ref: np.ndarray) -> float:
    return float(np.mean(np.any(np.abs(got - ref) > THRESHOLD, axis=-1)))


def test_every_halftone_golden_case_is_found():
    # the scene-styled cases (no [case.style]) count too: default-render, fig4/5/6/7 smooth
    assert len(NAMES) >= 17, NAMES
    assert "default-render" in NAMES and "halftone-fig5-teapot-engraving-smooth" in NAMES


@pytest.mark.parametrize("name", NAMES)
def test_shade_matches_refnpr_per_sample(gl, tmp_path, name):
    case = next(c for c in CASES if c.name == name)
    got, ref = _isolated(gl, tmp_path, case)
    assert got.shape == ref.shape
    assert np.array_equal(got[..., 3], ref[..., 3]), "coverage (alpha) differs"
    frac = _frac_over(got, ref)
    assert frac <= MAX_FRAC_OVER, f"{name}: {frac:.5f} of samples differ by more than 2/255"


VARIANTS = {
    "c-auto": ("halftone-fig4-sphere-hatching-binary", {"threshold": "smooth", "c": "auto"}),
    "per-level-lod-bias": (
        "halftone-fig6-knot-hatching-smooth",
        {"mip": "per_level", "lod_bias": 0.7},
    ),
    "sample-lod-spp4": ("default-render", {"sample_lod": True}),
    "aniso-dither-colours": (
        "halftone-fig1-sphere-dither-smooth-centred",
        {"anisotropy": 8, "specular": True, "ink": [0.2, 0.1, 0.0], "paper": [0.9, 0.9, 0.7]},
    ),
    "room-per-level-binary": (
        "halftone-fig7-room-bricks-smooth",
        {"threshold": "binary", "mip": "per_level"},
    ),
}


@pytest.mark.parametrize("variant", sorted(VARIANTS))
def test_shade_variants_match_refnpr(gl, tmp_path, variant):
    name, overrides = VARIANTS[variant]
    case = next(c for c in CASES if c.name == name)
    got, ref = _isolated(gl, tmp_path, case, overrides, scale=0.4)
    assert np.array_equal(got[..., 3], ref[..., 3])
    frac = _frac_over(got, ref)
    assert frac <= MAX_FRAC_OVER, f"{variant}: {frac:.5f} of samples differ by more than 2/255"


def test_double_precision_removes_the_binary_ties(gl, tmp_path, monkeypatch):
    """The Fig. 2 chart rendered square is symmetric about x = y, where screen + I = 1 ties
    exactly (the golden case is 256 x 255 so that no pixel sits on it): there float32 rounding
    flips samples that refnpr's float64 decides; float64 shader arithmetic reproduces refnpr bit
    for bit. This is what a shader engineer sees on any exact binary tie."""
    case = next(c for c in CASES if c.name == "halftone-fig2-threshold-binary")
    case = dataclasses.replace(case, params={**case.params, "height": case.width})
    got32, ref = _isolated(gl, tmp_path / "f", case, scale=1.0)
    monkeypatch.setenv("REFNPR_GLSL_HALFTONE_PRECISION", "double")
    got64, ref64 = _isolated(gl, tmp_path / "d", case, scale=1.0)
    assert _frac_over(got64, ref64) == 0.0
    assert np.max(np.abs(got64 - ref64)) < 1e-5
    assert _frac_over(got32, ref) > 0.0  # the float32 flips are real (else drop this test)


def test_export_resolves_every_parameter(tmp_path):
    """The exporter's params: per-object screens, uv scales and maps as the style uses them."""
    from refnpr.kit.styles import export_style, unresolved

    case = next(c for c in CASES if c.name == "halftone-fig7-room-bricks-smooth")
    scene, style = _base_style(case)
    exp = export_style(style, scene, tmp_path, width=32, height=24, spp=1)
    objs = {o["name"]: o for o in exp.params["objects"]}
    assert [o["name"] for o in exp.params["objects"]] == [o.name for o in scene.objects]
    assert objs["floor"]["uv_scale"] == [20.0, 1.0] and objs["floor"]["screen"]["direction"]
    assert objs["back_wall"]["screen"]["role"] == objs["left_wall"]["screen"]["role"]
    assert objs["back_wall"]["screen"]["normals_role"] in exp.textures
    assert objs["back_wall"]["indication_scale"] == [1.0, 2.0]
    for o in exp.params["objects"]:
        for role in (o["screen"]["role"], o["screen"]["normals_role"], o["indication_role"]):
            if role is not None:
                entry = exp.textures[role]
                assert all((tmp_path / f).is_file() for f in entry["levels"])
    screen = style.screen_for(style.object_specs(scene)[1], None)
    wall = exp.textures[objs["back_wall"]["screen"]["role"]]
    assert len(wall["levels"]) == screen.pyramid.n_levels
    assert unresolved(STYLE, exp.params) == []

    dither = next(c for c in CASES if c.name == "halftone-fig1-sphere-dither-smooth-centred")
    scene, style = _base_style(dither, {"c": "auto", "centred": False, "sample_lod": True})
    exp = export_style(style, scene, tmp_path / "d", width=32, height=24, spp=4)
    assert exp.params["c"] is None and exp.params["c_mode"] == "fwidth"
    assert exp.params["lod_offset"] == pytest.approx(-1.0)  # sample_lod with 2 x 2 samples
    (obj,) = exp.params["objects"]
    assert obj["equalize"] and obj["per_level"]
    lut = exp.textures[obj["tone_lut_role"]]
    n_levels = len(exp.textures[obj["screen"]["role"]]["levels"])
    assert lut["shape"][0] == n_levels and lut["shape"][1] >= 2
    assert unresolved(STYLE, exp.params) == []


def test_wrong_params_fail_loudly(gl, tmp_path):
    case = next(c for c in CASES if c.name == "halftone-fig2-threshold-smooth")
    scene, style = _base_style(case)
    from refnpr_glsl.kit_io import Case
    from refnpr_glsl.styles import halftone as glsl_halftone

    kit_case = Case(write_case(tmp_path, case.name, scene, style, 16, 16, 1))
    kit_case.data["style"]["params"]["show"] = "sparkles"
    with pytest.raises(ValueError, match="show"):
        glsl_halftone.shade(gl, kit_case, {"mesh_id": None}, (16, 16))


def test_shade_detects_a_wrong_screen(gl, tmp_path):
    """The comparison can fail: a kit whose screen texture is perturbed gives other samples."""

    def darker(kit_case):
        real_texture = kit_case.texture
        kit_case.texture = lambda role: [np.clip(a * 0.7, 0, 1) for a in real_texture(role)]

    case = next(c for c in CASES if c.name == "halftone-fig1-sphere-dither-binary")
    case = dataclasses.replace(case, params={**case.params, "width": 64, "height": 64, "spp": 1})
    got, ref = _isolated(gl, tmp_path, case, scale=1.0, edit=darker)
    assert _frac_over(got, ref) > 0.01


# -- the whole pipeline: export, render with the driver, kit check ----------------------------
@pytest.fixture(scope="module")
def halftone_results(tmp_path_factory):
    return render_and_check(export_cases(tmp_path_factory, STYLE, NAMES), NAMES)


@pytest.mark.parametrize("name", case_params(NAMES, KNOWN_FAILURES))
def test_kit_cases(halftone_results, name):
    assert_passed(halftone_results, name)


def test_known_failures_are_halftone_cases():
    assert set(KNOWN_FAILURES) <= set(NAMES)
