"""The GLSL backend's colour maps (material baseColorTexture) in the ``smooth`` and ``toon``
styles, end to end: a glTF scene of a textured quad (an 8 x 8 RGB map repeated 2.5 times,
seen at a grazing angle so that the map is magnified near the camera and minified further
away) and an object without a map, exported by ``refnpr kit export --scene``, rendered by
``python -m refnpr_glsl`` and judged by ``refnpr.kit.check.check_kit`` with the cases' own
tolerances. The same renders without the maps must fail the check (the cases see the maps),
and a malformed ``params.color_texture`` is a per-case error naming the key.
"""

from __future__ import annotations

import json
import shutil
import subprocess
import sys
import warnings
from pathlib import Path

import numpy as np
import pytest

pytest.importorskip("moderngl")  # the extra "glsl"; CI installs it

from refnpr.cli import main  # noqa: E402

#: The exported cases: name -> extra ``refnpr kit export`` arguments.
CASES = {"quad-smooth": ["--style", "smooth"], "quad-toon": ["--style", "toon", "--param", "n=3"]}
SIZE = (64, 48)


def _scene(path: Path) -> Path:
    """A .glb: a quad tilted 62 degrees away from the default +Z view with an 8 x 8 RGB
    baseColorTexture (uv 0 .. 2.5 on both axes), and a small sphere without a map in front."""
    trimesh = pytest.importorskip("trimesh")
    from PIL import Image

    rng = np.random.default_rng(3)
    image = Image.fromarray(rng.integers(0, 256, (8, 8, 3), dtype=np.uint8))
    t = np.radians(62.0)
    y, z = -1.0 + 2.0 * np.cos(t), -2.0 * np.sin(t)
    v = np.array([[-1.2, -1.0, 0.0], [1.2, -1.0, 0.0], [1.2, y, z], [-1.2, y, z]])
    uv = np.array([[0.0, 0.0], [2.5, 0.0], [2.5, 2.5], [0.0, 2.5]])
    visual = trimesh.visual.TextureVisuals(uv=uv, image=image)
    quad = trimesh.Trimesh(v, [[0, 1, 2], [0, 2, 3]], visual=visual, process=False)
    ball = trimesh.creation.icosphere(subdivisions=2, radius=0.35)
    ball.apply_translation([0.6, -0.4, 0.4])
    scene = trimesh.Scene()
    scene.add_geometry(quad, geom_name="quad")
    scene.add_geometry(ball, geom_name="ball")
    scene.export(path)
    return path


def _backend(kit: Path, out: Path) -> subprocess.CompletedProcess:
    return subprocess.run(
        [sys.executable, "-m", "refnpr_glsl", str(kit), str(out), "-q"],
        capture_output=True,
        text=True,
        timeout=600,
    )


def _edit_cases(kit: Path, edit) -> None:
    for name in CASES:
        path = kit / name / "case.json"
        data = json.loads(path.read_text())
        edit(name, data["style"]["params"])
        path.write_text(json.dumps(data))


@pytest.fixture(scope="module")
def kit(tmp_path_factory: pytest.TempPathFactory) -> Path:
    root = tmp_path_factory.mktemp("color_maps")
    glb = _scene(root / "quad.glb")
    out = root / "kit"
    size = f"{SIZE[0]}x{SIZE[1]}"
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        for name, extra in CASES.items():
            args = ["kit", "export", str(out), "--scene", str(glb), "--name", name, *extra]
            assert main([*args, "--size", size, "-q"]) == 0
    return out


