"""What a style's kit exporter returns (interface A of the conformance kit)."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

__all__ = ["StyleExport"]


@dataclass
class StyleExport:
    """A style's contribution to ``case.json`` and the case's files.

    Attributes
    ----------
    params : dict
        JSON data: EVERY parameter resolved to the value used (no "auto", preset data inlined;
        textures referenced by role name).
    textures : dict
        role -> texture entry (from :func:`refnpr.kit.textures.write_texture_levels`); the
        files are already written under ``case_dir/textures/<role>/``.
    derived : dict
        name -> one paragraph: how a backend derives what is not in the files.
    vertex_attributes : dict
        ``{object_index: {name: (N, C) or (N,) float array}}``: extra per-vertex data written
        to that object's .glb as the attribute ``"_" + name.upper()`` (N = the mesh's vertex
        count).
    frames : list or None
        Multi-frame cases only (optical flow, frame history): case.json's ``frames``, a list of
        ``{"frame": i, "camera": refnpr.kit.camera.camera_entry(...), "objects": [{"name",
        "mesh"}]}``, the last being the frame whose image is expected.
    """

    params: dict[str, Any]
    textures: dict[str, dict[str, Any]] = field(default_factory=dict)
    derived: dict[str, str] = field(default_factory=dict)
    vertex_attributes: dict[int, dict[str, np.ndarray]] = field(default_factory=dict)
    frames: list[dict[str, Any]] | None = None
