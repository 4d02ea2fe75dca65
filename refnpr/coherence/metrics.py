"""Per frame pair: warping error, plain frame difference, their ratio, flip fraction.

On the Rec. 709 luminance Y of the rendered linear RGB (one channel for every number; the flip's
ink state needs a scalar), with M the valid mask of :func:`~refnpr.coherence.motion_field` and
``Y_hat = warp(Y_{t-1})`` (docs/coherence.md, "The numbers of a pair"): ``warp_error`` E =
sum(M |Y_t - Y_hat|) / sum(M), the E_warp of Lai et al. 2018 in L1 form with the exact motion
field and visibility mask in place of estimated flow and occlusion; ``plain_diff`` D the same
against Y_{t-1} at the same pixel; ``ratio`` E / D, NaN when D = 0 (no motion to judge E by);
``flip`` / ``flip_plain`` the fraction of M whose ink state (Y < 0.5) differs from Y_hat's /
Y_{t-1}'s; ``motion_px`` the mean exact motion in pixels. All but the counts are NaN when M is
empty.
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass

import numpy as np

from ..formulas import lighting
from .motion import MotionField
from .resample import warp

__all__ = ["LUMA", "INK_THRESHOLD", "PairMetrics", "luminance", "pair_metrics"]

#: Rec. 709 luminance weights of linear RGB.
LUMA = lighting.LUMA_709
#: Luminance below which a pixel counts as ink (for the flip fraction).
INK_THRESHOLD = 0.5


def luminance(rgb: np.ndarray, *, name: str = "rgb") -> np.ndarray:
    """(H, W) float64 luminance of (H, W, 3 or 4) linear RGB[A] (alpha ignored); errors name
    the image ``name``."""
    a = np.asarray(rgb)
    if a.ndim != 3 or a.shape[2] not in (3, 4):
        raise ValueError(f"{name}: expected an (H, W, 3) or (H, W, 4) image, got shape {a.shape}")
    if a.dtype.kind != "f":  # a PNG frame as read (uint8): 0..255, not linear [0, 1]
        raise TypeError(
            f"{name}: expected float linear RGB in [0, 1], got dtype {a.dtype}; convert a PNG "
            "frame with refnpr.image.srgb_to_linear(frame / 255)"
        )
    bad = ~np.isfinite(a[..., :3]).all(axis=-1)
    if bad.any():
        y, x = (int(i) for i in np.argwhere(bad)[0])
        raise ValueError(
            f"{name}: expected finite colours, got NaN or inf in {int(bad.sum())} of its "
            f"pixels, the first at (y, x) = ({y}, {x}): {a[y, x].tolist()}"
        )
    return lighting.luminance(a[..., :3])  # alpha ignored, also where it is not finite


class _Row:
    """A dataclass of numbers with a JSON-ready ``as_dict``."""

    def as_dict(self) -> dict:
        """JSON-ready: NaN becomes None."""
        return {
            k: (None if isinstance(v, float) and math.isnan(v) else v)
            for k, v in asdict(self).items()
        }


@dataclass(frozen=True)
class PairMetrics(_Row):
    """The numbers of one frame pair (t-1, t); see the module docstring.

    Attributes
    ----------
    frame : int
        The index t of the later frame.
    warp_error, plain_diff, ratio, flip, flip_plain, motion_px : float
        NaN where undefined.
    n_valid, n_covered : int
    """

    frame: int
    warp_error: float
    plain_diff: float
    ratio: float
    flip: float
    flip_plain: float
    motion_px: float
    n_valid: int
    n_covered: int


def pair_metrics(
    image: np.ndarray, prev_image: np.ndarray, motion: MotionField, *, frame: int = 1
) -> PairMetrics:
    """Coherence numbers of frame t against frame t-1.

    Parameters
    ----------
    image, prev_image : (H, W, 3 or 4) float
        Linear RGB[A] of frames t and t-1 (``Image.rgba``), the motion field's size.
    motion : MotionField
        ``motion_field`` of the pair.
    frame : int
        t, recorded in the result.

    Returns
    -------
    PairMetrics
    """
    if not isinstance(motion, MotionField):
        raise TypeError(
            f"motion: expected a MotionField (motion_field(...)), got {type(motion).__name__}"
        )
    for name, img in (("image", image), ("prev_image", prev_image)):
        shape = np.shape(img)
        if len(shape) != 3 or shape[:2] != motion.shape:
            raise ValueError(
                f"{name}: expected an (H, W, 3 or 4) image of the motion field's size "
                f"{motion.shape}, got shape {shape}"
            )
    y = luminance(image, name="image")
    y_prev = luminance(prev_image, name="prev_image")
    y_hat = warp(y_prev, motion)
    m = motion.valid
    n = int(m.sum())
    nan = float("nan")
    if n == 0:
        return PairMetrics(frame, nan, nan, nan, nan, nan, nan, 0, int(motion.covered.sum()))
    e = float(np.abs(y - y_hat)[m].sum() / n)  # E_warp of Lai et al. 2018, L1 on Y
    d = float(np.abs(y - y_prev)[m].sum() / n)
    ratio = e / d if d > 0.0 else nan
    ink = y < INK_THRESHOLD
    flip = float(np.count_nonzero((ink != (y_hat < INK_THRESHOLD))[m]) / n)
    flip_plain = float(np.count_nonzero((ink != (y_prev < INK_THRESHOLD))[m]) / n)
    motion_px = float(np.hypot(*motion.flow()[m].T).mean())
    return PairMetrics(
        frame, e, d, ratio, flip, flip_plain, motion_px, n, int(motion.covered.sum())
    )
