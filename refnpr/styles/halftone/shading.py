"""Target intensity of the ``halftone`` style: lighting, individual stroke lighting (DOT3 bump
mapping of a stroke normal map, Freudenberg sec. 5.2) and indication maps (sec. 5.1).

All functions work on the N selected samples of one object, flattened: arrays (N, ...) float64.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from refnpr.formulas import halftone, lighting

__all__ = [
    "LUMA",
    "tangent_frame",
    "lit_intensity",
    "parse_indication",
    "sample_indication",
]

#: Rec. 709 luminance weights: the target intensity of a coloured light or material.
LUMA = np.array(lighting.LUMA_709)


def tangent_frame(
    n: np.ndarray, dp_dx: np.ndarray, dp_dy: np.ndarray, duv_dx: np.ndarray, duv_dy: np.ndarray
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Orthonormal (T, B) along +u and +v in the tangent plane of N, and a validity mask.

    ``[dP/dx dP/dy] = [dP/du dP/dv] J`` with ``J = [[du/dx, du/dy], [dv/dx, dv/dy]]``, so
    ``dP/du = (dP/dx dv/dy - dP/dy dv/dx) / det J`` and ``dP/dv = (dP/dy du/dx - dP/dx du/dy) /
    det J``; then Gram-Schmidt against N (the handedness of (u, v) is kept). Invalid where J is
    singular or a tangent vanishes (edge-on views, degenerate uv).

    Returns
    -------
    T, B : (N, 3) float64 unit vectors (0 where invalid); valid : (N,) bool
    """
    ux, vx = duv_dx[:, 0], duv_dx[:, 1]
    uy, vy = duv_dy[:, 0], duv_dy[:, 1]
    det = ux * vy - uy * vx
    ok = np.abs(det) > 1e-20
    inv = np.divide(1.0, det, out=np.zeros_like(det), where=ok)
    p_u = (dp_dx * vy[:, None] - dp_dy * vx[:, None]) * inv[:, None]
    p_v = (dp_dy * ux[:, None] - dp_dx * uy[:, None]) * inv[:, None]
    t = p_u - np.sum(p_u * n, axis=-1, keepdims=True) * n
    t_len = np.linalg.norm(t, axis=-1, keepdims=True)
    t = np.divide(t, t_len, out=np.zeros_like(t), where=t_len > 1e-30)
    b = (
        p_v
        - np.sum(p_v * n, axis=-1, keepdims=True) * n
        - np.sum(p_v * t, axis=-1, keepdims=True) * t
    )
    b_len = np.linalg.norm(b, axis=-1, keepdims=True)
    b = np.divide(b, b_len, out=np.zeros_like(b), where=b_len > 1e-30)
    valid = ok & (t_len[:, 0] > 1e-30) & (b_len[:, 0] > 1e-30)
    return t, b, valid


