"""Material colour maps (``Material.color_texture``, glTF's ``baseColorTexture``) per sample.

A colour map multiplies the material's colour: the styles that shade with m_a and m_d
(``smooth``, ``toon``) use ``m_a a`` and ``m_d a`` at a sample whose object has one, with ``a``
the map's linear RGB there. ``a`` is the GL_LINEAR_MIPMAP_LINEAR sample
(:func:`refnpr.device.sampling.trilinear`, GL_REPEAT) of the map's box-filtered mip pyramid at
the sample's uv times the material's ``uv_scale``, at the isotropic LOD of OpenGL 4.x sec. 8.14
(:func:`refnpr.device.sampling.gl_lod`) of the scaled per-pixel uv derivatives. The pyramid is
built from the image's values decoded from sRGB to linear (an 8-bit colour image, as glTF
stores base colours, is sRGB-encoded), RGB only: a grey image gives a = (g, g, g), alpha is
ignored.
"""

from __future__ import annotations

import os
import threading
from collections import OrderedDict
from typing import Any

import numpy as np

from refnpr.image import srgb_to_linear
from refnpr.texture import EmbeddedImage, MipPyramid, build_pyramid, load_texture

from . import _kernels as K

__all__ = [
    "ALBEDO_CHANNELS",
    "albedo_channels",
    "albedo_grid",
    "color_pyramid",
    "uses_color_textures",
]

#: G-buffer channels a colour map reads.
ALBEDO_CHANNELS = frozenset({"mesh_id", "uv", "duv_dx", "duv_dy"})
#: Built pyramids kept across frames (a sequence's frames, a kit export's cases), keyed by the
#: embedded image's digest, or the file's path, size and modification time (an edited file is
#: read again). At most this many bytes of texels; least recently used out first.
_PYRAMIDS: OrderedDict[tuple, MipPyramid] = OrderedDict()
_PYRAMIDS_BYTES = 512 << 20
_LOCK = threading.Lock()


def uses_color_textures(scene: Any) -> bool:
    """Whether some object of ``scene`` has a ``Material.color_texture``."""
    return any(o.material.color_texture is not None for o in scene.objects)


def albedo_channels(scene: Any) -> frozenset[str]:
    """The G-buffer channels the colour maps of ``scene`` read (:data:`ALBEDO_CHANNELS`; none
    without maps).

    Raises
    ------
    ValueError
        Some object has a colour map and some mesh has no texture coordinates: the rasterizer
        interpolates uv for every mesh of a frame. Names both.
    """
    if not uses_color_textures(scene):
        return frozenset()
    bare = [o.name for o in scene.objects if o.mesh.uv is None]
    if bare:
        mapped = next(o.name for o in scene.objects if o.material.color_texture is not None)
        raise ValueError(
            f"color_texture: object {mapped!r} has a colour map, so every mesh of the scene "
            f"needs texture coordinates (uv is rasterized for all of them), but {bare} have "
            "none; give them uv (refnpr.scenes.project_uv(mesh, 'planar'|'box'|'spherical'|"
            "'cylindrical'), or zeros where nothing samples them)"
        )
    return ALBEDO_CHANNELS


def _key(name: str) -> tuple:
    if isinstance(name, EmbeddedImage):
        return ("embedded", name.sha256)  # its bytes' digest
    if not os.path.isfile(name):
        return ("name", str(name))  # a built-in texture name (or an error to come)
    st = os.stat(name)
    return ("file", str(name), st.st_size, st.st_mtime_ns)


def color_pyramid(name: str) -> MipPyramid:
    """The linear-RGB mip pyramid of the colour map ``name`` (a file path, built-in texture
    name or :class:`~refnpr.texture.EmbeddedImage`): levels ``(rows, cols, 3)`` float32 in
    [0, 1], the image's values sRGB-decoded (RGB of a colour image; grey repeated; alpha
    dropped). Cached across calls; errors name ``color_texture``."""
    key = _key(name)
    with _LOCK:
        pyr = _PYRAMIDS.get(key)
        if pyr is not None:
            _PYRAMIDS.move_to_end(key)
            return pyr
    image = np.asarray(load_texture(name, gray=False, param="color_texture"))
    if image.ndim == 2:
        image = image[..., None]
    rgb = image[..., :3] if image.shape[2] >= 3 else image[..., :1]
    rgb = np.broadcast_to(rgb, image.shape[:2] + (3,))
    pyr = build_pyramid(srgb_to_linear(rgb).astype(np.float32))
    with _LOCK:
        _PYRAMIDS[key] = pyr
        _PYRAMIDS.move_to_end(key)
        while len(_PYRAMIDS) > 1 and sum(map(_nbytes, _PYRAMIDS.values())) > _PYRAMIDS_BYTES:
            _PYRAMIDS.popitem(last=False)
    return pyr


def _nbytes(pyr: MipPyramid) -> int:
    return sum(level.nbytes for level in pyr.levels)


def albedo_grid(ctx: Any) -> np.ndarray | None:
    """Per sample the colour map's factor ``a``, ``(nH, nW, 3)`` float64: the map's linear RGB
    where the sample's object has a colour map, 1 elsewhere (also where empty); None when no
    object of ``ctx.scene`` has one.

    Raises
    ------
    ValueError
        The G-buffer lacks a channel of :data:`ALBEDO_CHANNELS` (a mesh without texture
        coordinates under a colour map), or a map cannot be read.
    """
    scene, gb = ctx.scene, ctx.gb
    names = [o.material.color_texture for o in scene.objects]
    if all(n is None for n in names):
        return None
    missing = sorted(ALBEDO_CHANNELS - set(gb.channels))
    if missing:
        raise ValueError(
            f"color_texture: the G-buffer has no {', '.join(missing)}; an object with a colour "
            "map needs texture coordinates (give its mesh uv, or remove color_texture)"
        )
    out = np.ones(tuple(gb.sample_shape) + (3,))
    grids = tuple(np.ascontiguousarray(gb[c]) for c in ("mesh_id", "uv", "duv_dx", "duv_dy"))
    scale = np.array([o.material.uv_scale for o in scene.objects], dtype=np.float64)
    for name in dict.fromkeys(n for n in names if n is not None):
        marked = np.array([n is not None and n == name for n in names], dtype=np.bool_)
        K.sample_albedo(grids, (marked, scale), color_pyramid(name).packed(), out)
    return out
