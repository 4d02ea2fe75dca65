"""A case's tolerance as kit JSON (the golden suite's per-case keys, see refnpr.golden), and the
documented range of every key (what ``refnpr kit check`` accepts from a kit)."""

from __future__ import annotations

import math
from typing import Any

__all__ = [
    "COMPARE_ON",
    "DISCRETE_CHANNELS",
    "GBUFFER_TOLERANCE",
    "IMAGE_TOLERANCE",
    "MAX_DISCRETE_PIXELS",
    "MAX_POSITION_DEVIATION",
    "tolerance_entry",
    "validate_tolerance",
]

COMPARE_ON = "srgb8 composited over black by alpha, as refnpr.compare"
#: Integer channels compared exactly (except ``discrete_max_pixels`` samples).
DISCRETE_CHANNELS = ("tri_id", "mesh_id", "coverage_count")

#: Largest ``position_deviation`` (pixels): the compare costs (2 N + 1)^2 passes over the image.
MAX_POSITION_DEVIATION = 8
#: Largest ``discrete.<channel>.max_pixels``.
MAX_DISCRETE_PIXELS = 2**31 - 1

#: Image cases: key -> (type, lowest, highest, default; None: required). Ranges are inclusive.
IMAGE_TOLERANCE: dict[str, tuple[type, float, float, Any]] = {
    "threshold": (float, 0.0, 1.0, None),
    "max_frac_over": (float, 0.0, 1.0, None),
    "min_ssim": (float, -1.0, 1.0, None),
    "position_deviation": (int, 0, MAX_POSITION_DEVIATION, 0),
}
#: G-buffer cases: as :data:`IMAGE_TOLERANCE`, plus ``discrete`` (see :func:`validate_tolerance`).
GBUFFER_TOLERANCE: dict[str, tuple[type, float, float, Any]] = {
    "rtol": (float, 0.0, 1.0, None),
    "atol": (float, 0.0, 1e6, None),
    "max_frac_over": (float, 0.0, 1.0, 0.0),
}


def _value(tol: dict[str, Any], key: str, spec: tuple[type, float, float, Any]) -> float | int:
    kind, lo, hi, default = spec
    v = tol.get(key, default)
    if kind is int:
        ok = isinstance(v, int) and not isinstance(v, bool) and lo <= v <= hi
        want = f"an integer in [{lo}, {hi}]"
    else:
        ok = (
            isinstance(v, (int, float))
            and not isinstance(v, bool)
            and math.isfinite(v)
            and lo <= v <= hi
        )
        want = f"a finite number in [{lo:g}, {hi:g}]"
    if not ok:
        got = "nothing (the key is missing)" if key not in tol else repr(v)
        raise ValueError(f"tolerance.{key}: expected {want}, got {_short(got)}")
    return int(v) if kind is int else float(v)


def _short(text: str, limit: int = 80) -> str:
    return text if len(text) <= limit else text[: limit - 3] + "..."


def validate_tolerance(tol: Any, kind: str) -> dict[str, Any]:
    """A case's ``tolerance`` checked against the documented ranges.

    Parameters
    ----------
    tol : Any
        ``tolerance`` of a case.json, as parsed.
    kind : {"image", "gbuffer"}
        The case's kind.

    Returns
    -------
    dict
        Image: ``threshold``, ``max_frac_over``, ``min_ssim`` (floats), ``position_deviation``
        (int, default 0), and when given ``max_flip`` (the largest mean FLIP that passes, in
        [0, 1]: only then does FLIP decide) and ``compare_on``. G-buffer: ``rtol``, ``atol``,
        ``max_frac_over`` (default 0) and ``discrete`` ({channel: {"max_pixels": int}},
        default {}; a bare integer stands for ``{"max_pixels": K}``).

    Raises
    ------
    ValueError
        Naming the key (``tolerance.position_deviation``), the value and the range: a value
        out of range, NaN or infinite, of the wrong type, a required key missing, an unknown key
        (a kit newer than this refnpr) or a ``compare_on`` other than :data:`COMPARE_ON`.
    """
    if not isinstance(tol, dict):
        raise ValueError(f"tolerance: expected an object, got {_short(repr(tol))}")
    spec = IMAGE_TOLERANCE if kind == "image" else GBUFFER_TOLERANCE
    extra = {"compare_on", "max_flip"} if kind == "image" else {"discrete"}
    unknown = sorted(set(tol) - set(spec) - extra)
    if unknown:
        raise ValueError(
            f"tolerance: unknown key(s) {_short(repr(unknown))} for a {kind} case (known: "
            f"{', '.join(sorted(set(spec) | extra))}); a newer refnpr may know them"
        )
    out: dict[str, Any] = {key: _value(tol, key, s) for key, s in spec.items()}
    if kind == "image":
        if "max_flip" in tol:  # optional: FLIP decides too only where a case says so
            out["max_flip"] = _value(tol, "max_flip", (float, 0.0, 1.0, None))
        if "compare_on" in tol:
            if tol["compare_on"] != COMPARE_ON:
                raise ValueError(
                    f"tolerance.compare_on: this refnpr compares {COMPARE_ON!r}, the kit says "
                    f"{_short(repr(tol['compare_on']))}"
                )
            out["compare_on"] = COMPARE_ON
        return out
    discrete = tol.get("discrete", {})
    if discrete is None:
        discrete = {}
    if not isinstance(discrete, dict):
        raise ValueError(
            f"tolerance.discrete: expected an object {{channel: {{'max_pixels': K}}}}, got "
            f"{_short(repr(discrete))}"
        )
    out["discrete"] = {}
    for ch, entry in discrete.items():
        key = f"discrete.{ch}.max_pixels"
        v = entry.get("max_pixels", 0) if isinstance(entry, dict) else entry
        if isinstance(v, bool) or not isinstance(v, int) or not 0 <= v <= MAX_DISCRETE_PIXELS:
            raise ValueError(
                f"tolerance.{_short(repr(key)[1:-1])}: expected an integer in "
                f"[0, {MAX_DISCRETE_PIXELS}], got {_short(repr(v))}"
            )
        out["discrete"][ch] = {"max_pixels": v}
    return out


def tolerance_entry(case: Any) -> dict[str, Any]:
    """``tolerance`` of case.json for a ``refnpr.golden.GoldenCase``.

    Image cases: ``threshold`` (per-channel |diff| on sRGB values in [0, 1]), ``max_frac_over``,
    ``min_ssim``, ``position_deviation`` (pixels, Chebyshev), ``compare_on``. G-buffer cases:
    ``rtol``, ``atol``, ``max_frac_over`` (fraction of samples of a float channel allowed
    outside rtol/atol) and ``discrete`` ({channel: {"max_pixels": K}}) for the integer channels.

    Raises
    ------
    ValueError
        A value outside the range ``refnpr kit check`` accepts (:func:`validate_tolerance`), so
        that no kit is exported that its own checker refuses.
    """
    if case.kind == "gbuffer":
        entry = {
            "rtol": float(case.rtol),
            "atol": float(case.atol),
            "max_frac_over": float(case.max_frac_over),
            "discrete": {
                ch: {"max_pixels": int(case.discrete_max_pixels)}
                for ch in case.channels
                if ch in DISCRETE_CHANNELS
            },
        }
    else:
        entry = {
            "threshold": float(case.tolerance),
            "max_frac_over": float(case.max_frac_over),
            "min_ssim": float(case.min_ssim),
            "position_deviation": int(case.position_deviation),
            "compare_on": COMPARE_ON,
        }
    validate_tolerance(entry, case.kind)
    return entry
