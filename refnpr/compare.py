"""Image comparison: how far a candidate render (another backend) is from the reference.

Metrics per image, on sRGB-encoded values in [0, 1] (what a PNG stores), RGB channels composited
over the image's own alpha onto black so that transparent pixels compare by coverage:

* ``max_abs``: largest absolute difference of any channel (alpha included);
* ``rmse``: root mean square difference over all channels;
* ``frac_over``: fraction of pixels whose largest channel difference exceeds ``tolerance``;
* ``ssim``: mean structural similarity (scikit-image, ``data_range=1``, on luminance); NaN
  (``null`` in JSON, ``n/a`` in tables) for an image 1 or 2 pixels tall or wide that differs at
  all, where the smallest SSIM window (3 x 3) does not fit: the SSIM criterion is then not judged.
"""

from __future__ import annotations

import json
import os
from dataclasses import asdict, dataclass, replace
from pathlib import Path

import numpy as np

from .formulas.lighting import luminance
from .image import atomic_file, read_image_file, write_png_atomic

__all__ = [
    "ImageMetrics",
    "compare_images",
    "compare_dirs",
    "check_outside_compared",
    "load_image",
    "difference_image",
]


@dataclass(frozen=True)
class ImageMetrics:
    name: str
    max_abs: float
    rmse: float
    frac_over: float
    ssim: float
    tolerance: float
    #: "ok", "missing" (no candidate), "size" (sizes differ), "unreadable" (a file that is not
    #: a readable image), "nonfinite" (an image holding NaN or infinite values)
    status: str = "ok"
    #: Why the status is not "ok": the two sizes, the file and the decoder's reason
    message: str = ""

    @classmethod
    def failed(cls, name: str, tolerance: float, status: str, message: str) -> ImageMetrics:
        """The record of an image that could not be compared (worst metrics, ``status``)."""
        return cls(name, np.inf, np.inf, 1.0, 0.0, tolerance, status=status, message=message)

    def passes(self, *, max_frac_over: float, min_ssim: float) -> bool:
        """Whether the image was compared and meets both criteria; an SSIM of NaN (not
        computable, see :func:`compare_images`) leaves the SSIM criterion unjudged."""
        ssim_ok = bool(np.isnan(self.ssim)) or self.ssim >= min_ssim
        return self.status == "ok" and self.frac_over <= max_frac_over and ssim_ok

    def as_dict(self) -> dict:
        """JSON-ready: inf and NaN become None."""
        return {
            k: (None if isinstance(v, float) and not np.isfinite(v) else v)
            for k, v in asdict(self).items()
        }


def load_image(path: str | Path, *, what: str = "image") -> np.ndarray:
    """An image file as (H, W, 4) float64 (alpha 1 if absent): integer pixels divided by their
    type's maximum, in [0, 1]; float pixels (a float TIFF) as stored, also outside [0, 1]
    (compared as they are; NaN or inf gives status "nonfinite").

    Parameters
    ----------
    path : str or path
        PNG (1, 8 or 16 bit; gray, gray + alpha, RGB, RGBA), or another format imageio reads.
    what : str
        What the file is, the start of error messages (``"reference image"``).

    Raises
    ------
    ValueError
        Naming the file: missing, a directory, not a readable image (with the reason), or of an
        unsupported pixel type or channel count.
    """
    a = read_image_file(path, what=what)
    if a.dtype not in (np.bool_, np.uint8, np.uint16) and a.dtype.kind != "f":
        raise ValueError(
            f"{what}: {str(path)!r} has unsupported pixel type {a.dtype}; write 8- or 16-bit PNG"
        )
    f = a.astype(np.float64) / (np.iinfo(a.dtype).max if a.dtype.kind == "u" else 1.0)
    if f.ndim == 2:
        f = f[..., None]
    if f.ndim != 3 or not 1 <= f.shape[2] <= 4:
        raise ValueError(
            f"{what}: {str(path)!r} has shape {a.shape}; expected a single gray, gray + alpha, "
            "RGB or RGBA image"
        )
    if f.shape[2] <= 2:  # gray (+ alpha)
        f = np.concatenate([np.repeat(f[..., :1], 3, axis=2), f[..., 1:]], axis=2)
    if f.shape[2] == 3:
        f = np.concatenate([f, np.ones(f.shape[:2] + (1,))], axis=2)
    return f[..., :4]


#: Slack added to a threshold: composited 8-bit values are multiples of 1/65025 (colour k/255
#: times alpha j/255), so a difference is within a threshold of k/255 exactly or over it by at
#: least 1/65025, while float64 rounding can put a difference of two levels, |33/255 - 31/255|,
#: an ulp above 2/255. Comparing against ``threshold + LEVEL_SLACK`` counts such a difference as
#: the two levels it is and changes no other verdict.
LEVEL_SLACK = 1e-9


