"""``refnpr kit check``: compare a backend's renders with an exported conformance kit.

For every case of ``KIT_DIR/index.json`` the checker reads the case's ``case.json`` (its
``expected`` files and its own ``tolerance``) and the backend's output in ``RENDERS_DIR``: image
cases ``<name>.png`` (8-bit sRGB RGBA) and optionally ``<name>.exr`` (float32 linear
straight-alpha RGBA); G-buffer cases ``<name>/<channel>.npy`` for every channel of ``expected``.

An image case passes when the fraction of pixels failing the two-sided position-tolerant compare
(:func:`position_tolerant_mismatch`) is at most ``tolerance.max_frac_over`` and the mean SSIM of
luminance at least ``tolerance.min_ssim``; a G-buffer case when every channel is within
``rtol``/``atol`` (discrete channels: exact but ``max_pixels``). docs/kit.md ("How ``refnpr kit
check`` decides") states every rule and reported metric.
"""

from __future__ import annotations

import json
import math
from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from ..compare import compare_images, load_image
from ..image import linear_to_srgb
from . import KIT_FORMAT, KIT_VERSION
from ._json import jsonable, write_json

__all__ = ["CaseCheck", "Visual", "check_kit", "format_table", "position_tolerant_mismatch", "run"]


@dataclass(frozen=True)
class CaseCheck:
    """The verdict on one case.

    Attributes
    ----------
    name, kind : str
        The case and ``"image"`` or ``"gbuffer"``.
    passed : bool
        Whether the case meets its own tolerance (see the module docstring for the rule).
    status : str
        ``"ok"`` (compared; ``passed`` says the verdict), ``"missing"`` (no render),
        ``"unreadable"`` (a render that cannot be decoded), ``"size"`` (a render of the wrong
        size or shape), ``"channels"`` (a G-buffer channel missing) or ``"kit"`` (the kit's own
        files for the case are missing or invalid).
    message : str
        Why it failed, or the deciding numbers against their limits when it was compared.
    metrics : dict of str to float
        Image cases: ``max_abs``, ``rmse``, ``frac_over``, ``frac_over_position``,
        ``frac_over_position_cts``, ``ssim`` and, with an EXR render, ``linear_max_abs``,
        ``linear_rmse``, ``linear_frac_over``. G-buffer cases: the worst channel's ``frac_bad``.
    channels : dict of str to dict
        G-buffer cases: per channel ``{"kind": "float"|"discrete", "max_abs", "bad_pixels",
        "frac_bad" (float: fraction of bad elements; discrete: of bad pixels),
        "allowed_frac"|"allowed_pixels", "nonfinite_mismatch" (float), "passed"}``.
    tolerance : dict
        The case's ``tolerance`` from ``case.json``.
    images : dict of str to str
        Report files of the case (``"reference"``, ``"result"``, ``"diff16"``, ``"mask"``),
        relative to the report directory; filled by :func:`check_kit` when it writes a report.
    """

    name: str
    kind: str
    passed: bool
    status: str
    message: str
    metrics: dict[str, float] = field(default_factory=dict)
    channels: dict[str, dict[str, Any]] = field(default_factory=dict)
    tolerance: dict[str, Any] = field(default_factory=dict)
    images: dict[str, str] = field(default_factory=dict)

    @property
    def error(self) -> float:
        """One number to sort by: the deciding fraction of bad pixels (inf when not compared)."""
        if self.status != "ok":
            return math.inf
        if self.kind == "gbuffer":
            return float(self.metrics.get("frac_bad", 0.0))
        return float(self.metrics.get("frac_over_position", math.inf))

    def to_json(self) -> dict[str, Any]:
        """A JSON-able dict (non-finite numbers as ``None``)."""
        d = asdict(self)
        d["error"] = self.error
        return jsonable(d, where=self.name, nonfinite_as_none=True)


# -- the position-tolerant compare -------------------------------------------------------------


