"""Evaluation of the X-Toon style on a G-buffer: which channels a configuration needs (the plan),
per-vertex quantities (the paper's vertex shader) and per-sample tone, detail and normals, as
flat float64 arrays ``(K, ...)`` over the covered samples.

Per-vertex quantities are interpolated perspective-correctly at the samples, either by the
rasterizer (when the scene's meshes carry them as vertex attributes, see
``XToonStyle.prepare_scene``) or here from ``tri_id`` and ``bary`` (the same formula). Names:
``xtoon_d`` (D per vertex), ``xtoon_flow`` (screen displacement per vertex, pixels) and
``xtoon_normal`` (the linear blend (1 - w) n + w n_abstract per vertex, unnormalized).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from functools import partial
from typing import Any

import numpy as np

from refnpr.device.lights import LIGHT_POINT, light_dir, lights_record
from refnpr.formulas import xtoon
from refnpr.formulas._face import elementwise
from refnpr.raster.projection import project_points
from refnpr.texture import sample_level

from .detail import FLOW_BEHIND, columns, detail_values, style_record
from .geometry import VertexGeometry
from .shape import AbstractedNormals, abstract_normals, unit_rows

__all__ = ["Config", "Plan", "plan", "vertex_values", "evaluate", "Evaluated"]


@dataclass(frozen=True, eq=False)
class Config:
    """A validated X-Toon configuration (built by ``XToonStyle.__init__``): the parameter
    values ``p`` (``params.PARAMS``), the resolved toon texture, the shape weight's pyramid."""

    p: Any
    texture: np.ndarray  # (rows, cols, 4) float32 RGBA, rows grow with D
    weight_pyramid: Any = None
    cache: dict = field(default_factory=dict)


@dataclass(frozen=True)
class Plan:
    """What a frame needs: G-buffer channels, per-vertex quantities and how they arrive."""

    channels: frozenset[str]
    vertex_names: tuple[str, ...]
    carried: frozenset[str]  # vertex quantities the meshes carry as attributes


def map_channels(p: Any) -> set[str]:
    """G-buffer channels the attribute map reads per sample: the view-axis ``depth`` for the
    focal-axis distance (Fig. 2b), ``position`` for the eye distance and the other maps."""
    if p.detail in ("depth", "focus"):
        return {"depth"} if p.distance == "axis" else {"position"}
    return {"position"} if p.detail in ("orientation", "highlight", "flow") else set()


def light_of(cfg: Config, scene: Any) -> Any:
    """The scene light the tone is lit by (``light``), checked against the scene."""
    if not scene.lights:
        raise ValueError(
            "light: X-Toon's tone is n.l of one light, but the scene has no lights; add a "
            "[[light]] table to the scene"
        )
    if cfg.p.light >= len(scene.lights):
        raise ValueError(
            f"light: index {cfg.p.light} out of range; the scene has {len(scene.lights)} light(s) "
            f"(use 0..{len(scene.lights) - 1})"
        )
    return scene.lights[cfg.p.light]


def plan(cfg: Config, scene: Any) -> Plan:
    """The channels and per-vertex quantities ``cfg`` needs for ``scene`` (nothing more)."""
    kind = cfg.p.detail
    shaped = cfg.p.shape is not None
    vertex_blend = shaped and cfg.p.shape_blend == "vertex"
    channels = {"mesh_id"}
    names: list[str] = []
    if vertex_blend:
        names.append("xtoon_normal")
    else:
        channels.add("normal")
    if light_of(cfg, scene).kind == "point":
        channels.add("position")
    if cfg.p.detail_mode == "pixel":
        channels |= map_channels(cfg.p)
    elif kind not in ("map", "none"):
        names.append("xtoon_flow" if kind == "flow" else "xtoon_d")
    bary = shaped and not vertex_blend  # the abstracted normal, interpolated per pixel
    if bary and cfg.p.shape_weight.kind == "detail":
        channels |= map_channels(cfg.p)
    if bary and cfg.p.shape_weight.kind == "texture":
        channels.add("uv")
    meshes = scene.world_meshes()
    carried = frozenset(n for n in names if all(n in m.attributes for m in meshes))
    channels |= carried
    if bary or set(names) - carried:
        channels |= {"tri_id", "bary"}
    return Plan(frozenset(channels), tuple(names), carried)


