"""Raw checks of mesh files before trimesh reads them, and of what it read.

trimesh silently drops non-finite vertices with their faces, reads a truncated ASCII PLY as a
partial mesh and reports a truncated binary STL with an unrelated message; these parsers check
each file against its own format first. Every check raises :class:`BadMeshFile` (what is wrong)
and never anything else; :func:`refnpr.scenes.load_mesh` adds the path.

The parsers are vectorized with numpy (one pass of C code per element, not a Python loop per
line or face), so that checking costs about as much as trimesh's own read. A check returns
``None``, or (OFF, which trimesh reads line by line) the vertices and triangles it parsed.
"""

from __future__ import annotations

from .common import FIX, BadMeshFile, check_geometry
from .glb import _check_glb
from .obj import _check_obj
from .off import _check_off
from .ply import _check_ply
from .stl import _check_stl

__all__ = ["BadMeshFile", "CHECKS", "FIX", "check_geometry"]

#: Extension -> raw check of that format.
CHECKS = {
    "obj": _check_obj,
    "ply": _check_ply,
    "stl": _check_stl,
    "off": _check_off,
    "glb": _check_glb,
}
