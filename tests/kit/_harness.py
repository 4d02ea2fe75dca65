"""What the per-style GLSL tests share: the golden cases of a style, a style pass run on refnpr's
own G-buffer without the driver (isolates a style's shading from rasterization), and the
backend driver run on an exported kit and judged by ``refnpr kit check``."""

from __future__ import annotations

import dataclasses
import functools
import json
import os
import subprocess
import sys
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest

from refnpr.golden import DEFAULT_SUITE, load_suite
from refnpr.raster import rasterize
from refnpr.scenes import load_scene
from refnpr.styles import ShadeContext, style_from_spec

SUITE = DEFAULT_SUITE


@functools.cache
def _styled_cases() -> list:
    from refnpr.kit.export import _style_of
    from refnpr.kit.styles import style_name

    return [
        (c, style_name(_style_of(c, load_scene(c.scene))))
        for c in load_suite(SUITE)
        if c.kind == "image"
    ]


def style_cases(style: str) -> list:
    """The golden image cases rendered with ``style`` (the case's style, else its scene's;
    a contour layer unwrapped)."""
    return [c for c, name in _styled_cases() if name == style]


def point_lit(scene: str, offset, color, *more):
    """``scene`` lit by a point light at its eye + ``offset`` (and the lights ``more``)."""
    from refnpr.scenes.scene import Light

    s = load_scene(scene)
    eye = np.asarray(s.camera.eye)
    light = Light(kind="point", position=tuple(eye + offset), color=color)
    return dataclasses.replace(s, lights=(light, *more))


def write_case(case_dir: Path, name: str, scene, style, width: int, height: int, spp: int) -> Path:
    """A case.json of ``style`` on ``scene`` made by the kit's own exporters (no expected image),
    for ``refnpr_glsl.kit_io.Case``."""
    from refnpr.kit.export import _base
    from refnpr.kit.scene_export import objects_entry
    from refnpr.kit.styles import export_style, style_name

    exp = export_style(style, scene, case_dir, width=width, height=height, spp=spp)
    size = dict(width=width, height=height, spp=spp)
    data = _base(SimpleNamespace(name=name, description="", kind="image", **size), scene)
    data["objects"] = objects_entry(scene, case_dir, exp.vertex_attributes)
    data["style"] = {"name": style_name(style), "params": exp.params}
    data["channels"] = sorted(style.requires(scene))
    data["textures"] = exp.textures
    data["derived"] = exp.derived
    path = case_dir / "case.json"
    path.write_text(json.dumps(data))
    return path


def upload_gbuffer(gl, gb) -> dict:
    """refnpr's G-buffer channels as textures (float32 / int32, array layout)."""
    out = {}
    for name in gb.channels:
        a = np.asarray(gb[name])
        if a.dtype.kind in "iub":
            out[name] = gl.texture_from_array(a.astype(np.int32), dtype="i4")
        else:
            out[name] = gl.texture_from_array(a.astype(np.float32), dtype="f4")
    return out


def shade_pass(gl, module, case, gb, **options) -> np.ndarray:
    """``module.shade`` of a ``refnpr_glsl.kit_io.Case`` on refnpr's G-buffer ``gb``, read back."""
    textures = upload_gbuffer(gl, gb)
    try:
        out = module.shade(gl, case, textures, case.sample_size, **options)
        got = gl.read(out)
        out.release()
    finally:
        for t in textures.values():
            t.release()
    return got


def isolated(gl, case, tmp_path: Path, width: int, height: int, spp: int, module, edit=None):
    """(GLSL result, refnpr result), both (nH, nW, 4) float32, for one golden case's style on
    refnpr's G-buffer of the case's scene at ``width`` x ``height`` (``case.scene``: a scene
    name or a Scene; ``case.style``: a style table or a Style; ``edit``: called with the
    ``Case`` before shading)."""
    from refnpr_glsl.kit_io import Case

    scene = load_scene(case.scene) if isinstance(case.scene, str) else case.scene
    style = style_from_spec(case.style)
    inner = style.base if style.name == "contoured" else style
    channels = sorted(inner.requires(scene))
    gb = rasterize(scene, scene.camera, width, height, channels, spp, **inner.raster_options(scene))
    ref = np.asarray(inner.shade(ShadeContext(gb, scene)), dtype=np.float32)
    kit_case = Case(write_case(tmp_path, case.name, scene, style, width, height, spp))
    if edit is not None:
        edit(kit_case)
    return shade_pass(gl, module, kit_case, gb), ref


def render_and_check(kit: Path, names: list[str], derivatives: str = "analytic", env=None) -> dict:
    """Render ``names`` of ``kit`` with the backend driver (a subprocess, as CI does) and check
    them with ``refnpr kit check``'s comparator: name -> CaseCheck, plus ``"_driver_log"``."""
    from refnpr.kit.check import check_kit

    renders = kit.parent / f"renders-{derivatives}"
    run = subprocess.run(
        [sys.executable, "-m", "refnpr_glsl", str(kit), str(renders), "--only", *names, "-q",
         "--derivatives", derivatives],
        capture_output=True,
        text=True,
        timeout=1800,
        env=None if env is None else {**os.environ, **env},
    )  # fmt: skip
    assert run.returncode == 0, run.stdout[-3000:] + run.stderr[-3000:]
    results = check_kit(kit, renders, json_path=kit.parent / f"check-{derivatives}.json")
    out: dict = {r.name: r for r in results if r.name in names}
    out["_driver_log"] = run.stdout + run.stderr
    return out


def case_params(names: list[str], known: dict[str, str]) -> list:
    """``names`` as pytest params, the ``known`` failures marked strict xfail with their reason."""
    return [
        pytest.param(n, marks=pytest.mark.xfail(strict=True, reason=known[n])) if n in known else n
        for n in names
    ]


def assert_passed(results: dict, name: str) -> None:
    r = results[name]
    log = results["_driver_log"]
    detail = log[log.find(name) :][:600] if name in log else ""
    assert r.passed, f"{name}: {r.status}: {r.message}\n{detail}"


def assert_samples_match(
    got: np.ndarray, ref: np.ndarray, name: str, threshold: float, max_frac_over: float
) -> None:
    """A style pass's per-sample RGBA against refnpr's: the same coverage (alpha > 0), and at
    most ``max_frac_over`` of the samples with a channel more than ``threshold`` apart."""
    assert got.shape == ref.shape
    diff = np.abs(got.astype(np.float64) - ref)
    frac = float(np.mean(np.any(diff > threshold, axis=-1)))
    assert np.array_equal(got[..., 3] > 0, ref[..., 3] > 0), "coverage differs"
    assert frac <= max_frac_over, f"{name}: {frac:.4%} of samples over 2/255, max {diff.max():.4g}"


def export_cases(tmp_path_factory, style: str, names: list[str]) -> Path:
    """A style's golden cases exported as a kit (``refnpr kit export --only ...``)."""
    from refnpr.kit import export_kit

    kit = tmp_path_factory.mktemp(f"kit-{style}") / "kit"
    export_kit(kit, suite=SUITE, only=names)
    return kit
