"""The OpenGL context of the backend: a headless EGL OpenGL 4.5 core context (moderngl) and the
few operations every pass needs (textures from arrays, full-screen passes, read-backs).

Array layout everywhere: texel (x, y) of a texture is ``array[y, x]`` and y = 0 is the TOP image
row (refnpr's layout). Uploads write ``array`` row 0 as texel row 0 and read-backs return texel
row 0 as ``array[0]``, so nothing is ever flipped; in a full-screen pass over a W x H target
``ivec2(gl_FragCoord.xy)`` is ``(x, y_array)``.
"""

from __future__ import annotations

import ctypes
import ctypes.util
from collections.abc import Mapping, Sequence
from typing import Any

import moderngl
import numpy as np

__all__ = ["GL", "FULLSCREEN_VERTEX", "DTYPES"]

#: Our dtype names -> (moderngl dtype, numpy dtype).
DTYPES: dict[str, tuple[str, np.dtype]] = {
    "f4": ("f4", np.dtype(np.float32)),
    "i4": ("i4", np.dtype(np.int32)),
    "u1": ("f1", np.dtype(np.uint8)),  # normalized unsigned byte (sampled as float in [0, 1])
}

_FILTERS = {
    "nearest": (moderngl.NEAREST, moderngl.NEAREST),
    "linear": (moderngl.LINEAR, moderngl.LINEAR),
    "linear_mipmap_linear": (moderngl.LINEAR_MIPMAP_LINEAR, moderngl.LINEAR),
    "nearest_mipmap_nearest": (moderngl.NEAREST_MIPMAP_NEAREST, moderngl.NEAREST),
    "linear_mipmap_nearest": (moderngl.LINEAR_MIPMAP_NEAREST, moderngl.LINEAR),
    "nearest_mipmap_linear": (moderngl.NEAREST_MIPMAP_LINEAR, moderngl.NEAREST),
    # the style samples each level itself (texelFetch / its own filtering): nearest within a level
    "per_level": (moderngl.NEAREST_MIPMAP_NEAREST, moderngl.NEAREST),
}

#: A vertex shader drawing one triangle that covers the viewport (no vertex buffer needed).
FULLSCREEN_VERTEX = """
#version 450 core
void main() {
    vec2 p = vec2(float((gl_VertexID & 1) << 2) - 1.0, float((gl_VertexID & 2) << 1) - 1.0);
    gl_Position = vec4(p, 0.0, 1.0);
}
"""


def _check_dtype(dtype: str) -> tuple[str, np.dtype]:
    if dtype not in DTYPES:
        raise ValueError(f"dtype: expected one of {sorted(DTYPES)}, got {dtype!r}")
    return DTYPES[dtype]


