"""A scene's lights, materials and objects as kit JSON, and its meshes as .glb files."""

from __future__ import annotations

import re
from dataclasses import fields
from pathlib import Path
from typing import Any

import numpy as np

from ._json import jsonable
from .gltf import glb_attribute_name, write_glb

__all__ = ["kit_meshes", "lights_entry", "material_entry", "objects_entry"]

_UNSAFE = re.compile(r"[^A-Za-z0-9_\-]+")


def kit_meshes(scene: Any) -> list[Any]:
    """The scene's world meshes as the kit stores them: every vertex array rounded to float32
    (glTF's vertex type), kept as float64 refnpr Meshes. Rasterizing these reproduces what a
    backend reading the .glb files gets; the golden G-buffers were rasterized from the float64
    originals."""
    from ..raster import Mesh

    def r(a: Any) -> Any:
        return None if a is None else np.asarray(a, dtype=np.float32).astype(np.float64)

    return [
        Mesh(
            r(m.positions),
            m.faces,
            normals=r(m.normals),
            uv=r(m.uv),
            attributes={k: r(v) for k, v in m.attributes.items()},
            name=m.name,
        )
        for m in scene.world_meshes()
    ]


def lights_entry(scene: Any) -> list[dict[str, Any]]:
    """``lights``: per light ``kind``, ``color`` and the unit ``direction`` towards the light
    (normalized as refnpr's shading does) or the ``position``."""
    out = []
    for light in scene.lights:
        entry: dict[str, Any] = {"kind": light.kind, "color": [float(c) for c in light.color]}
        if light.kind == "point":
            entry["position"] = [float(c) for c in light.position]
        else:
            d = np.asarray(light.direction, dtype=np.float64)
            entry["direction"] = [float(c) for c in d / np.linalg.norm(d)]
        out.append(entry)
    return out


def material_entry(material: Any) -> dict[str, Any]:
    """Every field of a refnpr Material, with its value (``texture``: the name or path as the
    scene gives it; a style that samples it exports the texture file itself);
    ``color_texture`` only where the material has one."""
    return {
        f.name: jsonable(getattr(material, f.name), where=f"material.{f.name}")
        for f in fields(material)
        if not (f.name == "color_texture" and material.color_texture is None)
    }


def objects_entry(
    scene: Any, case_dir: Path, vertex_attributes: dict[int, dict[str, np.ndarray]] | None = None
) -> list[dict[str, Any]]:
    """Write every object's world mesh to ``case_dir/meshes/<k>_<name>.glb`` (the name reduced
    to ``[A-Za-z0-9_-]``) and describe the objects (``objects`` of case.json).

    ``vertex_attributes`` (``{object index: {name: (N, C) float}}``, a style's) are written
    with the mesh's own attributes as ``_NAME``. ``first_tri_id`` is the global triangle index
    of the object's first face: refnpr's ``tri_id`` concatenates the meshes in object order.
    """
    vertex_attributes = vertex_attributes or {}
    unknown = sorted(set(vertex_attributes) - set(range(len(scene.objects))))
    if unknown:
        raise ValueError(
            f"vertex_attributes: object indices {unknown} do not exist; the scene has "
            f"{len(scene.objects)} objects"
        )
    out, t0 = [], 0
    for k, (obj, mesh) in enumerate(zip(scene.objects, scene.world_meshes(), strict=True)):
        rel = f"meshes/{k}_{_UNSAFE.sub('-', obj.name).strip('-') or 'object'}.glb"
        attrs = dict(mesh.attributes)
        for key, value in vertex_attributes.get(k, {}).items():
            if key in attrs:
                raise ValueError(
                    f"vertex_attributes: {key!r} is already a vertex attribute of mesh "
                    f"{mesh.name!r}"
                )
            attrs[key] = value
        write_glb(
            case_dir / rel,
            mesh.positions,
            mesh.faces,
            normals=mesh.normals,
            uv=mesh.uv,
            attributes=attrs,
            name=mesh.name,
            extras={"refnpr_object": obj.name, "mesh_id": k, "first_tri_id": t0},
        )
        out.append(
            {
                "name": obj.name,
                "mesh": rel,
                "mesh_id": k,
                "first_tri_id": t0,
                "vertices": int(mesh.positions.shape[0]),
                "triangles": int(mesh.faces.shape[0]),
                "has_normals": mesh.normals is not None,
                "has_uv": mesh.uv is not None,
                "attributes": {glb_attribute_name(a): a for a in attrs},
                "material": material_entry(obj.material),
            }
        )
        t0 += int(mesh.faces.shape[0])
    return out
