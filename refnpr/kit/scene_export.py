"""A scene's lights, materials and objects as kit JSON, and its meshes as .glb files."""

from __future__ import annotations

import re
from dataclasses import fields
from pathlib import Path
from typing import Any

import numpy as np

from ._json import jsonable
from .gltf import glb_attribute_name, write_glb

__all__ = [
    "kit_meshes",
    "lights_entry",
    "material_entry",
    "mesh_file_name",
    "write_object_mesh",
    "objects_entry",
]

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
    scene gives it; a style that samples it exports the texture file itself)."""
    return {
        f.name: jsonable(getattr(material, f.name), where=f"material.{f.name}")
        for f in fields(material)
    }


def mesh_file_name(k: int, name: str) -> str:
    """``meshes/<k>_<name>.glb`` with the name reduced to ``[A-Za-z0-9_-]``."""
    safe = _UNSAFE.sub("-", name).strip("-") or "object"
    return f"meshes/{k}_{safe}.glb"


def write_object_mesh(
    case_dir: Path,
    rel: str,
    mesh: Any,
    *,
    extra: dict[str, np.ndarray] | None = None,
    extras: dict[str, Any] | None = None,
) -> dict[str, Any]:
    """Write a world-space refnpr Mesh to ``case_dir / rel`` as .glb.

    Parameters
    ----------
    case_dir : Path
    rel : str
        Path relative to ``case_dir`` (``mesh_file_name``).
    mesh : refnpr.raster.Mesh
        World space; its own ``attributes`` are written as ``_NAME`` attributes.
    extra : {name: (N, C) float}, optional
        More per-vertex attributes (a style's, e.g. abstracted normals).
    extras : dict, optional
        JSON stored in the glTF mesh's ``extras``.

    Returns
    -------
    dict
        ``vertices``, ``triangles``, ``attributes``: {glTF name: refnpr name} of the extra
        attributes, ``has_normals``, ``has_uv``.
    """
    attrs = dict(mesh.attributes)
    for key, value in (extra or {}).items():
        if key in attrs:
            raise ValueError(
                f"vertex_attributes: {key!r} is already a vertex attribute of mesh {mesh.name!r}"
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
        extras=extras,
    )
    return {
        "vertices": int(mesh.positions.shape[0]),
        "triangles": int(mesh.faces.shape[0]),
        "has_normals": mesh.normals is not None,
        "has_uv": mesh.uv is not None,
        "attributes": {glb_attribute_name(k): k for k in attrs},
    }


def objects_entry(
    scene: Any, case_dir: Path, vertex_attributes: dict[int, dict[str, np.ndarray]] | None = None
) -> list[dict[str, Any]]:
    """Write every object's world mesh and describe the objects (``objects`` of case.json).

    ``first_tri_id`` is the global triangle index of the object's first face: refnpr's
    ``tri_id`` concatenates the meshes in object order.
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
        rel = mesh_file_name(k, obj.name)
        info = write_object_mesh(
            case_dir,
            rel,
            mesh,
            extra=vertex_attributes.get(k),
            extras={"refnpr_object": obj.name, "mesh_id": k, "first_tri_id": t0},
        )
        out.append(
            {
                "name": obj.name,
                "mesh": rel,
                "mesh_id": k,
                "first_tri_id": t0,
                **info,
                "material": material_entry(obj.material),
            }
        )
        t0 += info["triangles"]
    return out