def test_the_cases_carry_a_colour_map_that_is_minified_in_part(kit: Path) -> None:
    from refnpr.raster import rasterize
    from refnpr.scenes import load_scene

    for name in CASES:
        case = json.loads((kit / name / "case.json").read_text())
        assert case["style"]["params"]["color_texture"] == ["color_0", None]
        assert {"uv", "duv_dx", "duv_dy"} <= set(case["channels"])
        assert len(case["textures"]["color_0"]["levels"]) == 4  # 8, 4, 2, 1 texels
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        scene = load_scene(kit.parent / "quad.glb")
    gb = rasterize(scene, scene.camera, *SIZE, channels=("mesh_id", "duv_dx", "duv_dy"))
    on_quad = gb["mesh_id"] == 0
    rho = (
        np.maximum(
            np.hypot(gb["duv_dx"][..., 0], gb["duv_dx"][..., 1]),
            np.hypot(gb["duv_dy"][..., 0], gb["duv_dy"][..., 1]),
        )[on_quad]
        * 8.0
    )
    assert on_quad.sum() > 200 and (gb["mesh_id"] == 1).sum() > 40
    assert (rho < 1.0).sum() > 10 and (rho > 1.5).sum() > 50  # magnified and minified


def test_derived_texts_without_textures_match_the_export(kit: Path) -> None:
    """``derived_texts`` (no texture built) gives the colour-map text the export wrote."""
    from refnpr.kit.styles import derived_texts
    from refnpr.scenes import load_scene
    from refnpr.styles import get_style

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        scene = load_scene(kit.parent / "quad.glb")
    size = {"width": SIZE[0], "height": SIZE[1], "spp": 1}
    for name, style in (
        ("quad-smooth", get_style("smooth")),
        ("quad-toon", get_style("toon", n=3)),
    ):
        case = json.loads((kit / name / "case.json").read_text())
        texts = derived_texts(style, scene, **size)
        assert "color_texture" in texts
        assert all(case["derived"][k] == v for k, v in texts.items())


def test_the_backend_renders_colour_maps_as_refnpr(kit: Path, tmp_path: Path) -> None:
    from refnpr.kit.check import check_kit

    proc = _backend(kit, tmp_path)
    assert proc.returncode == 0, proc.stderr[-4000:]
    results = {r.name: r for r in check_kit(kit, tmp_path)}
    assert sorted(results) == sorted(CASES)
    for name, r in results.items():
        assert r.passed, f"{name}: {r.message}"


def test_a_backend_ignoring_the_maps_fails_the_check(kit: Path, tmp_path: Path) -> None:
    """The same cases rendered without ``params.color_texture`` (the shaders of a backend that
    ignores colour maps), checked against the real kit: every case fails."""
    from refnpr.kit.check import check_kit

    plain = tmp_path / "kit"
    shutil.copytree(kit, plain)
    _edit_cases(plain, lambda name, params: params.pop("color_texture"))
    renders = tmp_path / "renders"
    proc = _backend(plain, renders)
    assert proc.returncode == 0, proc.stderr[-4000:]
    results = check_kit(kit, renders)
    assert [r.name for r in results if r.passed] == []
    assert len(results) == len(CASES)


def test_a_malformed_color_texture_is_a_per_case_error(kit: Path, tmp_path: Path) -> None:
    bad = tmp_path / "kit"
    shutil.copytree(kit, bad)
    wrong = {"quad-smooth": ["color_0"], "quad-toon": ["color_9", None]}
    _edit_cases(bad, lambda name, params: params.update(color_texture=wrong[name]))
    proc = _backend(bad, tmp_path / "renders")
    assert proc.returncode == 1
    assert (
        "quad-smooth: ERROR ValueError: case 'quad-smooth': style.params.color_texture: "
        "expected a list of 2 entries (one per object: a texture role or null), got 1"
    ) in proc.stderr
    assert (
        "quad-toon: ERROR ValueError: case 'quad-toon': style.params.color_texture[0] = "
        "'color_9': expected null or a texture role of the case (['color_0'])"
    ) in proc.stderr
    report = json.loads((tmp_path / "renders" / "backend.json").read_text())
    assert {k: v["status"] for k, v in report["cases"].items()} == dict.fromkeys(CASES, "error")