def _matches(
    a: np.ndarray, b: np.ndarray, threshold: float, deviation: int
) -> tuple[np.ndarray, np.ndarray]:
    """(H, W) bool: which pixels of ``a`` and of ``b`` match a pixel of the other image within
    ``deviation`` (both directions in one pass: each pair is compared once, credited to both)."""
    h, w = a.shape[:2]
    ca = np.ascontiguousarray(np.moveaxis(a, -1, 0))  # (C, H, W): fast per-channel planes
    cb = np.ascontiguousarray(np.moveaxis(b, -1, 0))
    a_matched = np.zeros((h, w), dtype=bool)
    b_matched = np.zeros((h, w), dtype=bool)
    for dy in range(-deviation, deviation + 1):
        ya = slice(max(0, -dy), h - max(0, dy))
        yb = slice(max(0, dy), h - max(0, -dy))
        for dx in range(-deviation, deviation + 1):
            xa = slice(max(0, -dx), w - max(0, dx))
            xb = slice(max(0, dx), w - max(0, -dx))
            close = np.abs(ca[0, ya, xa] - cb[0, yb, xb]) <= threshold
            for c in range(1, ca.shape[0]):
                close &= np.abs(ca[c, ya, xa] - cb[c, yb, xb]) <= threshold
            a_matched[ya, xa] |= close
            b_matched[yb, xb] |= close
    return a_matched, b_matched


def position_tolerant_mismatch(
    reference: np.ndarray,
    result: np.ndarray,
    *,
    threshold: float,
    deviation: int,
    symmetric: bool = True,
) -> np.ndarray:
    """Pixels that fail the position-tolerant threshold compare (Vulkan CTS fuzzy compare).

    Parameters
    ----------
    reference, result : (H, W, C) float
        The images to compare, same shape (refnpr compares sRGB values composited over black,
        alpha as the last channel).
    threshold : float
        Largest per-channel absolute difference that still matches.
    deviation : int
        N >= 0: a pixel matches when some pixel of the other image within Chebyshev distance N
        (inside the image) is within ``threshold`` on every channel. N = 0 is the plain
        per-pixel compare.
    symmetric : bool
        True (refnpr's rule): a pixel fails when the result pixel matches no reference pixel
        within N or the reference pixel matches no result pixel within N. False: only the first
        test (what the CTS does).

    Returns
    -------
    (H, W) bool
        True where the pixel fails.

    Raises
    ------
    ValueError
        Shapes that differ or are not (H, W, C); a negative or non-integer ``deviation``; a
        negative or non-finite ``threshold``.
    """
    reference, result = np.asarray(reference), np.asarray(result)
    if reference.ndim != 3 or reference.shape != result.shape:
        raise ValueError(
            f"reference, result: expected two (H, W, C) arrays of one shape, got "
            f"{reference.shape} and {result.shape}"
        )
    if isinstance(deviation, bool) or not isinstance(deviation, (int, np.integer)) or deviation < 0:
        raise ValueError(f"deviation: expected an integer >= 0 (pixels), got {deviation!r}")
    if not (isinstance(threshold, (int, float)) and math.isfinite(threshold) and threshold >= 0):
        raise ValueError(f"threshold: expected a finite number >= 0, got {threshold!r}")
    result_ok, reference_ok = _matches(result, reference, threshold, int(deviation))
    return ~(result_ok & reference_ok) if symmetric else ~result_ok


def composite_over_black(rgba: np.ndarray) -> np.ndarray:
    """(H, W, 4) float64: colour multiplied by alpha, alpha kept (what refnpr.compare compares)."""
    out = np.array(rgba, dtype=np.float64)
    out[..., :3] *= out[..., 3:4]
    return out


# -- reading the kit and the renders -----------------------------------------------------------


class _CaseError(Exception):
    """A case cannot be compared: carries the status and the message."""

    def __init__(self, status: str, message: str) -> None:
        super().__init__(message)
        self.status = status
        self.message = message


