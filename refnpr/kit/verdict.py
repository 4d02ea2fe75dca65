"""The verdict on one case of a conformance kit: the case's files read within the limits of
:mod:`refnpr.kit.limits` (headers checked before decoding), compared with the render under the
case's own tolerance. :mod:`refnpr.kit.check` runs it over a kit; docs/kit.md ("How ``refnpr kit
check`` decides") states every rule and reported metric.
"""

from __future__ import annotations

import math
import os
from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from .._reading import inside, printable, read_regular
from ..compare import LEVEL_SLACK, compare_images
from ..image import decode_png16, is_png16_colour, linear_to_srgb
from . import limits
from ._json import jsonable
from ._untrusted import exr_header, npy_array, npy_header, png_size

__all__ = [
    "CaseCheck",
    "KitCase",
    "Visual",
    "CaseError",
    "check_gbuffer",
    "check_image",
    "composite_over_black",
    "position_tolerant_mismatch",
    "render_exists",
]


def _q(value: Any, limit: int = 100) -> str:
    """``repr(value)`` (control characters escaped), shortened to ``limit`` characters."""
    text = repr(value)
    return text if len(text) <= limit else text[: limit - 3] + "..."


@dataclass(frozen=True)
class CaseCheck:
    """The verdict on one case.

    Attributes
    ----------
    name, kind : str
        The case (matches :data:`refnpr.kit.check.CASE_NAME`) and ``"image"``, ``"gbuffer"``
        (or ``"?"`` when the kit does not say).
    passed : bool
        Whether the case meets its own tolerance (the rule: :mod:`refnpr.kit.check`); False
        for every status but ``"ok"``.
    status : str
        ``"ok"`` (compared; ``passed`` says the verdict), ``"missing"`` (no render: listed
        apart, last; ``--missing skip`` keeps it out of the exit status), ``"unreadable"`` (a
        render that cannot be decoded, or that is not a regular file inside the renders
        directory), ``"size"`` (a render of the wrong size or shape, refused from its header),
        ``"channels"`` (a G-buffer channel missing) or ``"kit"`` (the kit's own files for the
        case are missing or invalid; the message names the file and key).
    message : str
        Why it failed, or the deciding numbers against their limits when it was compared.
        Non-printable characters are escaped (``\\x1b``), so it is safe to print.
    metrics : dict of str to float
        Image cases: ``max_abs``, ``rmse``, ``frac_over``, ``frac_over_position``,
        ``frac_over_position_cts``, ``ssim`` and, with an EXR render, ``linear_max_abs``,
        ``linear_rmse``, ``linear_frac_over``. G-buffer cases: the worst channel's ``frac_bad``.
    channels : dict of str to dict
        G-buffer cases: per channel ``{"kind": "float"|"discrete", "max_abs", "bad_pixels",
        "frac_bad" (float: fraction of bad elements; discrete: of bad pixels),
        "allowed_frac"|"allowed_pixels", "nonfinite_mismatch" (float), "passed"}``.
    tolerance : dict
        The case's ``tolerance`` as validated (:func:`refnpr.kit.tolerance.validate_tolerance`);
        empty when it was not read or is invalid.
    images : dict of str to str
        Report files of the case, relative to the report directory; filled by the report.
    style : str or None
        The case's style (:func:`refnpr.kit.check.case_style`), None when case.json could not
        be read.
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
    style: str | None = None

    def __post_init__(self) -> None:
        for key in ("name", "kind", "status", "message"):
            object.__setattr__(self, key, printable(getattr(self, key)))

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
    ``deviation`` (both directions in one pass: each pair is compared once, credited to both).
    ``threshold`` is widened by LEVEL_SLACK: a difference of k levels matches a threshold of k/255."""
    threshold = threshold + LEVEL_SLACK
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


# -- a case and its failures -------------------------------------------------------------------


class CaseError(Exception):
    """A case cannot be compared: carries the status and the message."""

    def __init__(self, status: str, message: str) -> None:
        super().__init__(message)
        self.status = status
        self.message = message


