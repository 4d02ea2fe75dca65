"""A case's tolerance as kit JSON (the golden suite's per-case keys, see refnpr.golden)."""

from __future__ import annotations

from typing import Any

__all__ = ["tolerance_entry", "COMPARE_ON", "DISCRETE_CHANNELS"]

COMPARE_ON = "srgb8 composited over black by alpha, as refnpr.compare"
#: Integer channels compared exactly (except ``discrete_max_pixels`` samples).
DISCRETE_CHANNELS = ("tri_id", "mesh_id", "coverage_count")


def tolerance_entry(case: Any) -> dict[str, Any]:
    """``tolerance`` of case.json for a ``refnpr.golden.GoldenCase``.

    Image cases: ``threshold`` (per-channel |diff| on sRGB values in [0, 1]), ``max_frac_over``,
    ``min_ssim``, ``position_deviation`` (pixels, Chebyshev), ``compare_on``. G-buffer cases:
    ``rtol``, ``atol``, ``max_frac_over`` (fraction of samples of a float channel allowed
    outside rtol/atol) and ``discrete`` ({channel: {"max_pixels": K}}) for the integer channels.
    """
    if case.kind == "gbuffer":
        return {
            "rtol": float(case.rtol),
            "atol": float(case.atol),
            "max_frac_over": float(case.max_frac_over),
            "discrete": {
                ch: {"max_pixels": int(case.discrete_max_pixels)}
                for ch in case.channels
                if ch in DISCRETE_CHANNELS
            },
        }
    return {
        "threshold": float(case.tolerance),
        "max_frac_over": float(case.max_frac_over),
        "min_ssim": float(case.min_ssim),
        "position_deviation": int(case.position_deviation),
        "compare_on": COMPARE_ON,
    }