def _abstract(cfg: Config, scene: Any) -> list[np.ndarray | None]:
    meshes = scene.world_meshes()
    if isinstance(cfg.p.shape, AbstractedNormals):
        return cfg.p.shape.for_meshes(meshes)
    key = tuple(id(m) for m in meshes)
    hit = cfg.cache.get("abstract")
    if hit is None or hit[0] != key:
        an = abstract_normals(
            scene,
            cfg.p.shape,
            objects=cfg.p.shape_objects,
            frame=cfg.p.shape_frame,
            iterations=cfg.p.shape_iterations,
        )
        hit = (key, an, meshes)  # keeps the meshes alive so their ids stay unique
        cfg.cache["abstract"] = hit
    return list(hit[1].normals)


def _abstract_rows(cfg: Config, scene: Any, geom: VertexGeometry, n_v: np.ndarray) -> np.ndarray:
    """(N, 3) abstracted normals of every vertex; ``n_v`` for objects left unabstracted."""
    parts = zip(_abstract(cfg, scene), geom.split(n_v), strict=True)
    return np.concatenate([b if a is None else a for a, b in parts])


def _light_dirs(cfg: Config, scene: Any, points: np.ndarray | None) -> np.ndarray:
    """Unit directions towards the style's light: (3,) for a directional light, (K, 3) at
    ``points (K, 3)`` for a point light (``refnpr.device.lights.light_dir``, as the kernel)."""
    light_of(cfg, scene)
    lights = lights_record(scene.lights)
    i = cfg.p.light
    if lights.kind[i] != LIGHT_POINT:
        return lights.vec[i]
    v = tuple(float(c) for c in lights.vec[i])
    return elementwise(light_dir, np.float64, True, v, columns(points, len(points)))


def _flow(points, cfg: Config, camera: Any, width: int, height: int, before=None) -> np.ndarray:
    """(K, 2) screen displacement in pixels since the previous frame (X-Toon sec. 5): world
    ``points (K, 3)`` through ``camera`` minus their previous world positions ``before`` (default:
    the same points, a still object) through the previous camera (default: ``camera``)."""
    prev_camera = camera if cfg.p.prev_camera is None else cfg.p.prev_camera
    before = points if before is None else before
    now, _ = project_points(points, camera.view_projection(width, height), width, height)
    then, _ = project_points(before, prev_camera.view_projection(width, height), width, height)
    f = now - then
    bad = ~np.all(np.isfinite(f), axis=1)
    f[bad] = (FLOW_BEHIND, 0.0)  # behind either camera: no screen position, coarsest detail
    return f


def _prev_transforms(cfg: Config, scene: Any) -> np.ndarray | None:
    """``prev_transforms`` (or None), checked against the scene's objects."""
    prev = cfg.p.prev_transforms
    if prev is not None and len(prev) != len(scene.objects):
        raise ValueError(
            f"prev_transforms: got {len(prev)} transforms but the scene has "
            f"{len(scene.objects)} objects; give one 4x4 per scene object, in scene order "
            "(the previous frame's [o.transform for o in prev_scene.objects])"
        )
    return prev


def _prev_vertices(cfg: Config, scene: Any) -> np.ndarray | None:
    """Every vertex's previous world position ``(N, 3)`` (as ``Mesh.transformed`` maps it)."""
    prev = _prev_transforms(cfg, scene)
    if prev is None:
        return None
    parts = []
    for obj, m in zip(scene.objects, prev, strict=True):
        if np.array_equal(m, obj.transform):  # still object: its world mesh itself
            parts.append(obj.world_mesh().positions)
        else:
            parts.append(obj.mesh.positions @ m[:3, :3].T + m[:3, 3])
    return np.concatenate(parts)