@contextmanager
def failing_as(status: str, prefix: str = "") -> Iterator[None]:
    """A ValueError inside (a file that cannot be read or is refused) fails the case."""
    try:
        yield
    except ValueError as exc:
        raise CaseError(status, f"{prefix}{exc}") from None


@dataclass
class KitCase:
    """A case.json read and checked: where it is and what the checker needs of it."""

    path: Path  # resolved, inside the kit
    rel: str  # as shown in messages: relative to the kit, '/'-separated
    data: dict[str, Any]
    kind: str
    width: int
    height: int
    spp: int
    style: str | None


def render_exists(renders_root: Path, case: KitCase, name: str) -> bool:
    """Whether the backend wrote anything for the case (``<name>.png`` for an image case, the
    directory ``<name>`` for a G-buffer case), a link or not."""
    rel = f"{name}.png" if case.kind == "image" else name
    return os.path.lexists(renders_root / rel)


def _render_path(renders_root: Path, rel: str) -> Path | None:
    """A render file inside the renders directory, or None when there is none (a ValueError,
    status ``unreadable``, when the path leads outside it)."""
    if not os.path.lexists(renders_root / rel):
        return None
    with failing_as("unreadable"):
        return inside(renders_root, rel, what="render", root_name="the renders directory")


def _kit_file(kit_root: Path, case: KitCase, rel: Any, key: str) -> tuple[Path, str]:
    """A file the case names under ``key`` (relative to its case.json), inside the kit: the
    resolved path and the path relative to the kit (for messages)."""
    with failing_as("kit", f"kit file {case.rel!r}: "):
        path = inside(kit_root, rel, what=key, root_name="the kit", base=case.path.parent)
    return path, path.relative_to(kit_root).as_posix()


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


# -- image cases -------------------------------------------------------------------------------


def _size_error(what: str, got: tuple[int, int], case: KitCase, status: str) -> CaseError:
    return CaseError(
        status,
        f"{what} is {got[0]}x{got[1]}, the case is {case.width}x{case.height} "
        "(refused from its header, not decoded)",
    )


def _decode_png(data: bytes, what: str) -> np.ndarray:
    """(H, W, 4) float64 in [0, 1] of PNG bytes (gray and RGB get alpha 1), as
    refnpr.compare.load_image reads a file."""
    import imageio.v3 as iio

    try:
        if is_png16_colour(data[:26]):  # 16-bit RGB(A), grey + alpha: imageio gives 8 bits
            a = decode_png16(data, max_pixels=limits.MAX_IMAGE_PIXELS)
        else:
            # index 0: the first frame only, whose size the header check bounded (an animated
            # PNG would otherwise decode every frame before any shape check)
            a = np.asarray(iio.imread(data, extension=".png", index=0))
    except Exception as exc:  # noqa: BLE001 -- the decoder raises many types on corrupt data
        first = (str(exc).strip().splitlines() or [type(exc).__name__])[0]
        raise ValueError(f"{what}: cannot read: {_q(first, 120)}; expected a PNG file") from None
    if a.dtype not in (np.bool_, np.uint8, np.uint16) or a.ndim not in (2, 3):
        raise ValueError(f"{what}: decodes to {a.dtype} {a.shape}; expected an 8- or 16-bit PNG")
    f = a.astype(np.float64) / (np.iinfo(a.dtype).max if a.dtype.kind == "u" else 1.0)
    if f.ndim == 2:
        f = f[..., None]
    if f.shape[2] <= 2:  # gray (+ alpha)
        f = np.concatenate([np.repeat(f[..., :1], 3, axis=2), f[..., 1:]], axis=2)
    if f.shape[2] == 3:
        f = np.concatenate([f, np.ones(f.shape[:2] + (1,))], axis=2)
    return f[..., :4]


def _read_png(path: Path, what: str, case: KitCase, status: str, size_status: str) -> np.ndarray:
    """A PNG of the case's size: header checked first, then decoded."""
    with failing_as(status):
        data = read_regular(path, what=what, max_bytes=limits.MAX_FILE_BYTES)
        size = png_size(data, what=what)
    if size != (case.width, case.height):
        raise _size_error(what, size, case, size_status)
    with failing_as(status):
        return _decode_png(data, what)


