"""Raw checks of mesh files before trimesh reads them (why: :mod:`refnpr.scenes.loading`), and
of what it read. Each check raises :class:`BadMeshFile` (what is wrong; ``load_mesh`` adds the
path) and nothing else. The parsers are vectorized with numpy (C speed, no Python loop per line
or face), so checking costs about as much as trimesh's own read. A check returns ``None``, or
(OFF, which trimesh reads line by line) the vertices and triangles it parsed.
"""

from __future__ import annotations

from .common import FIX, BadMeshFile, check_geometry, zero_area_message
from .glb import _check_glb
from .obj import _check_obj
from .off import _check_off
from .ply import _check_ply
from .stl import _check_stl

__all__ = ["BadMeshFile", "CHECKS", "FIX", "check_geometry", "zero_area_message"]

#: Extension -> raw check of that format.
CHECKS = {
    "obj": _check_obj,
    "ply": _check_ply,
    "stl": _check_stl,
    "off": _check_off,
    "glb": _check_glb,
}