def _prev_pixels(cfg: Config, scene: Any, points: np.ndarray, mesh_id: np.ndarray) -> Any:
    """Previous world positions ``(K, 3)`` of world ``points`` on objects ``mesh_id (K,)``."""
    prev = _prev_transforms(cfg, scene)
    if prev is None:
        return None
    before = np.array(points, dtype=np.float64)
    for i, (obj, m) in enumerate(zip(scene.objects, prev, strict=True)):
        if np.array_equal(m, obj.transform):
            continue  # still object: same world position
        sel = mesh_id == i
        motion = m @ np.linalg.inv(obj.transform)  # world now -> object -> world before
        before[sel] = points[sel] @ motion[:3, :3].T + motion[:3, 3]
    return before


def vertex_values(
    cfg: Config, scene: Any, width: int, height: int, geom: VertexGeometry | None = None
) -> dict[str, np.ndarray]:
    """The per-vertex quantities of the plan, ``(N,)`` or ``(N, C)`` float64 over all vertices."""
    names = plan(cfg, scene).vertex_names
    if not names:
        return {}
    camera = scene.camera
    geom = VertexGeometry.of(scene.world_meshes()) if geom is None else geom
    p = geom.positions
    n_v = unit_rows(geom.normals())
    flow = None
    if cfg.p.detail == "flow":
        flow = _flow(p, cfg, camera, width, height, _prev_vertices(cfg, scene))
    record = style_record(cfg.p, cfg.texture, scene, camera)
    light = _light_dirs(cfg, scene, p)
    d_at = partial(
        detail_values, cfg.p, record, camera, positions=p, light=light, flow=flow, count=len(p)
    )
    out: dict[str, np.ndarray] = {}
    n_shade = n_v
    if cfg.p.shape is not None:
        kind = cfg.p.shape_weight.kind
        # per-pixel weights (texture, map): the vertex D uses the mesh normals
        weight = cfg.p.shape_weight.value if kind == "global" else 0.0
        if kind == "detail":
            weight = 1.0 - d_at(normals=n_v)  # local weight from the same attribute map
        n_abs = _abstract_rows(cfg, scene, geom, n_v)
        blend = elementwise(  # sec. 4: the linear blend, in the vertex shader
            xtoon.blend_normals.scalar, np.float64, columns(n_v), columns(n_abs), weight, False
        )
        if "xtoon_normal" in names:
            out["xtoon_normal"] = blend
        n_shade = unit_rows(blend)
    if "xtoon_flow" in names:
        out["xtoon_flow"] = flow
    if "xtoon_d" in names:
        out["xtoon_d"] = d_at(normals=n_shade)  # sec. 3.1: D per vertex, then interpolated
    return out


@dataclass(frozen=True, eq=False)
class Evaluated:
    """Per-sample results on the covered samples ``mask`` (flat arrays of length K)."""

    mask: np.ndarray  # (nH, nW) bool
    tone: np.ndarray  # (K,)
    detail: np.ndarray  # (K,)
    normal: np.ndarray  # (K, 3) unit shading normals
    weight: np.ndarray | None  # (K,) shape weight where it varies, else None


def _sample_grid(arr: np.ndarray, gb: Any, name: str) -> np.ndarray:
    nh, nw = gb.sample_shape
    if arr.shape == (nh, nw):
        return arr
    if arr.shape == (gb.height, gb.width):
        return np.repeat(np.repeat(arr, gb.n, axis=0), gb.n, axis=1)
    raise ValueError(
        f"{name}: map of shape {arr.shape} does not match the image: expected ({gb.height}, "
        f"{gb.width}) per pixel or ({nh}, {nw}) per sample; render at the map's size"
    )


def _check_carried(name: str, values: np.ndarray, meshes: list[Any]) -> None:
    """Refuse vertex attributes ``name`` that the meshes carry from another frame."""
    for mesh, fresh in zip(meshes, VertexGeometry.of(meshes).split(values), strict=True):
        a = np.asarray(mesh.attributes[name], dtype=np.float64).reshape(fresh.shape)
        if not np.allclose(a, fresh, rtol=1e-7, atol=1e-9):
            raise ValueError(
                f"{name}: the vertex attribute carried by mesh {mesh.name!r} does not match this "
                "frame (camera, image size or style parameters changed); rebuild the scene with "
                "XToonStyle.prepare_scene(scene, width=..., height=..., camera=...)"
            )