def lit_intensity(
    ctx: Any,
    sel: np.ndarray,
    n: np.ndarray,
    *,
    specular: bool,
    bump: tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray] | None = None,
) -> np.ndarray:
    """Target intensity ``I = lum(m_a l_a + sum m_d f_d l_i + sum m_s f_s l_i)`` in [0, 1] of the
    samples ``sel`` (flat indices into the sample grid), with the diffuse term of Veryovka eq. 1.

    With ``bump = (normal_map (N, 3) RGB-encoded, T, B, valid)`` the diffuse term is the DOT3
    stroke lighting ``clip(N_map . L_t, 0, 1)`` (:func:`refnpr.formulas.halftone.stroke_lighting`)
    with ``L_t = (L.T, L.B, L.N)`` the light in the tangent frame (sec. 5.2); samples without a
    valid frame keep ``f_d(N, L)``.

    Returns
    -------
    (N,) float64
    """
    m_a = ctx.material_field("ambient").reshape(-1, 3)[sel]
    m_d = ctx.material_field("diffuse").reshape(-1, 3)[sel]
    rgb = m_a * np.asarray(ctx.scene.ambient, dtype=np.float64)  # Veryovka eq. 1: ambient
    if specular:
        m_s = ctx.material_field("specular").reshape(-1, 3)[sel]
        shin = ctx.material_field("shininess").reshape(-1)[sel]
        v = ctx.view_dir().reshape(-1, 3)[sel]
    for light_dir, color in ctx.light_dirs():
        ld = light_dir.reshape(-1, 3)[sel] if np.ndim(light_dir) > 1 else light_dir
        f_d = lighting.diffuse(n, ld)
        if bump is not None:
            nmap, t, b, valid = bump
            ldb = np.broadcast_to(ld, n.shape)
            l_t = np.stack([np.sum(ldb * t, -1), np.sum(ldb * b, -1), np.sum(ldb * n, -1)], axis=-1)
            lit = halftone.stroke_lighting(nmap, l_t, encoded=True, normalize=True)  # sec. 5.2
            f_d = np.where(valid, lit, f_d)
        rgb = rgb + m_d * f_d[:, None] * color
        if specular:
            f_s = np.zeros(n.shape[0])
            for p in np.unique(shin[shin > 0]):
                k = shin == p
                ldk = ld[k] if np.ndim(ld) > 1 else ld
                f_s[k] = lighting.specular(n[k], ldk, v[k], shininess=float(p))
            rgb = rgb + m_s * f_s[:, None] * color
    lum = lighting.luminance(rgb)
    return np.clip(lum, 0.0, 1.0)


def parse_indication(value: Any, where: str = "indication") -> np.ndarray | None:
    """An indication map: None, a (rows, cols) nested list of signed values in [-1, 1], or a
    gray image path (value ``2 g - 1``, so mid-grey is 0). Returns (rows, cols) float64."""
    if value is None:
        return None
    if isinstance(value, str):
        path = Path(value)
        if not path.is_file():
            raise ValueError(
                f"{where}: {value!r} is not an existing image file; give a gray PNG (mid-grey = "
                "no change) or a nested list of signed values"
            )
        from refnpr.texture import load_texture

        return 2.0 * load_texture(path, param="indication").astype(np.float64) - 1.0
    try:
        arr = np.array(value, dtype=np.float64)
    except (TypeError, ValueError):
        raise TypeError(
            f"{where}: expected a nested list of numbers (rows of a low-resolution signed map) "
            f"or an image path, got {value!r}"
        ) from None
    if arr.ndim == 1:
        arr = arr[None, :]
    if arr.ndim != 2 or arr.size == 0:
        raise ValueError(
            f"{where}: expected rows of equal length (a 2-D map), got shape {arr.shape}"
        )
    if not np.all(np.isfinite(arr)) or np.any(np.abs(arr) > 1.0):
        raise ValueError(
            f"{where}: expected signed values in [-1, 1] (0 = no change, > 0 lighter, < 0 darker), "
            f"got range [{arr.min()}, {arr.max()}]"
        )
    return arr


def sample_indication(imap: np.ndarray, uv: np.ndarray) -> np.ndarray:
    """Bilinear, clamp-to-edge samples (N,) of an indication map over uv in [0, 1]^2 (texel
    centres at (i + 0.5) / size; u along columns, v along rows)."""
    rows, cols = imap.shape
    x = np.clip(uv[:, 0] * cols - 0.5, 0.0, cols - 1)
    y = np.clip(uv[:, 1] * rows - 0.5, 0.0, rows - 1)
    x0 = np.minimum(np.floor(x).astype(np.int64), cols - 1)
    y0 = np.minimum(np.floor(y).astype(np.int64), rows - 1)
    x1, y1 = np.minimum(x0 + 1, cols - 1), np.minimum(y0 + 1, rows - 1)
    fx, fy = x - x0, y - y0
    top = imap[y0, x0] * (1 - fx) + imap[y0, x1] * fx
    bot = imap[y1, x0] * (1 - fx) + imap[y1, x1] * fx
    return top * (1 - fy) + bot * fy
