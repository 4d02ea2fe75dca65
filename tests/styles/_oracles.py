"""Numpy oracles of the shading inputs the kernels compute from the frame record: the view and
light directions per sample, each object's f_s, and straight-alpha RGBA assembly."""

from __future__ import annotations

import numpy as np

from refnpr.formulas import lighting


def _unit(d: np.ndarray) -> np.ndarray:
    length = np.linalg.norm(d, axis=-1, keepdims=True)
    return np.divide(d, length, out=np.zeros_like(d), where=length > 0)


def view_dir(ctx, mask: np.ndarray | None = None) -> np.ndarray:
    """Unit vectors towards the eye: (nH, nW, 3) float64, or (K, 3) where ``mask``."""
    pos = ctx.gb["position"] if mask is None else ctx.gb["position"][mask]
    return _unit(np.asarray(ctx.scene.camera.eye, dtype=np.float64) - pos)


def light_dirs(ctx, mask: np.ndarray | None = None) -> list[tuple[np.ndarray, np.ndarray]]:
    """Per light: (unit direction towards it, (3,) or per sample for a point light), colour."""
    out = []
    for light in ctx.scene.lights:
        if light.kind == "point":
            pos = ctx.gb["position"] if mask is None else ctx.gb["position"][mask]
            d = _unit(np.asarray(light.position, dtype=np.float64) - pos)
        else:
            d = np.asarray(light.direction, dtype=np.float64)
            d = d / np.linalg.norm(d)
        out.append((d, np.asarray(light.color, dtype=np.float64)))
    return out


def specular_field(ctx, n, light_dir, v, model="blinn-phong", mask=None) -> np.ndarray:
    """f_s of Veryovka eq. 1 with each object's own shininess; 0 where shininess <= 0."""
    shininess = ctx.material_field("shininess", mask)
    out = np.zeros(n.shape[:-1])
    for p in np.unique(shininess[shininess > 0]):
        sel = shininess == p
        ld = light_dir[sel] if np.ndim(light_dir) > 1 else light_dir
        out[sel] = lighting.specular(
            n[sel], ld, v[sel], shininess=float(p), model=model, normalize=False
        )
    return out


def scatter_rgba(rgb: np.ndarray, mask: np.ndarray, alpha: np.ndarray | None = None) -> np.ndarray:
    """(nH, nW, 4) float32 RGBA from the colours ``rgb (K, 3)`` of the samples where ``mask``."""
    out = np.zeros(mask.shape + (4,), dtype=np.float32)
    out[mask, :3] = np.clip(rgb, 0.0, 1.0)
    out[mask, 3] = 1.0 if alpha is None else np.clip(alpha, 0.0, 1.0)
    return out