def _read_exr(path: Path, what: str, case: KitCase, status: str, size_status: str) -> np.ndarray:
    """(H, W, 4) float32 RGBA of an OpenEXR file of the case's size (A: 1 when absent): header
    read and checked first (size, R, G, B present), then decoded."""
    with failing_as(status):
        head = read_regular(
            path, what=what, max_bytes=limits.MAX_FILE_BYTES, head=limits.MAX_EXR_HEADER_BYTES
        )
        hdr = exr_header(head, what=what, max_channels=limits.MAX_EXR_CHANNELS)
    if not {"R", "G", "B"} <= set(hdr.channels):
        raise CaseError(
            status, f"{what} has channels {_q(sorted(hdr.channels))}; expected R, G, B (and A)"
        )
    if (hdr.width, hdr.height) != (case.width, case.height):
        raise _size_error(what, (hdr.width, hdr.height), case, size_status)
    try:
        import OpenEXR
    except ImportError:  # pragma: no cover -- the kit extra installs it
        raise CaseError(
            status,
            f"{what}: cannot read it: the OpenEXR package is missing; pip install 'refnpr[kit]'",
        ) from None
    try:
        with OpenEXR.File(str(path), separate_channels=True) as f:
            ch = {k: np.asarray(v.pixels) for k, v in f.channels().items() if k in "RGBA"}
    except Exception as exc:  # noqa: BLE001 -- OpenEXR raises RuntimeError and others
        first = (str(exc).strip().splitlines() or [type(exc).__name__])[0]
        raise CaseError(status, f"{what}: cannot read: {_q(first, 120)}") from None
    want = (case.height, case.width)
    if any(a.shape != want for a in ch.values()):
        raise CaseError(status, f"{what}: a channel decodes to another size than the header's")
    a = ch.get("A", np.ones(want, dtype=np.float32))
    return np.stack([ch["R"], ch["G"], ch["B"], a], axis=-1).astype(np.float32)


def _background(case: KitCase) -> np.ndarray:
    bg = case.data.get("background", [0.0, 0.0, 0.0, 0.0])
    ok = (
        isinstance(bg, list)
        and len(bg) == 4
        and all(isinstance(v, (int, float)) and not isinstance(v, bool) for v in bg)
        and all(math.isfinite(v) for v in bg)
    )
    if not ok:
        raise CaseError(
            "kit",
            f"kit file {case.rel!r}: background: expected 4 finite numbers (linear RGBA), "
            f"got {_q(bg)}",
        )
    return np.asarray(bg, dtype=np.float64)


def _expected(case: KitCase, key: str) -> Any:
    """``expected.<key>`` of an image case (a file name), checked for presence."""
    expected = case.data.get("expected")
    value = expected.get(key) if isinstance(expected, dict) else None
    if not isinstance(value, str):
        raise CaseError(
            "kit",
            f"kit file {case.rel!r}: expected.{key}: expected a file name relative to "
            f"case.json, got {_q(value) if isinstance(expected, dict) else 'no expected object'}",
        )
    return value


