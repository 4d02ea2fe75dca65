"""Texture pyramids in one float storage buffer, filtered in the shader from the texels.

Styles that must sample the kit's mip levels exactly as refnpr does (GL_REPEAT bilinear per
level, texel centres at (i + 0.5) / size, linear between levels, weights in the shader's "real"
precision) pack every level into a float buffer with :class:`TexelBuffer` and compile
:data:`PYRAMID_GLSL` (``shaders/common/pyramid.glsl``) into their shader: the sampler hardware's
filtering weights have only 8 fractional bits on common GPUs. Used by the ``threshold`` style
(gray pyramids) and by the colour maps of ``smooth`` and ``toon``
(:mod:`refnpr_glsl.color_maps`, RGB pyramids).

Layout: level ``k`` of pyramid ``g`` is ``lv = LV0[g] + k``, ``LV_ROWS[lv]`` x ``LV_COLS[lv]``
texels of ``channels`` floats each, row-major (row 0 = v 0, channels interleaved), starting at
``DATA[LV_OFF[lv]]``; ``NLEV[g]`` levels. :meth:`TexelBuffer.tables` writes those five constant
arrays as GLSL.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

__all__ = ["TexelBuffer", "PYRAMID_GLSL", "glsl_int_array"]

#: The shared GLSL: ``wrap_i``, ``bilinear_taps`` and ``level_weights``. It needs, before it,
#: ``real`` / ``rvec2`` (float or double) and the constants of :meth:`TexelBuffer.tables`.
PYRAMID_GLSL = Path(__file__).resolve().parent / "shaders" / "common" / "pyramid.glsl"


def glsl_int_array(name: str, values: list[int]) -> str:
    """``const int NAME[n] = int[](...);`` (one 0 when ``values`` is empty: GLSL has no empty
    arrays)."""
    body = ", ".join(str(int(v)) for v in values) or "0"
    return f"const int {name}[{max(1, len(values))}] = int[]({body});\n"


class TexelBuffer:
    """The float storage buffer of a shader: texture pyramids and tables, with offsets.

    Attributes
    ----------
    size : int
        Floats appended so far.
    lv_off, lv_rows, lv_cols : list of int
        Per level (all pyramids, in order): offset in floats, rows, columns.
    lv0, nlev : list of int
        Per pyramid: index of its level 0 in the lists above, number of levels.
    pyramids : list of list of ndarray
        Per pyramid its levels as packed (float32; (rows, cols) or (rows, cols, C)).
    """

    def __init__(self) -> None:
        self.chunks: list[np.ndarray] = []
        self.size = 0
        self.lv_off: list[int] = []
        self.lv_rows: list[int] = []
        self.lv_cols: list[int] = []
        self.lv0: list[int] = []
        self.nlev: list[int] = []
        self.pyramids: list[list[np.ndarray]] = []

    def add(self, arr: np.ndarray) -> int:
        """Append ``arr`` (any shape, as float32, C order); returns its offset in floats."""
        flat = np.ascontiguousarray(arr, dtype=np.float32).ravel()
        off = self.size
        self.chunks.append(flat)
        self.size += flat.size
        return off

    def add_pyramid(self, levels: list[np.ndarray], role: str, channels: int = 1) -> int:
        """Append a pyramid; returns its pyramid index ``g``.

        Parameters
        ----------
        levels : list of ndarray
            Level 0 first; each (rows, cols) or (rows, cols, 1) for ``channels`` = 1, else
            (rows, cols, channels); uint8 levels are read as value / 255.
        role : str
            The texture role (for error messages).
        channels : int
            Floats per texel.

        Raises
        ------
        ValueError
            No level, or a level of another shape, or holding a non-finite value.
        """
        if not levels:
            raise ValueError(f"texture {role!r}: no mip level (the kit lists none)")
        self.lv0.append(len(self.lv_off))
        self.nlev.append(len(levels))
        self.pyramids.append([])
        for k, raw in enumerate(levels):
            lv = np.asarray(raw)
            lv = lv.astype(np.float32) / 255.0 if lv.dtype == np.uint8 else lv.astype(np.float32)
            if lv.ndim == 3 and lv.shape[2] == 1 and channels == 1:
                lv = lv[..., 0]
            want = "a gray (H, W)" if channels == 1 else f"an (H, W, {channels})"
            ok = lv.ndim == 2 if channels == 1 else lv.ndim == 3 and lv.shape[2] == channels
            if not ok or lv.shape[0] < 1 or lv.shape[1] < 1:
                raise ValueError(
                    f"texture {role!r} level {k}: expected {want} level, got shape {lv.shape}"
                )
            if not np.isfinite(lv).all():
                raise ValueError(
                    f"texture {role!r} level {k}: holds non-finite values (NaN or inf); "
                    "re-export the kit"
                )
            self.pyramids[-1].append(lv)
            self.lv_off.append(self.add(lv))
            self.lv_rows.append(int(lv.shape[0]))
            self.lv_cols.append(int(lv.shape[1]))
        return len(self.lv0) - 1

    def tables(self) -> str:
        """The GLSL constants ``LV0``, ``NLEV``, ``LV_OFF``, ``LV_ROWS``, ``LV_COLS``."""
        return "".join(
            glsl_int_array(name, values)
            for name, values in (
                ("LV0", self.lv0),
                ("NLEV", self.nlev),
                ("LV_OFF", self.lv_off),
                ("LV_ROWS", self.lv_rows),
                ("LV_COLS", self.lv_cols),
            )
        )

    def array(self) -> np.ndarray:
        """The buffer's contents, (size,) float32 (one 0 when empty)."""
        if not self.chunks:
            return np.zeros(1, dtype=np.float32)
        return np.concatenate(self.chunks)