@contextmanager
def _failing(status: str) -> Iterator[None]:
    """A ValueError inside (a file that cannot be read) fails the case with ``status``."""
    try:
        yield
    except ValueError as exc:
        raise _CaseError(status, str(exc)) from None


def _read_exr_rgba(path: str | Path, *, what: str) -> np.ndarray:
    """(H, W, 4) float32 RGBA of an OpenEXR file with R, G, B (A: 1 when absent) channels;
    ValueError naming ``what`` and the file when it is missing, unreadable or lacks them."""
    p = Path(path)
    if not p.is_file():
        why = "is a directory" if p.is_dir() else "does not exist"
        raise ValueError(f"{what}: {str(p)!r} {why}; expected an OpenEXR file")
    try:
        import OpenEXR
    except ImportError:  # pragma: no cover -- the kit extra installs it
        raise ValueError(
            f"{what}: cannot read {str(p)!r}: the OpenEXR package is missing; "
            "pip install 'refnpr[kit]'"
        ) from None
    try:
        with OpenEXR.File(str(p), separate_channels=True) as f:
            ch = {k: np.asarray(v.pixels) for k, v in f.channels().items()}
    except Exception as exc:  # noqa: BLE001 -- OpenEXR raises RuntimeError and others
        first = (str(exc).strip().splitlines() or [type(exc).__name__])[0]
        raise ValueError(
            f"{what}: cannot read {str(p)!r}: {first}; expected an OpenEXR file"
        ) from None
    if not {"R", "G", "B"} <= set(ch):
        raise ValueError(f"{what}: {str(p)!r} has channels {sorted(ch)}; expected R, G, B (and A)")
    a = ch.get("A", np.ones_like(ch["R"]))
    return np.stack([ch["R"], ch["G"], ch["B"], a], axis=-1).astype(np.float32)


def _read_index(kit_dir: Path) -> list[dict[str, Any]]:
    if not kit_dir.is_dir():
        why = "it is a file" if kit_dir.exists() else "it does not exist"
        raise ValueError(f"kit_dir: {str(kit_dir)!r} is not a directory ({why})")
    index = kit_dir / "index.json"
    if not index.is_file():
        raise ValueError(
            f"kit_dir: {str(kit_dir)!r} has no index.json; export a kit with `refnpr kit export DIR`"
        )
    try:
        data = json.loads(index.read_text())
    except (OSError, UnicodeDecodeError, json.JSONDecodeError) as exc:
        raise ValueError(f"{str(index)!r}: not valid JSON ({exc})") from None
    if not isinstance(data, dict) or data.get("format") != KIT_FORMAT:
        raise ValueError(f'{str(index)!r}: expected {{"format": "{KIT_FORMAT}", ...}}')
    if data.get("version") != KIT_VERSION:
        raise ValueError(
            f"{str(index)!r}: kit format version {data.get('version')!r}; this refnpr reads version {KIT_VERSION}"
        )
    cases = data.get("cases")
    if not isinstance(cases, list) or not cases:
        raise ValueError(f"{str(index)!r}: 'cases' must be a non-empty list, got {cases!r}")
    for i, c in enumerate(cases):
        if not isinstance(c, dict) or not isinstance(c.get("name"), str):
            raise ValueError(f"{str(index)!r}: cases[{i}] has no 'name': {c!r}")
    return cases


def _read_case(kit_dir: Path, entry: dict[str, Any]) -> tuple[Path, dict[str, Any]]:
    rel = entry.get("case", f"{entry['name']}/case.json")
    path = kit_dir / rel
    try:
        data = json.loads(path.read_text())
    except FileNotFoundError:
        raise _CaseError("kit", f"the kit has no {str(path)!r}") from None
    except (OSError, UnicodeDecodeError, json.JSONDecodeError) as exc:
        raise _CaseError("kit", f"cannot read {str(path)!r}: {exc}") from None
    if not isinstance(data, dict):
        raise _CaseError("kit", f"{str(path)!r}: expected a JSON object")
    return path, data


