"""Kit export of the material colour maps (``Material.color_texture``) that the ``smooth`` and
``toon`` styles multiply m_a and m_d by (:mod:`refnpr.styles.albedo`): each distinct map's
linear-RGB mip levels as the texture role ``color_<k>``, the role of each object in
``params.color_texture`` and the derived text ``color_texture``."""

from __future__ import annotations

from pathlib import Path
from typing import Any

from refnpr.styles.albedo import color_pyramid, uses_color_textures

from ..textures import write_pyramid

__all__ = ["COLOR_TEXTURE", "color_derived", "export_color_maps"]

#: How a backend takes a sample's colour map factor a (the derived text ``color_texture``).
COLOR_TEXTURE = (
    "Colour maps (glTF baseColorTexture; params.color_texture holds one entry per object in the "
    "order of case.objects: a texture role, or null for an object without a map). Where the "
    "sample's object o has a role, a = its GL_LINEAR_MIPMAP_LINEAR sample, three channels "
    "(linear RGB as stored; the levels 0 .. L - 1 as exported, level 0 W0 x H0 texels: do not "
    "regenerate them): (u, v) = uv * m.uv_scale and the derivatives du'/dx = duv_dx * "
    "m.uv_scale, du'/dy = duv_dy * m.uv_scale componentwise (per IMAGE pixel, the channels as "
    "stored); rho = max(hypot(du'/dx W0, dv'/dx H0), hypot(du'/dy W0, dv'/dy H0)), lambda = "
    "log2(max(rho, 2^-64)) clamped to [0, L - 1], k0 = floor(lambda), k1 = min(k0 + 1, L - 1), "
    "f = lambda - k0; B_k = the GL_LINEAR / GL_REPEAT sample of level k (cols x rows): x = (u - "
    "floor(u)) cols - 0.5, y = (v - floor(v)) rows - 0.5, i = floor(x), j = floor(y), f_x = x - "
    "i, f_y = y - j, columns i, i + 1 and rows j, j + 1 taken modulo cols / rows, B = (1 - "
    "f_x)(1 - f_y) t[j][i] + f_x (1 - f_y) t[j][i+1] + (1 - f_x) f_y t[j+1][i] + f_x f_y "
    "t[j+1][i+1] (summed in that order), per channel; a = 0 + (1 - f) B_k0, then + f B_k1 "
    "where f > 0. Elsewhere a = (1, 1, 1). The shading then starts from rgb = (m.ambient * "
    "ambient) * a and adds (m.diffuse * a) * tone * lights[i].color for the diffuse term, "
    "channel by channel (the specular term is not scaled); a = 1 gives the texts above exactly."
)


def color_derived(scene: Any) -> dict[str, str]:
    """The derived text ``color_texture`` where ``scene`` has colour maps, else nothing."""
    return {"color_texture": COLOR_TEXTURE} if uses_color_textures(scene) else {}


def export_color_maps(scene: Any, case_dir: Path) -> tuple[list[str | None], dict[str, Any]]:
    """Each object's colour-map role (None: none) and the ``textures`` entries, written under
    ``case_dir/textures/color_<k>/``; ``([], {})`` for a scene without colour maps."""
    if not uses_color_textures(scene):
        return [], {}
    roles: dict[str, str] = {}
    textures: dict[str, Any] = {}
    per_object: list[str | None] = []
    for obj in scene.objects:
        name = obj.material.color_texture
        if name is None:
            per_object.append(None)
            continue
        if name not in roles:
            role = roles[name] = f"color_{len(roles)}"
            textures[role] = write_pyramid(
                case_dir,
                role,
                color_pyramid(name).levels,
                filter="linear_mipmap_linear",
                used_for=(
                    f"colour map {str(name)!r} (linear RGB, sRGB-decoded from the image), "
                    "multiplying m_a and m_d"
                ),
            )
        per_object.append(roles[name])
    return per_object, textures
