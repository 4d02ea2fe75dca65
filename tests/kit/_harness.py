"""A style pass of the GLSL backend run on refnpr's own G-buffer, without the driver: isolates a
style's shading from rasterization (used by the per-style kit tests)."""

from __future__ import annotations

import dataclasses
import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from refnpr.raster import rasterize
from refnpr.scenes import load_scene
from refnpr.styles import ShadeContext, style_from_spec


class FakeCase:
    """The parts of ``refnpr_glsl.kit_io.Case`` a style pass reads, built from a refnpr scene
    and the style's kit export (the files go to ``case_dir``), without a driver."""

    def __init__(self, name, scene, style, case_dir: Path, width: int, height: int, spp: int):
        from refnpr_glsl.kit_io import MeshData, read_image

        from refnpr.kit.styles import export_style, style_name

        exp = export_style(style, scene, case_dir, width=width, height=height, spp=spp)
        self.name = name
        self.dir = case_dir
        self.width, self.height, self.spp = width, height, spp
        self.n = int(round(spp**0.5))
        self.sample_size = (self.n * width, self.n * height)
        cam = scene.camera
        lights = []
        for li in scene.lights:
            d = {"kind": li.kind, "color": list(li.color)}
            if li.kind == "point":
                d["position"] = list(li.position)
            else:
                d["direction"] = list(li.direction)
            lights.append(d)
        objects = [
            {"name": o.name, "mesh_id": k, "material": dataclasses.asdict(o.material)}
            for k, o in enumerate(scene.objects)
        ]
        self.data = {
            "name": name,
            "width": width,
            "height": height,
            "spp": spp,
            "camera": {
                "eye": cam.eye.tolist(),
                "view_matrix": cam.view_matrix().tolist(),
                "projection_matrix": cam.projection_matrix(width, height).tolist(),
            },
            "lights": lights,
            "ambient": list(scene.ambient),
            "objects": objects,
            "style": {"name": style_name(style), "params": json.loads(json.dumps(exp.params))},
            "textures": exp.textures,
            "derived": exp.derived,
        }
        self.params = self.data["style"]["params"]
        self.lights = lights
        self.objects = objects
        self.eye = np.asarray(cam.eye, dtype=np.float64)
        self.ambient = np.asarray(scene.ambient, dtype=np.float64)
        self._textures = exp.textures
        self._read = read_image
        meshes, first = [], 0
        for k, m in enumerate(scene.world_meshes()):
            attrs = {
                key: np.asarray(v, dtype=np.float32).astype(np.float64)
                for key, v in exp.vertex_attributes.get(k, {}).items()
            }
            f32 = lambda a: None if a is None else np.asarray(a, np.float32).astype(np.float64)  # noqa: E731
            meshes.append(
                MeshData(
                    name=m.name,
                    positions=f32(m.positions),
                    normals=f32(m.normals),
                    uv=f32(m.uv),
                    indices=np.asarray(m.faces, dtype=np.int64),
                    attributes=attrs,
                    mesh_id=k,
                    first_tri_id=first,
                    material=objects[k]["material"],
                )
            )
            first += int(m.faces.shape[0])
        self.meshes = meshes

    def view_matrix(self):
        return np.asarray(self.data["camera"]["view_matrix"], dtype=np.float64)

    def projection_matrix(self):
        return np.asarray(self.data["camera"]["projection_matrix"], dtype=np.float64)

    def materials(self, key, default=0.0):
        return np.array(
            [np.asarray(o["material"].get(key, default), dtype=np.float64) for o in self.objects]
        )

    def texture(self, role):
        entry = self._textures[role]
        return [self._read(self.dir / f) for f in entry["levels"]]


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


def isolated(gl, case, tmp_path: Path, width: int, height: int, spp: int, module):
    """(GLSL result, refnpr result), both (nH, nW, 4) float32, for one golden case's style on
    refnpr's G-buffer of the case's scene at ``width`` x ``height`` (``case.scene``: a scene
    name or a Scene; ``case.style``: a style table or a Style)."""
    scene = load_scene(case.scene) if isinstance(case.scene, str) else case.scene
    style = style_from_spec(case.style)
    inner = style.base if style.name == "contoured" else style
    gb = rasterize(
        scene,
        scene.camera,
        width,
        height,
        sorted(inner.requires(scene)),
        spp,
        **inner.raster_options(scene),
    )
    ref = np.asarray(inner.shade(ShadeContext(gb, scene)), dtype=np.float32)
    fake = FakeCase(case.name, scene, style, tmp_path, width, height, spp)
    textures = upload_gbuffer(gl, gb)
    try:
        out = module.shade(gl, fake, textures, fake.sample_size)
        got = gl.read(out)
        out.release()
    finally:
        for t in textures.values():
            t.release()
    return got, ref


def render_and_check(kit: Path, names: list[str], derivatives: str) -> dict:
    """Render ``names`` of ``kit`` with the backend driver (a subprocess) and check them with
    ``refnpr kit check``'s comparator: name -> CaseCheck, plus ``"_driver_log"``."""
    from refnpr.kit.check import check_kit

    renders = kit.parent / f"renders-{derivatives}"
    run = subprocess.run(
        [sys.executable, "-m", "refnpr_glsl", str(kit), str(renders), "--only", *names, "-q",
         "--derivatives", derivatives],
        capture_output=True,
        text=True,
    )  # fmt: skip
    renders.mkdir(exist_ok=True)
    results = check_kit(kit, renders, json_path=kit.parent / f"check-{derivatives}.json")
    out: dict = {r.name: r for r in results}
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


def export_cases(tmp_path_factory, style: str, suite: Path, names: list[str]) -> Path:
    """A style's golden cases exported as a kit (``refnpr kit export --only ...``)."""
    from refnpr.kit import export_kit

    kit = tmp_path_factory.mktemp(f"kit-{style}") / "kit"
    export_kit(kit, suite=suite, only=names)
    return kit
