"""``CoherenceReport``: the per-pair rows of a sequence, their summary, JSON and a plot."""

from __future__ import annotations

import json
import math
import os
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from ..image import atomic_file, check_png_path
from .metrics import PairMetrics
from .strokes import StrokePairMetrics

__all__ = ["METRICS", "STROKE_METRICS", "CoherenceReport"]

#: The per-pair numbers the summary covers (see :mod:`refnpr.coherence.metrics`).
METRICS = ("warp_error", "plain_diff", "ratio", "flip", "flip_plain", "motion_px", "n_valid")
#: The per-pair stroke numbers (see :mod:`refnpr.coherence.strokes`).
STROKE_METRICS = tuple(
    "jitter_mean jitter_p95 jitter_max appeared vanished n_strokes n_ends".split()
)


@dataclass(frozen=True, eq=False)
class CoherenceReport:
    """Temporal-coherence numbers of a sequence, one row per consecutive frame pair.

    Attributes
    ----------
    rows : tuple of PairMetrics
        Row k compares frame ``rows[k].frame`` with the frame before it.
    meta : dict
        How the frames were made (style, size, spp, depth tolerance, frame indices).
    images : tuple of (H, W, 4) float32
        The rendered frames (only with ``measure(..., keep_images=True)``; else empty).
    strokes : tuple of StrokePairMetrics
        Stroke numbers per pair (only with ``measure(..., strokes=True)``; else empty).
    """

    rows: tuple[PairMetrics, ...]
    meta: dict[str, Any] = field(default_factory=dict)
    images: tuple[np.ndarray, ...] = ()
    strokes: tuple[StrokePairMetrics, ...] = ()

    def column(self, name: str) -> np.ndarray:
        """(n_pairs,) float64 values of one metric (``METRICS`` or, with strokes,
        ``STROKE_METRICS``) over the pairs (NaN where undefined)."""
        if name in METRICS:
            rows: tuple = self.rows
        elif name in STROKE_METRICS:
            rows = self.strokes
        else:
            raise ValueError(
                f"name: unknown metric {name!r}; expected one of {METRICS + STROKE_METRICS}"
            )
        return np.array([float(getattr(r, name)) for r in rows], dtype=np.float64)

    def summary(self) -> dict[str, dict[str, float | int | None]]:
        """Per metric: ``median`` and ``max`` over the pairs where it is defined, and
        ``defined`` (how many pairs that is); median and max are None when none is. The
        stroke metrics are included when the report has strokes."""
        out: dict[str, dict[str, float | int | None]] = {}
        for name in METRICS + (STROKE_METRICS if self.strokes else ()):
            vals = [v for v in self.column(name).tolist() if not math.isnan(v)]
            out[name] = {
                "median": float(np.median(vals)) if vals else None,
                "max": float(np.max(vals)) if vals else None,
                "defined": len(vals),
            }
        return out

    def as_dict(self) -> dict[str, Any]:
        """JSON-ready dict: ``meta``, ``summary`` and ``pairs`` (NaN as None)."""
        out = {
            "meta": self.meta,
            "summary": self.summary(),
            "pairs": [r.as_dict() for r in self.rows],
        }
        if self.strokes:
            out["strokes"] = [r.as_dict() for r in self.strokes]
        return out

    def to_json(self) -> str:
        """The report as JSON text (strict: no NaN literals)."""
        return json.dumps(self.as_dict(), indent=2, allow_nan=False)

    def save(self, path: str | os.PathLike) -> Path:
        """Write :meth:`to_json` to ``path`` (atomic); returns the path."""
        text = self.to_json()
        with atomic_file(path, suffix=".json") as tmp:
            tmp.write_text(text + "\n", encoding="utf-8")
        return Path(path)

    def plot(self, path: str | os.PathLike) -> Path:
        """Plot the numbers over frames into a PNG (matplotlib, Agg backend).

        Warping error E and plain difference D; E / D; flip fractions; with strokes, the
        endpoint jitter (mean, 95th percentile) and the strokes appearing / vanishing.

        Raises
        ------
        ImportError
            matplotlib is not installed (``pip install matplotlib``).
        """
        path = check_png_path(path)
        try:
            import matplotlib

            matplotlib.use("Agg", force=False)
            from matplotlib.figure import Figure
        except ImportError as exc:
            raise ImportError(
                "plot: needs matplotlib, which is not installed; `pip install matplotlib`, or "
                "use save() / to_json() for the numbers"
            ) from exc
        frames = [r.frame for r in self.rows]
        from matplotlib.ticker import MaxNLocator

        n_panels = 4 if self.strokes else 3
        fig = Figure(figsize=(8, 2.4 * n_panels), layout="constrained")
        axes = fig.subplots(n_panels, 1, sharex=True)
        ax_e, ax_r, ax_f = axes[:3]
        ax_e.plot(frames, self.column("warp_error"), "o-", label="warping error E")
        ax_e.plot(frames, self.column("plain_diff"), "s--", label="plain difference D")
        ax_e.set_ylabel("mean |dY| on M")
        ax_e.legend(loc="best")
        ax_r.plot(frames, self.column("ratio"), "o-", color="C2")
        ax_r.axhline(1.0, color="0.6", lw=0.8)
        ax_r.set_ylabel("E / D")
        ax_f.plot(frames, self.column("flip"), "o-", color="C3", label="flip (warped)")
        ax_f.plot(frames, self.column("flip_plain"), "s--", color="C4", label="flip (same pixel)")
        ax_f.set_ylabel("fraction of M")
        ax_f.legend(loc="best")
        if self.strokes:
            ax_s = axes[3]
            sf = [r.frame for r in self.strokes]
            ax_s.plot(sf, self.column("jitter_mean"), "o-", label="end jitter, mean")
            ax_s.plot(sf, self.column("jitter_p95"), "s--", label="end jitter, p95")
            ax_s.set_ylabel("pixels")
            ax_n = ax_s.twinx()
            ax_n.plot(sf, self.column("appeared"), "^:", color="C5", label="appeared")
            ax_n.plot(sf, self.column("vanished"), "v:", color="C6", label="vanished")
            ax_n.set_ylabel("strokes")
            lines = ax_s.get_lines() + ax_n.get_lines()
            ax_s.legend(lines, [ln.get_label() for ln in lines], loc="best")
        axes[-1].set_xlabel("frame t (pair t-1, t)")
        axes[-1].xaxis.set_major_locator(MaxNLocator(integer=True))
        title = self.meta.get("title") or (
            f"temporal coherence: {self.meta.get('scene', '')}, style {self.meta.get('style', '')}"
        )
        fig.suptitle(str(title))
        with atomic_file(path, suffix=".png") as tmp:
            fig.savefig(tmp, format="png", dpi=100)
        return path