def evaluate(cfg: Config, ctx: Any) -> Evaluated:
    """Tone, detail and shading normals at the covered samples."""
    gb, scene = ctx.gb, ctx.scene
    camera = scene.camera
    pl = plan(cfg, scene)
    mask = gb["mesh_id"] >= 0
    k = int(mask.sum())

    def at(channel: str) -> np.ndarray:
        return np.asarray(gb[channel][mask], dtype=np.float64)

    geom = None
    if "tri_id" in pl.channels:
        geom = VertexGeometry.of(scene.world_meshes())
        tri, bary = gb["tri_id"][mask], gb["bary"][mask]
    vals = vertex_values(cfg, scene, gb.width, gb.height, geom) if pl.vertex_names else {}
    interp: dict[str, np.ndarray] = {}
    for name, v in vals.items():
        if name in pl.carried:
            _check_carried(name, v, scene.world_meshes())
            interp[name] = at(name)
        else:
            interp[name] = geom.interpolate(v, tri, bary)

    pos = at("position") if "position" in pl.channels else None
    light = _light_dirs(cfg, scene, pos)
    record = style_record(cfg.p, cfg.texture, scene, camera)
    user = None
    if cfg.p.detail == "map":
        user = _sample_grid(cfg.p.detail_map, gb, "detail_map")[mask]

    d_at = partial(detail_values, cfg.p, record, camera, positions=pos, light=light, count=k)

    def d_at_pixels(normals: np.ndarray) -> np.ndarray:
        flow = None
        if cfg.p.detail == "flow":
            before = _prev_pixels(cfg, scene, pos, gb["mesh_id"][mask])
            flow = _flow(pos, cfg, camera, gb.width, gb.height, before)
        depth = at("depth") if "depth" in map_channels(cfg.p) else None
        return d_at(depth=depth, normals=normals, flow=flow, user=user)

    weight = None
    if cfg.p.shape is None:
        n = unit_rows(at("normal"))
    elif cfg.p.shape_blend == "vertex":
        n = unit_rows(interp["xtoon_normal"])  # renormalized per pixel (sec. 4)
    else:
        n0 = unit_rows(at("normal"))
        na = geom.interpolate(
            _abstract_rows(cfg, scene, geom, unit_rows(geom.normals())), tri, bary
        )
        w = _pixel_weight(cfg, gb, mask, n0, d_at_pixels, at)
        weight = None if np.ndim(w) == 0 else w
        ok = np.linalg.norm(na, axis=1) > 0
        na[~ok] = n0[~ok]
        zero = np.linalg.norm(n0, axis=1) == 0
        n0[zero] = np.where(ok[zero, None], na[zero], (0.0, 0.0, 1.0))
        na[zero & ~ok] = (0.0, 0.0, 1.0)
        n = xtoon.blend_normals(n0, na, w)  # per-pixel blend (refnpr option)

    n_dot_l = np.sum(n * light, axis=-1)
    tone = xtoon.tone(n_dot_l, half_lambert=cfg.p.tone == "half_lambert")  # sec. 3
    if "xtoon_d" in interp:
        detail = np.clip(interp["xtoon_d"], 0.0, 1.0)
    elif "xtoon_flow" in interp:  # |interpolated flow| -> D
        detail = detail_values(cfg.p, record, camera, flow=interp["xtoon_flow"])
    else:
        detail = d_at_pixels(n)
    return Evaluated(mask, tone, detail, n, weight)


def _pixel_weight(cfg, gb, mask, n0, d_at_pixels, at) -> Any:
    """The shape weight at the samples: a scalar, or (K,) where it varies locally (sec. 5)."""
    spec = cfg.p.shape_weight
    if spec.kind == "global":
        return spec.value
    if spec.kind == "detail":
        return 1.0 - d_at_pixels(n0)  # same attribute map as the tone detail, mesh normals
    if spec.kind == "texture":
        uv = at("uv") * np.asarray(spec.uv_scale)
        return np.clip(sample_level(cfg.weight_pyramid, uv, 0, dtype=np.float64), 0.0, 1.0)
    return _sample_grid(spec.texture, gb, "shape_weight")[mask]