def _flatten(rgba: np.ndarray) -> np.ndarray:
    out = rgba.copy()
    out[..., :3] *= rgba[..., 3:4]
    return out


def difference_image(
    reference: np.ndarray, candidate: np.ndarray, *, gain: float = 4.0
) -> np.ndarray:
    """(H, W, 3) uint8 visualisation: |difference| of the largest channel, amplified by ``gain``,
    red where the candidate is brighter, blue where darker, gray scale of the reference below."""
    ref, cand = _flatten(reference), _flatten(candidate)
    d = cand[..., :3].mean(axis=-1) - ref[..., :3].mean(axis=-1)
    mag = np.clip(np.abs(cand - ref).max(axis=-1) * gain, 0, 1)
    base = 0.25 * ref[..., :3].mean(axis=-1)
    hi = np.maximum(base, mag)
    red, blue = np.where(d >= 0, hi, base), np.where(d < 0, hi, base)
    out = np.stack([red, np.where(mag > 0, base * (1 - mag), base), blue], axis=-1)
    return np.rint(np.clip(out, 0, 1) * 255).astype(np.uint8)


def compare_images(
    reference: np.ndarray, candidate: np.ndarray, *, name: str = "", tolerance: float = 2.0 / 255
) -> ImageMetrics:
    """Metrics of ``candidate`` against ``reference``, both (H, W, 4) float in [0, 1].

    Parameters
    ----------
    reference, candidate : (H, W, 4) float array
        RGBA in [0, 1], as :func:`load_image` returns.
    name : str
        The image's name, copied to the result.
    tolerance : float
        Per-channel difference in [0, 1] above which a pixel counts in ``frac_over``.

    Returns
    -------
    ImageMetrics
        Status "size" or "nonfinite" (worst metrics) when the images cannot be compared. ``ssim``
        is NaN for images 1 or 2 pixels tall or wide that differ at all: the smallest SSIM window
        (3 x 3) does not fit them, and :meth:`ImageMetrics.passes` then judges them by
        ``frac_over`` alone (identical images have SSIM 1 at any size).

    Raises
    ------
    ValueError
        A ``tolerance`` that is not a number in [0, 1].
    """
    from skimage.metrics import structural_similarity

    if not (isinstance(tolerance, (int, float)) and 0.0 <= tolerance <= 1.0):
        raise ValueError(f"tolerance: expected a number in [0, 1], got {tolerance!r}")
    if reference.shape != candidate.shape:
        why = f"sizes differ: reference {_wxh(reference)}, candidate {_wxh(candidate)}"
        return ImageMetrics.failed(name, tolerance, "size", why)
    for what, image in (("reference", reference), ("candidate", candidate)):
        bad = ~np.isfinite(image)
        if bad.any():
            y, x = np.argwhere(bad)[0][:2]
            why = (
                f"the {what} holds {int(bad.sum())} NaN or infinite value(s), the first at pixel "
                f"(x={x}, y={y}); metrics of such an image mean nothing"
            )
            return ImageMetrics.failed(name, tolerance, "nonfinite", why)
    ref, cand = _flatten(reference), _flatten(candidate)
    diff = np.abs(cand - ref)
    lum_r, lum_c = luminance(ref), luminance(cand)
    win = min(7, *(s if s % 2 else s - 1 for s in lum_r.shape))
    ssim = (
        float(structural_similarity(lum_r, lum_c, data_range=1.0, win_size=win))
        if win >= 3
        else (1.0 if not diff.any() else float("nan"))
    )
    return ImageMetrics(
        name=name,
        max_abs=float(diff.max()),
        rmse=float(np.sqrt(np.mean(diff**2))),
        frac_over=float(np.mean(diff.max(axis=-1) > tolerance + LEVEL_SLACK)),
        ssim=ssim,
        tolerance=tolerance,
    )


def _wxh(a: np.ndarray) -> str:
    return f"{a.shape[1]}x{a.shape[0]}"