def _number(tol: dict[str, Any], key: str, where: str, lo: float, hi: float, default=None) -> float:
    v = tol.get(key, default)
    if isinstance(v, bool) or not isinstance(v, (int, float)) or not lo <= v <= hi:
        raise _CaseError(
            "kit", f"{where}: tolerance.{key}: expected a number in [{lo}, {hi}], got {v!r}"
        )
    return float(v)


def _count(v: Any, key: str, where: str) -> int:
    if isinstance(v, bool) or not isinstance(v, int) or v < 0:
        raise _CaseError("kit", f"{where}: tolerance.{key}: expected an integer >= 0, got {v!r}")
    return v


def _size_error(path: Path, got: tuple, want: tuple, extra: str = "") -> _CaseError:
    return _CaseError(
        "size",
        f"render {str(path)!r} is {got[1]}x{got[0]}, the case is {want[1]}x{want[0]}{extra}",
    )


# -- image cases -------------------------------------------------------------------------------


@dataclass
class Visual:
    """What the report shows of a case besides its verdict (filled as far as the check got).

    Attributes
    ----------
    reference, result : (H, W, 4) float64 or None
        Image cases: sRGB values composited over black, alpha last. G-buffer cases: a gray
        visualisation of one channel (``label`` says which), normalised by the expected range.
    bad : (H, W) bool or None
        The deciding per-pixel verdict (True: the pixel fails).
    empty : (H, W) bool or None
        Both pixels are background (image: the case's background colour; G-buffer: tri_id -1).
    label : str
        What ``reference``/``result`` show.
    """

    reference: np.ndarray | None = None
    result: np.ndarray | None = None
    bad: np.ndarray | None = None
    empty: np.ndarray | None = None
    label: str = "sRGB over black"


def _check_image(
    name: str, case_path: Path, case: dict[str, Any], tol: dict, renders_dir: Path, data: Visual
) -> CaseCheck:
    where = str(case_path)
    threshold = _number(tol, "threshold", where, 0.0, 1.0)
    max_frac = _number(tol, "max_frac_over", where, 0.0, 1.0)
    min_ssim = _number(tol, "min_ssim", where, -1.0, 1.0)
    dev = _count(tol.get("position_deviation", 0), "position_deviation", where)
    expected = case.get("expected")
    if not isinstance(expected, dict) or not isinstance(expected.get("png"), str):
        raise _CaseError("kit", f"{where}: 'expected.png' must name the expected PNG")
    ref_path = case_path.parent / expected["png"]
    with _failing("kit"):
        ref = load_image(ref_path, what="expected image (kit)")
    data.reference = composite_over_black(ref)
    res_path = renders_dir / f"{name}.png"
    if not res_path.exists():
        raise _CaseError("missing", f"no render {str(res_path)!r}")
    with _failing("unreadable"):
        res = load_image(res_path, what="render")
    if res.shape != ref.shape:
        raise _size_error(res_path, res.shape, ref.shape, f" ({str(ref_path)!r})")
    data.result = composite_over_black(res)
    m = compare_images(ref, res, name=name, tolerance=threshold)
    result_ok, reference_ok = _matches(data.result, data.reference, threshold, dev)
    bad = ~(result_ok & reference_ok)  # the two-sided verdict that decides
    cts = ~result_ok  # the CTS's one-sided verdict, reported
    data.bad = bad
    data.empty = _empty(case, data.reference, data.result, threshold)
    metrics = {
        "max_abs": m.max_abs,
        "rmse": m.rmse,
        "frac_over": m.frac_over,
        "frac_over_position": float(bad.mean()),
        "frac_over_position_cts": float(cts.mean()),
        "ssim": m.ssim,
    }
    ok = metrics["frac_over_position"] <= max_frac and metrics["ssim"] >= min_ssim
    msg = (
        f"frac_over_position={metrics['frac_over_position']:.5f} (allowed {max_frac:g}, "
        f"N={dev}) ssim={metrics['ssim']:.4f} (min {min_ssim:g})"
    )
    exr_path = renders_dir / f"{name}.exr"
    if exr_path.exists():
        try:
            metrics.update(_linear_metrics(case_path, expected, exr_path, ref.shape, threshold))
        except _CaseError as exc:  # the PNG's metrics stay in the record
            message = f"{exc.message} (PNG: {msg})"
            return CaseCheck(name, "image", False, exc.status, message, metrics, tolerance=tol)
    return CaseCheck(name, "image", ok, "ok", msg, metrics=metrics, tolerance=tol)


