"""Figure for docs/scenes.md: a glTF scene written by trimesh (three boxes, one with a checker
colour map), rendered by refnpr from the file's camera, beside the file's camera's own expectation: the corners of every box projected with a
float64 pinhole of the glTF camera (yfov, node matrix) read straight from the file's JSON.

Run from the repository root: ``python docs/figures/gltf_projection.py`` (writes
``docs/images/gltf-projection.png`` and prints the largest distance between a projected corner
and the silhouette refnpr drew around it).
"""

from __future__ import annotations

import json
import math
import struct
import tempfile
import warnings
from pathlib import Path

import numpy as np
import trimesh
from PIL import Image, ImageDraw

from refnpr.raster import rasterize
from refnpr.render import render
from refnpr.scenes import load_scene

W, H = 480, 320
OUT = Path(__file__).resolve().parents[1] / "images" / "gltf-projection.png"


def checker_box(s: float) -> trimesh.Trimesh:
    """A cube of side ``s`` whose faces carry a 4 x 4 checker colour map (baseColorTexture):
    vertices unshared, each face's uv its two in-plane coordinates over [0, 1]."""
    box = trimesh.creation.box(extents=(s, s, s))
    box.unmerge_vertices()
    axis = np.abs(box.face_normals).argmax(axis=1).repeat(3)  # each vertex's face normal axis
    keep = np.array([[1, 2], [0, 2], [0, 1]])[axis]
    uv = np.take_along_axis(box.vertices, keep, axis=1) / s + 0.5
    cells = (np.indices((64, 64)) // 16).sum(axis=0) % 2
    image = np.where(cells[..., None] == 1, (235, 200, 120), (150, 60, 40)).astype(np.uint8)
    box.visual = trimesh.visual.TextureVisuals(
        uv=uv,
        material=trimesh.visual.material.PBRMaterial(
            baseColorFactor=(1.0, 1.0, 1.0, 1.0), baseColorTexture=Image.fromarray(image)
        ),
    )
    return box


def build(path: Path) -> None:
    scene = trimesh.Scene()
    for i, (x, z, s) in enumerate([(-1.6, 0.0, 0.8), (0.0, -0.8, 1.2), (1.7, 0.6, 0.6)]):
        if i == 1:  # a colour map, as user content has
            box = checker_box(s)
        else:
            box = trimesh.creation.box(extents=(s, s, s))
            colour = [(0.35, 0.5, 0.8, 1.0), None, (0.4, 0.7, 0.4, 1.0)][i]
            box.visual = trimesh.visual.TextureVisuals(
                material=trimesh.visual.material.PBRMaterial(baseColorFactor=colour)
            )
        move = trimesh.transformations.translation_matrix([x, s / 2, z])
        scene.add_geometry(box, node_name=f"box{i}", transform=move)
    scene.camera.resolution = (W, H)
    scene.camera.fov = (60.0 * W / H, 45.0)
    eye = np.array([1.5, 3.0, 6.0])
    forward = -eye / np.linalg.norm(eye)
    right = np.cross(forward, [0.0, 1.0, 0.0])
    right /= np.linalg.norm(right)
    up = np.cross(right, forward)
    cam = np.eye(4)
    cam[:3, 0], cam[:3, 1], cam[:3, 2], cam[:3, 3] = right, up, -forward, eye
    scene.camera_transform = cam
    scene.export(path)


def gltf_json(path: Path) -> dict:
    data = path.read_bytes()
    length, kind = struct.unpack_from("<II", data, 12)
    assert kind == 0x4E4F534A  # JSON chunk
    return json.loads(data[20 : 20 + length])


def world(doc: dict, index: int, parents: dict[int, int]) -> np.ndarray:
    node = doc["nodes"][index]
    if "matrix" in node:
        m = np.array(node["matrix"], dtype=np.float64).reshape(4, 4).T
    else:
        t = np.eye(4)
        t[:3, 3] = node.get("translation", [0, 0, 0])
        x, y, z, w = node.get("rotation", [0, 0, 0, 1])
        r = np.eye(4)
        r[:3, :3] = trimesh.transformations.quaternion_matrix([w, x, y, z])[:3, :3]
        s = np.diag([*node.get("scale", [1, 1, 1]), 1.0])
        m = t @ r @ s
    return world(doc, parents[index], parents) @ m if index in parents else m


def main() -> None:
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "boxes.glb"
        build(path)
        doc = gltf_json(path)
        parents = {c: i for i, n in enumerate(doc["nodes"]) for c in n.get("children", [])}
        cam_node = next(i for i, n in enumerate(doc["nodes"]) if "camera" in n)
        yfov = doc["cameras"][doc["nodes"][cam_node]["camera"]]["perspective"]["yfov"]
        view = np.linalg.inv(world(doc, cam_node, parents))
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            scene = load_scene(path)
            image = render(scene, {"name": "toon", "n": 3}, W, H, 4).to_srgb8()
            covered = rasterize(scene, scene.camera, W, H, channels=("tri_id",))["tri_id"] >= 0
        f = 1.0 / math.tan(yfov / 2.0)
        points = []
        for i, node in enumerate(doc["nodes"]):
            if "mesh" not in node:
                continue
            model = world(doc, i, parents)
            for corner in np.array(np.meshgrid([-1, 1], [-1, 1], [-1, 1])).T.reshape(-1, 3):
                half = 0.5 * np.ptp(_positions(path, doc, node["mesh"]), axis=0)
                p = view @ model @ np.r_[corner * half, 1.0]
                ndc = (f * (H / W) * p[0] / -p[2], f * p[1] / -p[2])
                points.append(((ndc[0] + 1) / 2 * W, (1 - ndc[1]) / 2 * H))
    # the distance from each projected corner to the nearest covered pixel centre
    ys, xs = np.nonzero(covered)
    centres = np.c_[xs + 0.5, ys + 0.5]
    worst = max(float(np.min(np.hypot(*(centres - p).T))) for p in points)
    left = Image.fromarray(image).convert("RGB")
    right = Image.new("RGB", (W, H), "white")
    draw_l, draw_r = ImageDraw.Draw(left), ImageDraw.Draw(right)
    for x, y in points:
        for d in (draw_l, draw_r):
            d.ellipse([x - 3, y - 3, x + 3, y + 3], outline=(220, 30, 30), width=2)
    sheet = Image.new("RGB", (2 * W + 8, H), "white")
    sheet.paste(left, (0, 0))
    sheet.paste(right, (W + 8, 0))
    OUT.parent.mkdir(parents=True, exist_ok=True)
    sheet.save(OUT, optimize=True)
    print(f"wrote {OUT}: {len(points)} corners, farthest {worst:.2f} px from a covered pixel")


def _positions(path: Path, doc: dict, mesh: int) -> np.ndarray:
    """The mesh's POSITION accessor min/max (the glTF file states them)."""
    acc = doc["accessors"][doc["meshes"][mesh]["primitives"][0]["attributes"]["POSITION"]]
    return np.array([acc["min"], acc["max"]], dtype=np.float64)


if __name__ == "__main__":
    main()