def check_image(
    case: KitCase, name: str, tol: dict, kit_root: Path, renders_root: Path, data: Visual
) -> CaseCheck:
    png_rel = _expected(case, "png")
    bg = _background(case)
    ref_path, ref_rel = _kit_file(kit_root, case, png_rel, "expected.png")
    ref = _read_png(ref_path, f"kit file {ref_rel!r}", case, "kit", "kit")
    data.reference = composite_over_black(ref)  # shown by the report, also without a render
    res_path = _render_path(renders_root, f"{name}.png")
    if res_path is None:
        raise CaseError("missing", f"no render {name + '.png'!r}")
    res = _read_png(res_path, f"render {name + '.png'!r}", case, "unreadable", "size")
    data.result = composite_over_black(res)
    threshold, dev = tol["threshold"], tol["position_deviation"]
    m = compare_images(ref, res, name=name, tolerance=threshold)
    result_ok, reference_ok = _matches(data.result, data.reference, threshold, dev)
    bad = ~(result_ok & reference_ok)  # the two-sided verdict that decides
    cts = ~result_ok  # the CTS's one-sided verdict, reported
    data.bad = bad
    data.empty = _empty(bg, data.reference, data.result, threshold)
    metrics = {
        "max_abs": m.max_abs,
        "rmse": m.rmse,
        "frac_over": m.frac_over,
        "frac_over_position": float(bad.mean()),
        "frac_over_position_cts": float(cts.mean()),
        "ssim": m.ssim,
    }
    max_frac, min_ssim = tol["max_frac_over"], tol["min_ssim"]
    # an SSIM of NaN: an image under 3 px tall or wide that differs (compare_images), whose
    # SSIM cannot be computed; that criterion is not judged, as in ImageMetrics.passes
    unjudged = math.isnan(m.ssim)
    ok = metrics["frac_over_position"] <= max_frac and (unjudged or m.ssim >= min_ssim)
    ssim_text = (
        "n/a (not judged: SSIM needs 3x3 pixels)"
        if unjudged
        else f"{m.ssim:.4f} (min {min_ssim:g})"
    )
    msg = (
        f"frac_over_position={metrics['frac_over_position']:.5f} (allowed {max_frac:g}, "
        f"N={dev}) ssim={ssim_text}"
    )
    if "max_flip" in tol:  # FLIP decides too only where the case says so
        from .diagnose import flip_error

        flip = flip_error(data.reference, data.result)
        if flip.mean is None:
            raise CaseError(
                "flip",
                f"tolerance.max_flip: the case is judged by FLIP too, which is {flip.note}; "
                "install it with `pip install 'refnpr[flip]'`",
            )
        metrics["flip"] = flip.mean
        ok = ok and flip.mean <= tol["max_flip"]
        msg += f" flip={flip.mean:.4f} (max {tol['max_flip']:g})"
    exr_path = _render_path(renders_root, f"{name}.exr")
    if exr_path is not None:
        try:
            lin_rel = _expected(case, "linear")
            metrics.update(_linear_metrics(case, kit_root, lin_rel, exr_path, name, threshold))
        except CaseError as exc:  # the PNG's metrics stay in the record
            message = f"{exc.message} (PNG: {msg})"
            return CaseCheck(name, "image", False, exc.status, message, metrics, tolerance=tol)
    return CaseCheck(name, "image", ok, "ok", msg, metrics=metrics, tolerance=tol)


def _empty(bg: np.ndarray, ref: np.ndarray, res: np.ndarray, threshold: float) -> np.ndarray:
    """(H, W) bool: both pixels are the case's background (within the threshold)."""
    alpha = np.clip(bg[3], 0, 1)
    enc = np.concatenate([linear_to_srgb(np.clip(bg[:3], 0, None)) * alpha, [alpha]])
    near = threshold + 0.5 / 255  # the background after 8-bit rounding
    return (np.abs(ref - enc).max(axis=-1) <= near) & (np.abs(res - enc).max(axis=-1) <= near)


def _linear_metrics(
    case: KitCase, kit_root: Path, lin_rel: str, exr_path: Path, name: str, threshold: float
) -> dict[str, float]:
    ref_path, ref_rel = _kit_file(kit_root, case, lin_rel, "expected.linear")
    ref = _read_exr(ref_path, f"kit file {ref_rel!r}", case, "kit", "kit")
    what = f"render {name + '.exr'!r}"
    res = _read_exr(exr_path, what, case, "unreadable", "size")
    if not np.all(np.isfinite(res)):
        raise CaseError("unreadable", f"{what} holds NaN or inf")
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


