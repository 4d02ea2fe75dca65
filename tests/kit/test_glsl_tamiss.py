"""The GLSL backend's tamiss style against refnpr (TAMISS: gather, hash, blend, fit, extrude).

Two levels:

* ``test_shade_matches_refnpr``: refnpr's own G-buffer of the case (float64, rounded to float32
  as the backend's textures hold it) uploaded as textures; the backend's ``shade`` against
  refnpr's ``TamissStyle.shade`` on the SAME rounded G-buffer, per sample. This isolates the
  style's GPU passes from rasterization differences. It also checks that the gathered fragment
  and stroke counts agree exactly.
* ``test_case_passes_kit_check``: the whole backend (its rasterizer and driver) on the exported
  case, compared with ``refnpr kit check``'s comparison at the case's own tolerance, for every
  golden case of the tamiss style; :data:`KNOWN_FAILURES` lists the cases that do not pass, with
  the reason.
"""

from __future__ import annotations

import dataclasses
import json

import numpy as np
import pytest

moderngl = pytest.importorskip("moderngl")

from refnpr.raster import rasterize  # noqa: E402
from refnpr.scenes import load_scene  # noqa: E402
from refnpr.styles import ShadeContext, style_from_spec  # noqa: E402

from ._harness import (  # noqa: E402
    assert_passed,
    case_params,
    export_cases,
    render_and_check,
    shade_pass,
    style_cases,
    write_case,
)

#: Golden cases of the tamiss style.
CASES = [c.name for c in style_cases("tamiss")]

#: Cases of the full backend that do not pass their own tolerance, and why (docs/kit.md).
KNOWN_FAILURES: dict[str, str] = {}

#: Per-sample tolerance of the isolated shading test (straight RGBA, linear).
SHADE_ATOL = 2.0 / 255


@pytest.fixture(scope="module")
def kit(tmp_path_factory):
    """A kit of the tamiss cases exported by ``refnpr kit export``."""
    return export_cases(tmp_path_factory, "tamiss", CASES)


def _rounded_gbuffer(scene, style, width, height, spp):
    """refnpr's G-buffer with every float channel rounded to float32 (as the textures hold it)."""
    gb = rasterize(
        scene, scene.camera, width, height, sorted(style.requires(scene)), spp,
        **style.raster_options(scene),
    )  # fmt: skip
    for k, a in gb.channels.items():
        if a.dtype.kind == "f":
            gb.channels[k] = a.astype(np.float32).astype(np.float64)
    return gb


def _check_shade(gl, kit_case, scene, style, gb, label: str) -> None:
    """The backend's shade against refnpr's on ``gb``: the same fragment and stroke counts, and
    at most 5e-4 of the samples more than SHADE_ATOL apart."""
    from refnpr_glsl.styles import tamiss as glsl_tamiss

    ctx = ShadeContext(gb, scene)
    result = style.run(ctx)
    ref = style.shade(ctx)
    got = shade_pass(gl, glsl_tamiss, kit_case, gb)
    stats = glsl_tamiss.shade.last_stats
    assert stats["fragments"] == len(result.fragments)
    assert stats["strokes"] == len(result.aggregates)
    diff = np.abs(got.astype(np.float64) - ref.astype(np.float64))
    frac = float(np.mean(np.any(diff > SHADE_ATOL, axis=-1)))
    print(
        f"{label}: {len(result.fragments)} fragments, max |diff| {diff.max():.3g}, frac {frac:.2e}"
    )
    assert frac <= 5e-4, f"{label}: {frac:.2e} of samples differ by more than {SHADE_ATOL}"


@pytest.mark.parametrize("name", CASES)
def test_shade_matches_refnpr(gl, kit, name):
    from refnpr_glsl.kit_io import Case

    case = next(c for c in style_cases("tamiss") if c.name == name)
    scene = load_scene(case.scene)
    style = style_from_spec(dict(case.style))
    style = style.base if style.name == "contoured" else style
    gb = _rounded_gbuffer(scene, style, case.width, case.height, case.spp)
    _check_shade(gl, Case(kit / name / "case.json"), scene, style, gb, name)


