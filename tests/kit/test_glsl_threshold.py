"""The GLSL backend's ``threshold`` style (Veryovka 2002) against refnpr.

Two levels, so that a failure says where it comes from:

1. **Shading in isolation**: refnpr's own G-buffer uploaded as textures, the backend's
   ``shade()`` (reading only the exported kit case) against refnpr's ``ThresholdStyle.shade`` per
   sample, for every golden case of the style and for variants that cover the options the
   golden cases do not use (PCF grids, trilinear PCF, stipple PCF, noise with analytic
   filtering, no multiscale, a constant specular threshold, n > 1), with the shader's "real"
   arithmetic in float32 (the default, as a GPU shader) and in double.
2. **End to end**: ``python -m refnpr_glsl KIT OUT`` (the backend's own rasterizer, resolve and
   contours) and ``refnpr.kit.check.check_kit`` with each case's own tolerance. Every case not in
   ``KNOWN_FAILURES`` must pass; every case in it must still fail (so the table stays true).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

moderngl = pytest.importorskip("moderngl")  # the extra "glsl"; CI installs it

from refnpr.golden import load_suite  # noqa: E402
from refnpr.scenes import load_scene  # noqa: E402

from ._harness import SUITE, render_and_check, shade_pass, style_cases  # noqa: E402

#: End-to-end failures with their cause (copied into docs/kit.md). Empty: every case passes.
KNOWN_FAILURES: dict[str, str] = {}

#: Options the golden cases leave out, on small images (style tables as in a suite file).
VARIANTS = {
    "thr-var-image-pcf4-trilinear": (
        "veryovka_room",
        '{ name = "threshold", source = "image", filter = "pcf", samples = 4, mip = "trilinear",'
        " lod_bias = 0.5 }",
        4,
    ),
    "thr-var-image-pcf9-tone": (
        "veryovka_room",
        '{ name = "threshold", source = "image", filter = "pcf", samples = 9, tone_correct = true,'
        " n = 2 }",
        1,
    ),
    "thr-var-stipple-pcf-lattice": (
        "sphere",
        '{ name = "threshold", source = "stipple", period = 5.0, uv_scale = 8.0, filter = "pcf",'
        " samples = 4, jitter = 0.0, multiscale = false }",
        1,
    ),
    "thr-var-lines-pcf-noise-cross": (
        "sphere",
        '{ name = "threshold", source = "lines", period = 6.0, uv_scale = [4.0, 2.0], filter = "pcf",'
        ' samples = 4, noise = 0.3, noise_seed = 7, directions = [30.0, -60.0, "v"] }',
        1,
    ),
    "thr-var-analytic-noise-n3": (
        "teapot",
        '{ name = "threshold", source = "lines", period = 5.0, filter = "analytic", noise = 0.25,'
        " n = 3, specular_threshold = 0.7, strength = 0.8, noise_seed = -3 }",
        4,
    ),
    "thr-var-lines-flat-scale": (
        "torus_knot",
        '{ name = "threshold", source = "lines", period = 4.0, multiscale = false, uniform = true,'
        " tone_fade = [0.2, 0.1] }",
        1,
    ),
}


def _base_style(case, scene):
    """The style refnpr renders ``case`` with, its contour layer unwrapped."""
    from refnpr.kit.export import _style_of

    style = _style_of(case, scene)
    return style.base if style.name == "contoured" else style


def _textured(case) -> bool:
    """Whether ``case`` samples texture pyramids (source "image" or a bump map)."""
    base = _base_style(case, load_scene(case.scene))
    return base.p.source == "image" or base.p.bump is not None


CASES = [c.name for c in style_cases("threshold")]
TEXTURED_CASES = [c.name for c in style_cases("threshold") if _textured(c)]


@pytest.fixture(scope="module")
def threshold_kit(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """The golden threshold cases and the variants, exported (refnpr kit export)."""
    from refnpr.kit import export_kit

    d = tmp_path_factory.mktemp("threshold_kit") / "kit"  # renders go beside it
    export_kit(d, suite=SUITE, only=CASES)
    suite = d / "variants.toml"
    lines = ["[defaults]\nwidth = 96\nheight = 64\n"]
    for name, (scene, style, spp) in VARIANTS.items():
        lines.append(
            f'[[case]]\nname = "{name}"\nscene = "{scene}"\nstyle = {style}\nspp = {spp}\n'
        )
    suite.write_text("\n".join(lines))
    export_kit(d, suite=suite)
    return d


def shade_both(
    gl,
    kit: Path,
    name: str,
    case_json: Path | None = None,
    precision: str = "float",
    sampling: str = "shader",
) -> tuple[np.ndarray, np.ndarray, float]:
    """refnpr's and the backend's per-sample RGBA on refnpr's own G-buffer, and the case's
    ``max_frac_over`` (``case_json``: the backend reads this case file instead; ``precision``:
    the shader's arithmetic; ``sampling``: its texture filtering)."""
    from refnpr_glsl.kit_io import Case
    from refnpr_glsl.styles import threshold as glsl_threshold

    from refnpr.raster import rasterize
    from refnpr.styles.base import ShadeContext

    suite = SUITE if name in CASES else kit / "variants.toml"
    case = next(c for c in load_suite(suite) if c.name == name)
    scene = load_scene(case.scene)
    base = _base_style(case, scene)
    channels = sorted(base.requires(scene))
    size = (case.width, case.height, channels, case.spp)
    gb = rasterize(scene, scene.camera, *size, **base.raster_options(scene))
    ref = np.asarray(base.shade(ShadeContext(gb, scene)), dtype=np.float32)
    kit_case = Case(case_json or kit / name / "case.json")
    got = shade_pass(gl, glsl_threshold, kit_case, gb, precision=precision, sampling=sampling)
    return ref, got, float(case.max_frac_over)


def test_every_threshold_case_is_covered():
    """The suite has threshold cases and every known failure names one of them."""
    assert len(CASES) >= 20, CASES
    assert 5 <= len(TEXTURED_CASES) < len(CASES), TEXTURED_CASES
    assert set(KNOWN_FAILURES) <= set(CASES) | set(VARIANTS)


@pytest.mark.parametrize("precision", ["float", "double"])
@pytest.mark.parametrize("name", CASES + sorted(VARIANTS))
def test_shade_matches_refnpr_per_sample(gl, threshold_kit: Path, name: str, precision: str):
    """On refnpr's G-buffer the backend's shading (float32 or double arithmetic) matches refnpr
    per sample: no more samples than the case's max_frac_over differ by more than 2/255, the
    others by less than 1e-3, and alpha is identical."""
    ref, got, max_frac = shade_both(gl, threshold_kit, name, precision=precision)
    assert got.shape == ref.shape
    np.testing.assert_array_equal(got[..., 3], ref[..., 3])
    over = np.abs(got[..., :3] - ref[..., :3]).max(axis=-1) > 2.0 / 255
    assert over.mean() <= max_frac, (
        f"{name}: {int(over.sum())} of {over.size} samples differ by > 2/255 "
        f"(max |diff| {np.abs(got - ref).max():.3g})"
    )
    assert np.abs(got - ref)[~over].max(initial=0.0) < 1e-3


@pytest.mark.parametrize("name", TEXTURED_CASES)
def test_hardware_sampling_matches_refnpr_per_sample(gl, threshold_kit: Path, name: str):
    """Texture pyramids sampled by the sampler hardware (textureLod on the kit's mip levels)
    instead of the shader's own filtering: still within the case's budget per sample."""
    ref, got, max_frac = shade_both(gl, threshold_kit, name, sampling="hardware")
    np.testing.assert_array_equal(got[..., 3], ref[..., 3])
    over = np.abs(got[..., :3] - ref[..., :3]).max(axis=-1) > 2.0 / 255
    assert over.mean() <= max_frac, f"{name}: {int(over.sum())} samples differ by > 2/255"


def test_shade_detects_a_wrong_parameter(gl, threshold_kit: Path, tmp_path: Path):
    """The comparison can fail: the backend given a kit case with another line period no
    longer matches refnpr; an unknown precision is refused."""
    import json
    import shutil

    name = "veryovka-fig4-sphere-cross"
    dst = tmp_path / name
    shutil.copytree(threshold_kit / name, dst)
    data = json.loads((dst / "case.json").read_text())
    data["style"]["params"]["period"] = 9.0
    (dst / "case.json").write_text(json.dumps(data))
    ref, got, max_frac = shade_both(gl, threshold_kit, name, dst / "case.json")
    over = np.abs(got[..., :3] - ref[..., :3]).max(axis=-1) > 2.0 / 255
    assert over.mean() > 10 * max_frac
    from refnpr_glsl.kit_io import Case
    from refnpr_glsl.styles import threshold as glsl_threshold

    with pytest.raises(ValueError, match="precision: expected one of"):
        glsl_threshold.fragment_source(Case(dst / "case.json"), precision="half")
    with pytest.raises(ValueError, match="sampling: expected one of"):
        glsl_threshold.fragment_source(Case(dst / "case.json"), sampling="bilinear")


def test_end_to_end_kit_check(threshold_kit: Path):
    """The backend renders every threshold case (and variant) from the kit alone and each passes
    its own tolerance under ``refnpr kit check`` (except the listed known failures, which must
    fail)."""
    from refnpr.kit.check import format_table

    names = CASES + sorted(VARIANTS)
    results = [r for n, r in render_and_check(threshold_kit, names).items() if n in names]
    print(format_table(results))
    assert {r.name for r in results} == set(names)
    wrong = [f"{r.name}: {r.message}" for r in results if r.passed == (r.name in KNOWN_FAILURES)]
    assert not wrong, "\n".join(wrong)