def _empty(case: dict[str, Any], ref: np.ndarray, res: np.ndarray, threshold: float) -> np.ndarray:
    """(H, W) bool: both pixels are the case's background (within the threshold)."""
    bg = case.get("background", [0.0, 0.0, 0.0, 0.0])
    try:
        bg = np.asarray(bg, dtype=np.float64).reshape(4)
    except (TypeError, ValueError):
        bg = np.zeros(4)
    enc = np.concatenate([linear_to_srgb(bg[:3]) * np.clip(bg[3], 0, 1), [np.clip(bg[3], 0, 1)]])
    near = threshold + 0.5 / 255  # the background after 8-bit rounding
    return (np.abs(ref - enc).max(axis=-1) <= near) & (np.abs(res - enc).max(axis=-1) <= near)


def _linear_metrics(
    case_path: Path, expected: dict[str, Any], exr_path: Path, shape: tuple, threshold: float
) -> dict[str, float]:
    lin = expected.get("linear")
    if not isinstance(lin, str):
        raise _CaseError("kit", f"{case_path}: 'expected.linear' must name the expected EXR")
    with _failing("kit"):
        ref = _read_exr_rgba(case_path.parent / lin, what="expected linear image (kit)")
    with _failing("unreadable"):
        res = _read_exr_rgba(exr_path, what="render (EXR)")
    if res.shape != ref.shape or ref.shape[:2] != shape[:2]:
        raise _size_error(exr_path, res.shape, ref.shape)
    if not np.all(np.isfinite(res)):
        raise _CaseError("unreadable", f"render {str(exr_path)!r} holds NaN or inf")
    a, b = composite_over_black(ref), composite_over_black(res)
    d = np.abs(a - b)

    def enc(x: np.ndarray) -> np.ndarray:
        return np.concatenate([linear_to_srgb(x[..., :3]), np.clip(x[..., 3:], 0, 1)], axis=-1)

    return {
        "linear_max_abs": float(d.max()),
        "linear_rmse": float(np.sqrt(np.mean(d**2))),
        "linear_frac_over": float(np.mean(np.abs(enc(a) - enc(b)).max(axis=-1) > threshold)),
    }


# -- G-buffer cases ----------------------------------------------------------------------------