@pytest.fixture(scope="module")
def checks(kit):
    """The whole backend (``python -m refnpr_glsl``, analytic derivatives) on the tamiss kit."""
    return render_and_check(kit, CASES)


@pytest.mark.parametrize("name", case_params(CASES, KNOWN_FAILURES))
def test_case_passes_kit_check(checks, name):
    print(f"{name}: {json.dumps(checks[name].metrics)}")
    assert_passed(checks, name)


def test_known_failures_are_cases():
    assert set(KNOWN_FAILURES) <= set(CASES)


def test_unsupported_params_are_refused(gl, kit):
    """What the backend does not implement fails with the parameter named, never silently."""
    from refnpr_glsl.kit_io import Case
    from refnpr_glsl.styles import tamiss as glsl_tamiss

    case = Case(kit / "tamiss-teapot" / "case.json")
    case.data["style"]["params"]["dtype"] = "float64"
    with pytest.raises(ValueError, match="dtype"):
        glsl_tamiss.shade(gl, case, {}, (4, 4))


#: Options no golden case exercises, each checked per sample against refnpr (small frames).
VARIANTS = {
    "flat-derivatives": {"derivatives": "flat"},
    "no-chart-orientation": {"orient_charts": False},
    "constant-tone": {"constant_tone": 0.6},
    "extent-visible": {"extent": "visible"},
    "extent-range": {"extent": "range", "max_stretch": None},
    "extent-stroke": {"extent": "stroke"},
    "dry-brush-jitter-wobble": {"brush": "dry", "end_jitter": 0.3, "wobble": 0.7},
    "paper-and-ink": {"paper": [1.0, 0.95, 0.9], "ink": [0.2, 0.1, 0.05]},
    "show-levels": {"show": "levels", "directions": ["u", 30.0, "v"]},
    "spp4": {"_spp": 4},
    "hashed": {"aggregation": "hashed"},
    "hashed-small-table": {"aggregation": "hashed", "table_size": 1024, "warmup_frames": 0},
    "hashed-warm-tiny-table": {"aggregation": "hashed", "table_size": 256, "warmup_frames": 1},
    "point-light": {"_point_light": True},
}


@pytest.mark.parametrize("variant", sorted(VARIANTS))
def test_variant_matches_refnpr(gl, tmp_path, variant):
    from refnpr_glsl.kit_io import Case

    from refnpr.scenes import Light

    opts = dict(VARIANTS[variant])
    spp = opts.pop("_spp", 1)
    point = opts.pop("_point_light", False)
    width, height = 160, 120
    scene = load_scene("tamiss_teapot")
    if point:
        lights = (Light(kind="point", position=(2.0, -3.0, 4.0), color=(1.0, 1.0, 1.0)),)
        scene = dataclasses.replace(scene, lights=lights)
    params = {"directions": ["u", "v"], "period": 4.0, "density": 1.0, "taper": 0.25} | opts
    style = style_from_spec({"name": "tamiss", **params})
    kit_case = Case(write_case(tmp_path, variant, scene, style, width, height, spp))
    gb = _rounded_gbuffer(scene, style, width, height, spp)
    _check_shade(gl, kit_case, scene, style, gb, variant)


def test_backend_style_imports_without_refnpr():
    """The GLSL tamiss pass reads only the kit: it imports with refnpr unimportable."""
    import subprocess
    import sys

    code = (
        "import sys; sys.modules['refnpr'] = None; "
        "import refnpr_glsl.styles.tamiss as t; print(t.shader_source('fit.comp')[:8])"
    )
    proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120)
    assert proc.returncode == 0, proc.stderr
    assert proc.stdout.startswith("#version")
