"""The parameters of the toon and smooth styles, each declared once."""

from __future__ import annotations

from refnpr.styles._declare import Param, Params

__all__ = ["TOON", "SMOOTH"]

_SPECULAR = (
    "include the specular term of eq. 1 (Blinn-Phong with each object's shininess; needs the "
    "position channel for V)"
)

TOON = Params(
    "toon",
    Param(
        "n",
        2,
        "steps of T_n (eq. 4): the diffuse term takes the n + 1 values k / n",
        kind="int",
        lo=1,
        hi=256,
    ),
    Param(
        "t", 0.5, "threshold within each step (eq. 3's t; 0.5 is Lake's suggestion)", lo=0.0, hi=1.0
    ),
    Param(
        "mode",
        "step",
        "step: eq. 2 with eq. 4's T_n on both terms; lake: Lake et al. "
        "2000's hard-edged ramp of n + 1 tones split at (k + t) / n (nearest texel)",
        kind="choice",
        choices=("step", "lake"),
    ),
    Param(
        "specular",
        True,
        _SPECULAR + ", thresholded by T_n (step mode only)",
        kind="bool",
        used_when={"mode": ("step",)},
    ),
    module=__name__,
    name="TOON",
)

SMOOTH = Params(
    "smooth",
    Param("specular", True, _SPECULAR, kind="bool"),
    Param(
        "model",
        "blinn-phong",
        "specular model of f_s: max(N.H, 0)^p or max(R.V, 0)^p",
        kind="choice",
        choices=("blinn-phong", "phong"),
    ),
    module=__name__,
    name="SMOOTH",
)