def _check_gbuffer(
    name: str, case_path: Path, case: dict[str, Any], tol: dict, renders_dir: Path, data: Visual
) -> CaseCheck:
    where = str(case_path)
    rtol = _number(tol, "rtol", where, 0.0, 1.0)
    atol = _number(tol, "atol", where, 0.0, math.inf)
    max_frac = _number(tol, "max_frac_over", where, 0.0, 1.0, default=0.0)
    discrete = tol.get("discrete", {}) or {}
    if not isinstance(discrete, dict):
        raise _CaseError("kit", f"{where}: tolerance.discrete must be an object, got {discrete!r}")
    expected = case.get("expected")
    chans = expected.get("channels") if isinstance(expected, dict) else None
    if not isinstance(chans, dict) or not chans:
        raise _CaseError("kit", f"{where}: 'expected.channels' must map channel -> file")
    missing = [c for c in chans if not (renders_dir / name / f"{c}.npy").is_file()]
    if len(missing) == len(chans) and not (renders_dir / name).is_dir():
        raise _CaseError("missing", f"no render directory {str(renders_dir / name)!r}")
    if missing:
        raise _CaseError(
            "channels",
            f"render {str(renders_dir / name)!r} lacks channel(s) {missing} (.npy files)",
        )
    per: dict[str, dict[str, Any]] = {}
    for ch, entry in chans.items():
        file = entry.get("file") if isinstance(entry, dict) else entry
        if not isinstance(file, str):
            raise _CaseError("kit", f"{where}: expected.channels.{ch}: no 'file'")
        exp = _load_npy(case_path.parent / file, "kit", "expected channel (kit)")
        got = _load_npy(renders_dir / name / f"{ch}.npy", "unreadable", "render channel")
        if got.shape != exp.shape:
            raise _CaseError(
                "size",
                f"channel {ch!r}: render {str(renders_dir / name / (ch + '.npy'))!r} has shape "
                f"{got.shape}, the kit {exp.shape}",
            )
        is_discrete = ch in discrete or exp.dtype.kind in "iub"
        if is_discrete:
            spec = discrete.get(ch, {})
            allowed = spec.get("max_pixels", 0) if isinstance(spec, dict) else spec
            allowed = _count(allowed, f"discrete.{ch}.max_pixels", where)
            bad = exp != got
            diff = np.abs(exp.astype(np.float64) - got.astype(np.float64))
            rec = {"kind": "discrete", "allowed_pixels": allowed}
        else:
            fa, fb = np.isfinite(exp), np.isfinite(got)
            pattern, both = fa != fb, fa & fb
            close = np.isclose(got[both], exp[both], rtol=rtol, atol=atol)
            frac = float(np.mean(~close)) if close.size else 0.0  # as refnpr.golden counts
            bad = pattern.copy()
            bad[both] = ~close
            diff = np.zeros(exp.shape)
            np.subtract(exp, got, out=diff, where=both, dtype=np.float64)
            diff = np.abs(diff)
            n_pattern = int(pattern.sum())
            rec = {"kind": "float", "allowed_frac": max_frac, "nonfinite_mismatch": n_pattern}
        bad_px = bad.any(axis=-1) if bad.ndim == 3 else bad
        n_bad = int(bad_px.sum())
        if is_discrete:
            frac, passed = n_bad / max(bad_px.size, 1), n_bad <= allowed
        else:
            passed = frac <= max_frac and not pattern.any()
        max_abs = float(diff.max()) if diff.size else 0.0
        rec.update(max_abs=max_abs, bad_pixels=n_bad, frac_bad=frac, passed=bool(passed))
        per[ch] = rec
        _accumulate(data, ch, exp, got, bad_px)
    failed = [c for c, r in per.items() if not r["passed"]]
    worst = max((r["frac_bad"] for r in per.values()), default=0.0)
    msg = (
        "all channels within tolerance"
        if not failed
        else f"beyond rtol={rtol:g} atol={atol:g}: "
        + "; ".join(_channel_failure(c, per[c]) for c in failed)
    )
    metrics = {"frac_bad": worst}
    return CaseCheck(name, "gbuffer", not failed, "ok", msg, metrics, per, tol)


def _channel_failure(ch: str, r: dict[str, Any]) -> str:
    """One channel's failure in a few words: bad pixels against what was allowed."""
    if r["kind"] == "discrete":
        return f"{ch}: {r['bad_pixels']} bad pixel(s) (allowed {r['allowed_pixels']})"
    text = f"{ch}: {r['bad_pixels']} bad pixel(s), frac {r['frac_bad']:.3g} (allowed {r['allowed_frac']:g})"
    if r["nonfinite_mismatch"]:
        text += f", {r['nonfinite_mismatch']} non-finite mismatch(es)"
    return text