def compare_dirs(
    reference_dir: str | Path,
    candidate_dir: str | Path,
    *,
    out_dir: str | Path | None = None,
    tolerance: float = 2.0 / 255,
) -> list[ImageMetrics]:
    """Compare every ``*.png`` of ``reference_dir`` with the file of the same name in
    ``candidate_dir``.

    A missing candidate is reported with status "missing", images of different sizes with
    "size", a file that cannot be read (either side) with "unreadable"; ``message`` says why, with
    the paths. With ``out_dir``, writes ``<name>.diff.png`` per image and ``report.json``.

    Raises
    ------
    ValueError
        A directory that does not exist or holds no ``.png`` files, the same directory twice, or
        an ``out_dir`` that is a file or is (or lies inside) one of the compared directories.
    """
    ref_dir, cand_dir = Path(reference_dir), Path(candidate_dir)
    for label, d in (("reference_dir", ref_dir), ("candidate_dir", cand_dir)):
        if not d.is_dir():
            why = "it is a file" if d.exists() else "it does not exist"
            raise ValueError(f"{label}: {str(d)!r} is not a directory ({why})")
    if ref_dir.resolve() == cand_dir.resolve():
        raise ValueError(
            f"candidate_dir: {str(cand_dir)!r} is the same directory as reference_dir "
            f"{str(ref_dir)!r}; every image would match itself: give the other backend's renders"
        )
    if out_dir is not None and Path(out_dir).exists() and not Path(out_dir).is_dir():
        raise ValueError(f"out_dir: {str(out_dir)!r} is a file; expected a directory")
    if out_dir is not None:
        check_outside_compared(out_dir, "out_dir", ref_dir, cand_dir)
    names = sorted(p.name for p in ref_dir.glob("*.png"))
    if not names:
        raise ValueError(f"reference_dir: no .png files in {str(ref_dir)!r}")
    results = []
    for fname in names:
        stem = fname[:-4]
        ref_path, cand_path = ref_dir / fname, cand_dir / fname
        if cand_path.is_symlink() and not cand_path.exists():  # there, but reads nothing
            try:
                cand_path.stat()
                reason = "it cannot be followed"
            except OSError as exc:  # no such file; too many levels of symbolic links
                reason = exc.strerror or type(exc).__name__
            why = (
                f"candidate {str(cand_path)!r} is a symbolic link to "
                f"{os.readlink(cand_path)!r} that cannot be followed ({reason}); write the "
                "render there or fix the link"
            )
            results.append(ImageMetrics.failed(stem, tolerance, "unreadable", why))
            continue
        if not cand_path.exists():
            results.append(
                ImageMetrics.failed(stem, tolerance, "missing", f"no candidate {str(cand_path)!r}")
            )
            continue
        try:
            ref = load_image(ref_path, what="reference image")
            cand = load_image(cand_path, what="candidate image")
        except ValueError as exc:  # one bad file must not hide the others
            results.append(ImageMetrics.failed(stem, tolerance, "unreadable", str(exc)))
            continue
        m = compare_images(ref, cand, name=stem, tolerance=tolerance)
        if m.status == "size":
            why = (
                f"sizes differ: reference {str(ref_path)!r} is {_wxh(ref)}, "
                f"candidate {str(cand_path)!r} is {_wxh(cand)}"
            )
            m = replace(m, message=why)
        results.append(m)
        if out_dir is not None and m.status == "ok":
            write_png_atomic(Path(out_dir) / f"{stem}.diff.png", difference_image(ref, cand))
    if out_dir is not None:
        with atomic_file(Path(out_dir) / "report.json", suffix=".json") as tmp:
            tmp.write_text(json.dumps([m.as_dict() for m in results], indent=2))
    return results


def check_outside_compared(
    path: str | Path, what: str, reference_dir: str | Path, candidate_dir: str | Path
) -> None:
    """A ValueError naming ``what`` (the parameter or option) unless ``path`` lies outside both
    compared directories: files written into them would overwrite an image or be compared as
    images by the next run.

    Parameters
    ----------
    path : str or path
        The output directory or file.
    what : str
        The parameter or option that gave it (``"--out"``), the start of the message.
    reference_dir, candidate_dir : str or path
        The compared directories.

    Raises
    ------
    ValueError
        ``path`` is one of the directories or lies inside one (after resolving symbolic links).
    """
    target = Path(path).resolve()
    for label, d in (("reference", reference_dir), ("candidate", candidate_dir)):
        if target.is_relative_to(Path(d).resolve()):
            raise ValueError(
                f"{what}: {str(path)!r} is or lies inside the {label} directory {str(d)!r}; "
                "write the comparison's files elsewhere (they would be compared as images or "
                "overwrite them)"
            )


def format_table(results: list[ImageMetrics]) -> str:
    """Plain-text table of metrics (an SSIM that could not be computed shows as ``n/a``)."""
    lines = [
        f"{'image':32s} {'status':10s} {'max_abs':>8s} {'rmse':>8s} {'frac>tol':>9s} {'ssim':>7s}"
    ]
    for m in results:
        lines.append(
            f"{m.name:32s} {m.status:10s} {m.max_abs:8.4f} {m.rmse:8.4f} {m.frac_over:9.5f} "
            + ("    n/a" if np.isnan(m.ssim) else f"{m.ssim:7.4f}")
        )
        if m.message:
            lines.append(f"    {m.message}")
    return "\n".join(lines)
