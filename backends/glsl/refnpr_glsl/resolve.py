"""Composite and resolve, as refnpr's ``render``: per sample premultiplied "over" the background,
the n x n box mean, then unpremultiply (rgb / alpha where alpha > 0); sRGB encoding as
refnpr.image (IEC 61966-2-1, rounded to nearest, linear alpha).
"""

from __future__ import annotations

import moderngl
import numpy as np

from .context import GL

__all__ = ["resolve", "linear_to_srgb", "to_srgb8"]

_RESOLVE = """
#version 450 core
uniform sampler2D samples;
out vec4 o_rgba;
void main() {
    ivec2 p = ivec2(gl_FragCoord.xy) * N;
    dvec4 bg = dvec4(BG.rgb * BG.a, BG.a);  // background, premultiplied
    dvec4 acc = dvec4(0.0LF);
    for (int j = 0; j < N; ++j)
        for (int i = 0; i < N; ++i) {
            dvec4 s = dvec4(texelFetch(samples, p + ivec2(i, j), 0));
            acc += dvec4(s.rgb * s.a, s.a) + bg * (1.0LF - s.a);  // premultiplied over
        }
    acc /= double(N * N);  // box resolve
    dvec3 rgb = acc.a > 0.0LF ? acc.rgb / acc.a : dvec3(0.0LF);  // unpremultiply
    o_rgba = vec4(vec3(rgb), float(acc.a));
}
"""


def resolve(gl: GL, samples: moderngl.Texture, n: int, background: np.ndarray) -> moderngl.Texture:
    """(W, H) RGBA32F straight-alpha linear pixels from (n W, n H) per-sample RGBA."""
    nw, nh = samples.size
    out = gl.empty((nw // n, nh // n), 4, "f4")
    bg = ", ".join(f"{float(v)!r}LF" for v in np.asarray(background, np.float64).reshape(4))
    head = f"#version 450 core\nconst int N = {int(n)};\nconst dvec4 BG = dvec4({bg});"
    gl.fullscreen(_RESOLVE.replace("#version 450 core", head), out, {"samples": samples})
    return out


def linear_to_srgb(x: np.ndarray) -> np.ndarray:
    """IEC 61966-2-1 sRGB transfer function (linear [0, 1] -> encoded [0, 1]), float64."""
    x = np.clip(np.asarray(x, dtype=np.float64), 0.0, 1.0)
    return np.where(x <= 0.0031308, 12.92 * x, 1.055 * np.power(x, 1.0 / 2.4) - 0.055)


def to_srgb8(rgba: np.ndarray) -> np.ndarray:
    """(H, W, 4) uint8: sRGB-encoded colour, linear alpha, rounded to nearest (refnpr.image)."""
    out = np.empty(rgba.shape, dtype=np.uint8)
    out[..., :3] = np.rint(linear_to_srgb(rgba[..., :3]) * 255.0)
    out[..., 3] = np.rint(np.clip(rgba[..., 3], 0.0, 1.0) * 255.0)
    return out
