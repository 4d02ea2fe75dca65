"""The GLSL backend's tamiss style against refnpr (TAMISS: gather, hash, blend, fit, extrude).

Two levels:

* ``test_shade_matches_refnpr``: refnpr's own G-buffer of the case (float64, rounded to float32
  as the backend's textures hold it) uploaded as textures; the backend's ``shade`` against
  refnpr's ``TamissStyle.shade`` on the SAME rounded G-buffer, per sample. This isolates the
  style's GPU passes from rasterization differences. It also checks that the gathered fragment
  and stroke counts agree exactly.
* ``test_case_passes_kit_check``: the whole backend (K3's rasterizer and driver) on the exported
  case, compared with ``refnpr kit check``'s comparison at the case's own tolerance, for every
  golden case of the tamiss style; :data:`KNOWN_FAILURES` lists the cases that do not pass, with
  the reason.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

moderngl = pytest.importorskip("moderngl")

from refnpr.golden import load_suite  # noqa: E402
from refnpr.raster import rasterize  # noqa: E402
from refnpr.scenes import load_scene  # noqa: E402
from refnpr.styles import ShadeContext, style_from_spec  # noqa: E402

ROOT = Path(__file__).resolve().parents[2]
SUITE = ROOT / "golden" / "suite.toml"

#: Golden cases of the tamiss style (style name "tamiss" in golden/*.toml).
CASES = [c.name for c in load_suite(SUITE) if c.style and c.style.get("name") == "tamiss"]

#: Cases of the full backend that do not pass their own tolerance, and why (docs/kit.md).
KNOWN_FAILURES: dict[str, str] = {}

#: Per-sample tolerance of the isolated shading test (straight RGBA, linear).
SHADE_ATOL = 2.0 / 255


def _case(name):
    return next(c for c in load_suite(SUITE) if c.name == name)


@pytest.fixture(scope="module")
def kit(tmp_path_factory):
    """A kit of the tamiss cases exported by ``refnpr kit export``."""
    from refnpr.kit import export_kit

    out = tmp_path_factory.mktemp("kit_tamiss")
    export_kit(out, suite=SUITE, only=CASES)
    return out


def _base(style):
    return style.base if style.name == "contoured" else style


def _rounded_gbuffer(case):
    """refnpr's G-buffer of the case and a copy with every float channel rounded to float32."""
    scene = load_scene(case.scene)
    style = _base(style_from_spec(dict(case.style)))
    gb = rasterize(
        scene, scene.camera, case.width, case.height, sorted(style.requires(scene)), case.spp,
        **style.raster_options(scene),
    )  # fmt: skip
    for k, a in gb.channels.items():
        if a.dtype.kind == "f":
            gb.channels[k] = a.astype(np.float32).astype(np.float64)
    return scene, style, gb


def _upload(gl, gb):
    tex = {}
    for k, a in gb.channels.items():
        if a.dtype.kind == "f":
            tex[k] = gl.texture_from_array(np.ascontiguousarray(a, dtype=np.float32), dtype="f4")
        else:
            tex[k] = gl.texture_from_array(np.ascontiguousarray(a, dtype=np.int32), dtype="i4")
    return tex


@pytest.mark.parametrize("name", CASES)
def test_shade_matches_refnpr(gl, kit, name):
    from refnpr_glsl.kit_io import Case
    from refnpr_glsl.styles import tamiss as glsl_tamiss

    case = _case(name)
    scene, style, gb = _rounded_gbuffer(case)
    ctx = ShadeContext(gb, scene)
    result = style.run(ctx)
    ref = style.shade(ctx)
    kcase = Case(kit / name / "case.json")
    tex = _upload(gl, gb)
    size = (gb["tri_id"].shape[1], gb["tri_id"].shape[0])
    out = glsl_tamiss.shade(gl, kcase, tex, size)
    got = gl.read(out)
    stats = glsl_tamiss.shade.last_stats
    assert stats["fragments"] == len(result.fragments)
    assert stats["strokes"] == len(result.aggregates)
    diff = np.abs(got.astype(np.float64) - ref.astype(np.float64))
    frac = float(np.mean(np.any(diff > SHADE_ATOL, axis=-1)))
    print(f"{name}: max |diff| {diff.max():.3g}, frac over {SHADE_ATOL:.4f}: {frac:.2e}")
    assert frac <= 5e-4, f"{name}: {frac:.2e} of samples differ by more than {SHADE_ATOL}"


@pytest.fixture(scope="module")
def renders(kit, tmp_path_factory):
    """The whole backend (``python -m refnpr_glsl``, analytic derivatives) on the tamiss kit."""
    import subprocess
    import sys

    out = tmp_path_factory.mktemp("renders_tamiss")
    proc = subprocess.run(
        [sys.executable, "-m", "refnpr_glsl", str(kit), str(out)],
        capture_output=True,
        text=True,
        timeout=1800,
    )
    assert proc.returncode == 0, proc.stdout + proc.stderr
    return out


@pytest.fixture(scope="module")
def checks(kit, renders):
    from refnpr.kit.check import check_kit

    return {c.name: c for c in check_kit(kit, renders)}


@pytest.mark.parametrize("name", CASES)
def test_case_passes_kit_check(checks, name):
    check = checks[name]
    print(f"{name}: {json.dumps(check.metrics)}")
    if name in KNOWN_FAILURES:
        assert not check.passed, f"{name} passes now: remove it from KNOWN_FAILURES"
        return
    assert check.status == "ok", check.message
    assert check.passed, f"{name}: {check.message}"


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
def test_variant_matches_refnpr(gl, kit, tmp_path, variant):
    import dataclasses
    import shutil

    from refnpr_glsl.kit_io import Case
    from refnpr_glsl.styles import tamiss as glsl_tamiss

    from refnpr.kit.styles import export_style
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
    case_dir = tmp_path / variant
    shutil.copytree(kit / "tamiss-teapot", case_dir)
    shutil.rmtree(case_dir / "textures")
    exp = export_style(style, scene, case_dir, width=width, height=height, spp=spp)
    kcase = Case(case_dir / "case.json")
    kcase.data["style"]["params"] = exp.params
    kcase.data["textures"] = exp.textures
    kcase.data["spp"] = spp
    kcase.data["lights"] = [
        {"kind": "point", "position": list(li.position), "color": list(li.color)}
        if li.kind == "point"
        else {"kind": "directional", "direction": list(li.direction), "color": list(li.color)}
        for li in scene.lights
    ]
    gb = rasterize(
        scene, scene.camera, width, height, sorted(style.requires(scene)), spp,
        **style.raster_options(scene),
    )  # fmt: skip
    for k, a in gb.channels.items():
        if a.dtype.kind == "f":
            gb.channels[k] = a.astype(np.float32).astype(np.float64)
    ctx = ShadeContext(gb, scene)
    result = style.run(ctx)
    ref = style.shade(ctx)
    out = glsl_tamiss.shade(gl, kcase, _upload(gl, gb), (width * gb.n, height * gb.n))
    got = gl.read(out)
    assert glsl_tamiss.shade.last_stats["fragments"] == len(result.fragments)
    assert glsl_tamiss.shade.last_stats["strokes"] == len(result.aggregates)
    diff = np.abs(got.astype(np.float64) - ref.astype(np.float64))
    frac = float(np.mean(np.any(diff > SHADE_ATOL, axis=-1)))
    print(
        f"{variant}: {len(result.fragments)} fragments, max |diff| {diff.max():.3g}, frac {frac:.2e}"
    )
    assert frac <= 5e-4, f"{variant}: {frac:.2e} of samples differ by more than {SHADE_ATOL}"


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