def _accumulate(
    data: Visual, ch: str, exp: np.ndarray, got: np.ndarray, bad_px: np.ndarray
) -> None:
    """Fold one channel into the case's visual: bad pixels, empty pixels, a gray preview."""
    if data.bad is None:
        data.bad = np.zeros(bad_px.shape[:2], dtype=bool)
    if bad_px.shape[:2] != data.bad.shape:
        return  # a channel on another grid (none in refnpr today) is not drawn in the mask
    data.bad |= bad_px
    if ch == "tri_id":
        e = (exp == -1) & (got == -1)
        data.empty = e.all(axis=-1) if e.ndim == 3 else e
    preview = ch == "depth" or (data.reference is None and exp.dtype.kind == "f")
    if preview:
        a = exp.astype(np.float64)
        a = a if a.ndim == 2 else np.linalg.norm(a, axis=-1)
        b = got.astype(np.float64)
        b = b if b.ndim == 2 else np.linalg.norm(b, axis=-1)
        fin = a[np.isfinite(a)]
        lo, hi = (float(fin.min()), float(fin.max())) if fin.size else (0.0, 1.0)
        scale = 1.0 / (hi - lo) if hi > lo else 1.0

        def gray(x: np.ndarray) -> np.ndarray:
            g = np.clip(np.nan_to_num((x - lo) * scale, nan=0.0, posinf=1.0, neginf=0.0), 0, 1)
            return np.stack([g, g, g, np.ones_like(g)], axis=-1)

        data.reference, data.result = gray(a), gray(b)
        data.label = f"{ch} (normalised{', |v|' if exp.ndim == 3 else ''})"


def _load_npy(path: Path, status: str, what: str) -> np.ndarray:
    try:
        return np.load(path, allow_pickle=False)
    except FileNotFoundError:
        raise _CaseError(status, f"{what}: {str(path)!r} does not exist") from None
    except Exception as exc:  # noqa: BLE001 -- numpy raises many types on corrupt files
        first = (str(exc).strip().splitlines() or [type(exc).__name__])[0]
        raise _CaseError(status, f"{what}: cannot read {str(path)!r}: {first}") from None


# -- the whole kit -----------------------------------------------------------------------------


def check_kit(
    kit_dir: str | Path,
    renders_dir: str | Path,
    *,
    report_dir: str | Path | None = None,
    json_path: str | Path | None = None,
) -> list[CaseCheck]:
    """Compare a backend's renders with every case of an exported kit.

    Parameters
    ----------
    kit_dir : str or path
        An exported kit (``refnpr kit export``): ``index.json`` and ``<case>/case.json``.
    renders_dir : str or path
        The backend's output: ``<case>.png`` (optionally ``<case>.exr``) per image case,
        ``<case>/<channel>.npy`` per G-buffer case.
    report_dir : str or path, optional
        Writes ``index.html`` and, per case, ``cases/<case>/{reference,result,diff16,mask}.png``.
    json_path : str or path, optional
        Writes ``{"kit", "renders", "summary": {cases, passed, failed}, "cases": [...]}``, each
        case as :meth:`CaseCheck.to_json`.

    Returns
    -------
    list of CaseCheck
        One per case, in ``index.json`` order. A case whose render is missing, unreadable or of
        the wrong size fails with the reason; so does a case whose kit files are broken.

    Raises
    ------
    ValueError
        ``kit_dir`` is not a kit (no or invalid ``index.json``), ``renders_dir`` is not a
        directory, ``report_dir`` is a file or ``json_path`` is a directory.
    """
    kit_dir, renders_dir = Path(kit_dir), Path(renders_dir)
    entries = _read_index(kit_dir)
    if not renders_dir.is_dir():
        why = "it is a file" if renders_dir.exists() else "it does not exist"
        raise ValueError(f"renders_dir: {str(renders_dir)!r} is not a directory ({why})")
    if report_dir is not None and Path(report_dir).exists() and not Path(report_dir).is_dir():
        raise ValueError(f"report_dir: {str(report_dir)!r} is a file; expected a directory")
    if json_path is not None and Path(json_path).is_dir():
        raise ValueError(
            f"json_path: {str(json_path)!r} is a directory; give a file name such as "
            f"{str(Path(json_path) / 'check.json')!r}"
        )
    results: list[CaseCheck] = []
    report_cases = []
    for entry in entries:
        name = entry["name"]
        kind = entry.get("kind", "image")
        data = Visual()
        try:
            case_path, case = _read_case(kit_dir, entry)
            kind = case.get("kind", kind)
            check = {"image": _check_image, "gbuffer": _check_gbuffer}.get(kind)
            if check is None:
                raise _CaseError(
                    "kit", f"{case_path}: kind must be 'image' or 'gbuffer', got {kind!r}"
                )
            tol = case.get("tolerance")
            if not isinstance(tol, dict):
                raise _CaseError("kit", f"{case_path}: 'tolerance' must be an object, got {tol!r}")
            r = check(name, case_path, case, tol, renders_dir, data)
        except _CaseError as exc:
            r = CaseCheck(name, str(kind), False, exc.status, exc.message)
        results.append(r)
        report_cases.append((r, data))
    if report_dir is not None:
        from .report import write_report

        results = write_report(
            Path(report_dir), report_cases, kit_dir=kit_dir, renders_dir=renders_dir
        )
    if json_path is not None:
        passed = sum(r.passed for r in results)
        summary = {"cases": len(results), "passed": passed, "failed": len(results) - passed}
        cases = [r.to_json() for r in results]
        doc = {"kit": str(kit_dir), "renders": str(renders_dir), "summary": summary, "cases": cases}
        write_json(json_path, doc)
    return results