def _channels(case: KitCase) -> dict[str, Any]:
    """``expected.channels`` of a G-buffer case: channel -> file name (checked names)."""
    where = f"kit file {case.rel!r}: expected.channels"
    expected = case.data.get("expected")
    chans = expected.get("channels") if isinstance(expected, dict) else None
    if not isinstance(chans, dict) or not chans or len(chans) > limits.MAX_GBUFFER_CHANNELS:
        raise CaseError(
            "kit",
            f"{where}: expected an object of 1 to {limits.MAX_GBUFFER_CHANNELS} channels "
            f"{{channel: {{'file': ...}}}}, got {_q(chans)}",
        )
    out = {}
    for ch, entry in chans.items():
        if not limits.CHANNEL_NAME.fullmatch(ch):
            raise CaseError(
                "kit",
                f"{where}: channel name {_q(ch)} does not match {limits.CHANNEL_NAME.pattern!r}",
            )
        file = entry.get("file") if isinstance(entry, dict) else entry
        if not isinstance(file, str):
            raise CaseError("kit", f"{where}.{ch}.file: expected a file name, got {_q(file)}")
        out[ch] = file
    return out


def _npy(path: Path, what: str, status: str) -> tuple[bytes, Any]:
    with failing_as(status):
        data = read_regular(path, what=what, max_bytes=limits.MAX_FILE_BYTES)
        return data, npy_header(data, what=what)


def check_gbuffer(
    case: KitCase, name: str, tol: dict, kit_root: Path, renders_root: Path, data: Visual
) -> CaseCheck:
    chans = _channels(case)
    rdir = _render_path(renders_root, name)
    if rdir is None:
        raise CaseError("missing", f"no render directory {name!r}")
    if not rdir.is_dir():
        raise CaseError("unreadable", f"render {name!r} is not a directory of .npy files")
    absent = [c for c in chans if not os.path.lexists(rdir / f"{c}.npy")]
    if absent:
        raise CaseError("channels", f"render {name!r} lacks channel(s) {absent} (.npy files)")
    n = math.isqrt(case.spp)
    grids = {(case.height, case.width), (n * case.height, n * case.width)}
    rtol, atol, max_frac = tol["rtol"], tol["atol"], tol["max_frac_over"]
    discrete = tol["discrete"]
    per: dict[str, dict[str, Any]] = {}
    for ch, file in chans.items():
        exp_path, exp_rel = _kit_file(kit_root, case, file, f"expected.channels.{ch}.file")
        exp_what = f"kit file {exp_rel!r}"
        exp_bytes, eh = _npy(exp_path, exp_what, "kit")
        shape = eh.shape
        if (
            len(shape) not in (2, 3)
            or shape[:2] not in grids
            or (len(shape) == 3 and not 1 <= shape[2] <= limits.MAX_CHANNEL_COMPONENTS)
        ):
            raise CaseError(
                "kit",
                f"{exp_what} has shape {shape}; the case ({case.width}x{case.height}, spp "
                f"{case.spp}) needs (H, W) or (H, W, C) with (H, W) in {sorted(grids)} and C <= "
                f"{limits.MAX_CHANNEL_COMPONENTS}",
            )
        got_rel = f"{name}/{ch}.npy"
        got_what = f"render {got_rel!r}"
        got_path = _render_path(renders_root, got_rel)
        if got_path is None:  # removed since the listing above
            raise CaseError("channels", f"render {name!r} lacks channel {ch!r}")
        got_bytes, gh = _npy(got_path, got_what, "unreadable")
        if gh.shape != shape:
            raise CaseError(
                "size",
                f"channel {ch!r}: {got_what} has shape {gh.shape}, the kit {shape} (refused "
                "from its header, not loaded)",
            )
        with failing_as("kit"):
            exp = npy_array(exp_bytes, eh, what=exp_what)
        with failing_as("unreadable"):
            got = npy_array(got_bytes, gh, what=got_what)
        is_discrete = ch in discrete or exp.dtype.kind in "iub"
        if is_discrete:
            allowed = discrete.get(ch, {"max_pixels": 0})["max_pixels"]
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
        del exp_bytes, got_bytes, exp, got, bad, diff  # one channel in memory at a time
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