class GL:
    """A headless OpenGL 4.5 core context and helpers.

    Parameters
    ----------
    ctx : moderngl.Context, optional
        Use this context instead of creating one.
    backend : str
        moderngl standalone backend ("egl": headless, Mesa llvmpipe on CPU or any EGL GPU driver).

    Attributes
    ----------
    ctx : moderngl.Context
    """

    def __init__(self, ctx: moderngl.Context | None = None, *, backend: str = "egl") -> None:
        if ctx is None:
            try:
                ctx = moderngl.create_standalone_context(backend=backend, require=450)
            except Exception as exc:  # noqa: BLE001 -- EGL/driver errors come in many types
                raise RuntimeError(
                    f"GL: cannot create a headless OpenGL 4.5 core context with backend "
                    f"{backend!r}: {exc}. Install libegl1 libgl1-mesa-dri libegl-mesa0 "
                    "(Mesa llvmpipe) or a GPU driver with EGL"
                ) from exc
        self.ctx = ctx
        self._programs: dict[tuple[str, str, str | None], moderngl.Program] = {}
        self._vao_empty: dict[int, moderngl.VertexArray] = {}

    # -- info ----------------------------------------------------------------------------------
    @property
    def renderer(self) -> str:
        """GL_RENDERER and GL_VERSION, e.g. ``"llvmpipe (LLVM 15.0.6, 256 bits) | 4.5 ..."``."""
        return f"{self.ctx.info['GL_RENDERER']} | {self.ctx.info['GL_VERSION']}"

    # -- programs ------------------------------------------------------------------------------
    def program(
        self, vertex: str, fragment: str | None = None, geometry: str | None = None
    ) -> moderngl.Program:
        """Compile (and cache by source) a program; GLSL errors raise ``RuntimeError`` with the log."""
        key = (vertex, fragment or "", geometry)
        prog = self._programs.get(key)
        if prog is None:
            try:
                prog = self.ctx.program(
                    vertex_shader=vertex, fragment_shader=fragment, geometry_shader=geometry
                )
            except moderngl.Error as exc:
                raise RuntimeError(f"GL: shader compilation failed:\n{exc}") from None
            self._programs[key] = prog
        return prog

    def compute(self, source: str) -> moderngl.ComputeShader:
        """Compile a compute shader (``#version 450 core``)."""
        try:
            return self.ctx.compute_shader(source)
        except moderngl.Error as exc:
            raise RuntimeError(f"GL: compute shader compilation failed:\n{exc}") from None

    # -- textures ------------------------------------------------------------------------------
    def texture_from_array(
        self,
        arr: np.ndarray,
        *,
        dtype: str | None = None,
        mip_levels: Sequence[np.ndarray] | None = None,
        wrap: str = "repeat",
        filter: str = "nearest",
    ) -> moderngl.Texture:
        """A 2D texture holding ``arr`` in array layout.

        Parameters
        ----------
        arr : (H, W) or (H, W, C) array, C in 1..4
            Level 0. Texel (x, y) = ``arr[y, x]``, y = 0 the top row (never flipped).
        dtype : {"f4", "i4", "u1"}, optional
            Texel type: float32 (R32F...), int32 (R32I..., sample with ``isampler2D``), or uint8
            normalized (R8...). Default: from ``arr.dtype`` (float -> f4, int -> i4, uint8 -> u1).
        mip_levels : sequence of arrays, optional
            Explicit mip levels: either levels 1, 2, ... or the full list with level 0 first
            (recognized when its first array has ``arr``'s shape). Each level halves the size
            (floor, at least 1). The texture's max level is the last one given.
        wrap : {"repeat", "clamp"}
        filter : {"nearest", "linear", "linear_mipmap_linear", "per_level", ...}
            GL min/mag filters (see ``_FILTERS``).

        Returns
        -------
        moderngl.Texture of size (W, H).
        """
        arr = np.asarray(arr)
        if arr.ndim not in (2, 3) or (arr.ndim == 3 and not 1 <= arr.shape[2] <= 4):
            raise ValueError(f"arr: expected shape (H, W) or (H, W, C<=4), got {arr.shape}")
        if dtype is None:
            if arr.dtype == np.uint8:
                dtype = "u1"
            elif arr.dtype.kind in "iub":
                dtype = "i4"
            else:
                dtype = "f4"
        mgl_dtype, np_dtype = _check_dtype(dtype)
        if wrap not in ("repeat", "clamp"):
            raise ValueError(f"wrap: expected 'repeat' or 'clamp', got {wrap!r}")
        if filter not in _FILTERS:
            raise ValueError(f"filter: expected one of {sorted(_FILTERS)}, got {filter!r}")
        h, w = arr.shape[:2]
        comps = 1 if arr.ndim == 2 else arr.shape[2]
        levels = list(mip_levels or [])
        if levels and np.asarray(levels[0]).shape == arr.shape:
            levels = levels[1:]
        tex = self.ctx.texture(
            (w, h), comps, np.ascontiguousarray(arr, dtype=np_dtype).tobytes(), dtype=mgl_dtype
        )
        if levels:
            tex.build_mipmaps(0, len(levels))  # allocates the levels; overwritten below
            lw, lh = w, h
            for i, lev in enumerate(levels, start=1):
                lev = np.asarray(lev)
                lw, lh = max(1, lw // 2), max(1, lh // 2)
                if lev.shape[:2] != (lh, lw):
                    raise ValueError(
                        f"mip_levels[{i - 1}]: level {i} of a {w} x {h} texture must be "
                        f"{lw} x {lh} (H, W = {lh}, {lw}), got shape {lev.shape}"
                    )
                tex.write(np.ascontiguousarray(lev, dtype=np_dtype).tobytes(), level=i)
        if dtype == "i4":
            tex.filter = (moderngl.NEAREST, moderngl.NEAREST)
        else:
            mn, mg = _FILTERS[filter]
            if not levels and mn not in (moderngl.NEAREST, moderngl.LINEAR):
                tex.build_mipmaps()  # GL-generated levels where the kit gives none
            tex.filter = (mn, mg)
        tex.repeat_x = tex.repeat_y = wrap == "repeat"
        return tex

    def empty(self, size: tuple[int, int], components: int, dtype: str = "f4") -> moderngl.Texture:
        """An uninitialized (W, H) texture of ``components`` (1..4) texels of ``dtype``."""
        mgl_dtype, _ = _check_dtype(dtype)
        if not 1 <= int(components) <= 4:
            raise ValueError(f"components: expected 1..4, got {components!r}")
        tex = self.ctx.texture(tuple(int(s) for s in size), int(components), dtype=mgl_dtype)
        tex.filter = (moderngl.NEAREST, moderngl.NEAREST)
        return tex

    def read(self, texture: moderngl.Texture, level: int = 0) -> np.ndarray:
        """Read a texture back: (H, W) for one component, else (H, W, C), array layout.

        float32 for float textures, int32 for integer ones, uint8 for normalized bytes.
        """
        dt = {"f4": np.float32, "i4": np.int32, "f1": np.uint8, "u4": np.uint32}.get(texture.dtype)
        if dt is None:
            raise TypeError(f"texture: cannot read dtype {texture.dtype!r}")
        w, h = texture.size
        for _ in range(level):
            w, h = max(1, w // 2), max(1, h // 2)
        data = np.frombuffer(texture.read(level=level, alignment=1), dtype=dt)
        c = texture.components
        return data.reshape((h, w) if c == 1 else (h, w, c)).copy()

    # -- raw GL (what moderngl does not expose) ---------------------------------------------
    def _gl(self, name: str, *argtypes):
        """A GL entry point through eglGetProcAddress (None when unavailable)."""
        if not hasattr(self, "_egl"):
            path = ctypes.util.find_library("EGL")
            self._egl = ctypes.CDLL(path) if path else None
            if self._egl is not None:
                self._egl.eglGetProcAddress.restype = ctypes.c_void_p
                self._egl.eglGetProcAddress.argtypes = [ctypes.c_char_p]
        if self._egl is None:
            return None
        addr = self._egl.eglGetProcAddress(name.encode())
        return ctypes.CFUNCTYPE(None, *argtypes)(addr) if addr else None

    def depth32f(self, fbo: moderngl.Framebuffer, size: tuple[int, int]) -> int | None:
        """Attach a new GL_DEPTH_COMPONENT32F texture to ``fbo`` (clear it with
        :meth:`clear_depth32f` after ``fbo.use()``); returns its
        GL name (release with :meth:`delete_texture`), or None where raw GL is unavailable
        (then use moderngl's 24-bit ``depth_texture``)."""
        c_uint, c_int, c_float_p = ctypes.c_uint, ctypes.c_int, ctypes.POINTER(ctypes.c_float)
        create = self._gl("glCreateTextures", c_uint, c_int, ctypes.POINTER(c_uint))
        storage = self._gl("glTextureStorage2D", c_uint, c_int, c_uint, c_int, c_int)
        attach = self._gl("glNamedFramebufferTexture", c_uint, c_uint, c_uint, c_int)
        clear = self._gl("glClearNamedFramebufferfv", c_uint, c_uint, c_int, c_float_p)
        status = self._gl("glCheckNamedFramebufferStatus", c_uint, c_uint)
        if None in (create, storage, attach, clear):
            return None
        tex = c_uint()
        create(0x0DE1, 1, ctypes.byref(tex))  # GL_TEXTURE_2D
        storage(tex.value, 1, 0x8CAC, int(size[0]), int(size[1]))  # GL_DEPTH_COMPONENT32F
        attach(fbo.glo, 0x8D00, tex.value, 0)  # GL_DEPTH_ATTACHMENT
        del status
        self._clear_depth = lambda: clear(fbo.glo, 0x1801, 0, ctypes.byref(ctypes.c_float(1.0)))
        return int(tex.value)

    def clear_depth32f(self) -> None:
        """Clear the depth texture of the last :meth:`depth32f` call to 1.0 (depth writes on:
        glClear honours glDepthMask, which moderngl turns off for its own framebuffers)."""
        self.depth_write(True)
        self._clear_depth()

    def depth_write(self, enable: bool = True) -> None:
        """glDepthMask: moderngl turns depth writes off for framebuffers it made without a depth
        attachment, so call this after ``fbo.use()`` on one with :meth:`depth32f`."""
        mask = self._gl("glDepthMask", ctypes.c_ubyte)
        if mask is not None:
            mask(1 if enable else 0)

    def delete_texture(self, name: int) -> None:
        """glDeleteTextures for a texture made by :meth:`depth32f`."""
        delete = self._gl("glDeleteTextures", ctypes.c_int, ctypes.POINTER(ctypes.c_uint))
        if delete is not None:
            delete(1, ctypes.byref(ctypes.c_uint(name)))

    # -- passes --------------------------------------------------------------------------------
    def _empty_vao(self, prog: moderngl.Program) -> moderngl.VertexArray:
        vao = self._vao_empty.get(id(prog))
        if vao is None:
            vao = self.ctx.vertex_array(prog, [])
            self._vao_empty[id(prog)] = vao
        return vao

    def bind(
        self,
        prog: moderngl.Program,
        textures: Mapping[str, moderngl.Texture] | None = None,
        uniforms: Mapping[str, Any] | None = None,
    ) -> None:
        """Bind sampler uniforms by name to texture units 0, 1, ... and set plain uniforms.

        Names the program does not use (optimized away) are ignored; a value for a uniform is
        converted (tuples/arrays become their flattened values).
        """
        for unit, (name, tex) in enumerate((textures or {}).items()):
            tex.use(location=unit)
            if name in prog:
                prog[name].value = unit
        for name, value in (uniforms or {}).items():
            if name not in prog:
                continue
            member = prog[name]
            if isinstance(value, np.ndarray):
                if value.dtype.kind == "f":
                    # GLSL matrices are column-major: write the transpose of a row-major matrix
                    v = value.T if value.ndim == 2 else value
                    fmt = "f8" if getattr(member, "fmt", "").endswith("d") else "f4"
                    member.write(np.ascontiguousarray(v, dtype=fmt).tobytes())
                else:
                    member.write(np.ascontiguousarray(value, dtype=np.int32).tobytes())
            else:
                member.value = value

    def fullscreen(
        self,
        fragment_source: str,
        target: moderngl.Texture | Sequence[moderngl.Texture],
        textures: Mapping[str, moderngl.Texture] | None = None,
        uniforms: Mapping[str, Any] | None = None,
        *,
        blend: bool = False,
    ) -> None:
        """Run a full-screen fragment pass over ``target`` (one texture, or several for MRT).

        Parameters
        ----------
        fragment_source : str
            ``#version 450 core`` fragment shader; output k goes to ``target[k]``. Matrices given
            as numpy (4, 4) arrays are row-major (uploaded transposed, i.e. as the same matrix).
        target : Texture or sequence of Texture
            Render targets, all of the same size (W, H).
        textures : dict name -> Texture
            Sampler uniforms bound by name.
        uniforms : dict name -> value
        blend : bool
            Additive blending (ONE, ONE) instead of overwriting.
        """
        targets = [target] if isinstance(target, moderngl.Texture) else list(target)
        prog = self.program(FULLSCREEN_VERTEX, fragment_source)
        fbo = self.ctx.framebuffer(color_attachments=targets)
        try:
            fbo.use()
            self.ctx.viewport = (0, 0, *targets[0].size)
            self.ctx.disable(moderngl.DEPTH_TEST | moderngl.CULL_FACE)
            if blend:
                self.ctx.enable(moderngl.BLEND)
                self.ctx.blend_func = moderngl.ONE, moderngl.ONE
            else:
                self.ctx.disable(moderngl.BLEND)
            self.bind(prog, textures, uniforms)
            self._empty_vao(prog).render(moderngl.TRIANGLES, vertices=3)
        finally:
            self.ctx.disable(moderngl.BLEND)
            fbo.release()

    def finish(self) -> None:
        """Wait for the GPU (glFinish)."""
        self.ctx.finish()

    def release(self) -> None:
        """Release the context and the programs compiled on it."""
        for p in self._programs.values():
            p.release()
        self._programs.clear()
        self.ctx.release()