def format_table(results: list[CaseCheck]) -> str:
    """Plain-text table: one line per case and the reason under each failure."""
    lines = [
        f"{'case':44s} {'kind':7s} {'result':6s} {'status':10s} {'max_abs':>8s} {'rmse':>8s} "
        f"{'frac>thr':>9s} {'pos.frac':>9s} {'ssim':>7s}"
    ]
    for r in results:
        m = r.metrics
        nums = " ".join(
            f"{m[k]:{w}.{p}f}" if k in m else f"{'-':>{w}s}"
            for k, w, p in (
                ("max_abs", 8, 4),
                ("rmse", 8, 5),
                ("frac_over", 9, 5),
                ("frac_over_position", 9, 5),
                ("ssim", 7, 4),
            )
        )
        if r.kind == "gbuffer" and r.status == "ok":
            nums = f"{'':8s} {'':8s} {'':9s} {m.get('frac_bad', 0.0):9.5f} {'':7s}"
        verdict = "PASS" if r.passed else "FAIL"
        lines.append(f"{r.name:44s} {r.kind:7s} {verdict:6s} {r.status:10s} {nums}")
        if not r.passed:
            lines.append(f"    {r.message}")
    passed = sum(r.passed for r in results)
    lines.append(f"{len(results)} cases: {passed} passed, {len(results) - passed} failed")
    return "\n".join(lines)


def run(args: Any) -> int:
    """The ``refnpr kit check`` command: print the table, write the report/JSON, exit status.

    ``args`` has ``kit_dir``, ``renders_dir``, ``report`` (directory or None) and ``json``
    (file or None). Returns 0 when every case passes, 1 otherwise.
    """
    results = check_kit(
        args.kit_dir,
        args.renders_dir,
        report_dir=getattr(args, "report", None),
        json_path=getattr(args, "json", None),
    )
    print(format_table(results))
    names = {r.name for r in results}
    extra = sorted(
        p.name for p in Path(args.renders_dir).glob("*.png") if p.name[: -len(".png")] not in names
    )
    if extra:
        print(
            f"note: {len(extra)} render(s) without a case in the kit, not compared: "
            + ", ".join(extra)
        )
    if getattr(args, "report", None) is not None:
        print(f"report: {Path(args.report) / 'index.html'}")
    return 0 if all(r.passed for r in results) else 1
