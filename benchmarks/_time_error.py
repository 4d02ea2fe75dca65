"""Shared bookkeeping of the run-time-against-error benchmarks (bench_veryovka, bench_halftone):
the Pareto front of (time, error) rows, the fastest method reaching a target error, and the
time-vs-error plot."""

from __future__ import annotations

from pathlib import Path


def pareto_front(rows: list[dict], time_key: str, error_key: str = "mae") -> list[str]:
    """Methods that no other row beats in both time and error (an equal row beats neither)."""
    front = []
    for r in rows:
        dominated = any(
            o[time_key] <= r[time_key]
            and o[error_key] <= r[error_key]
            and (o[time_key], o[error_key]) != (r[time_key], r[error_key])
            for o in rows
        )
        if not dominated:
            front.append(r["method"])
    return front


def summarize(rows: list[dict], time_key: str, target_method: str) -> tuple[list[str], float, str]:
    """Mark each row's ``pareto`` flag; return (front, the target method's error, the fastest
    method whose error is at most that)."""
    front = pareto_front(rows, time_key)
    for r in rows:
        r["pareto"] = r["method"] in front
    target = next(r["mae"] for r in rows if r["method"] == target_method)
    best = min((r for r in rows if r["mae"] <= target), key=lambda r: r[time_key])
    return front, target, best["method"]


def plot_time_vs_error(path: Path, panels: list[dict], *, time_key: str, xlabel: str) -> None:
    """One log-log panel per view: every method, the Pareto front, and the target error line.

    Each panel: ``{"title", "rows", "target", "target_label", "ylabel"}``.
    """
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, len(panels), figsize=(6 * len(panels), 4.5), squeeze=False)
    for ax, panel in zip(axes[0], panels, strict=True):
        rows = panel["rows"]
        for r in rows:
            ax.scatter(r[time_key], r["mae"], c="C3" if r["pareto"] else "C0", zorder=3)
            ax.annotate(
                r["method"],
                (r[time_key], r["mae"]),
                fontsize=7,
                xytext=(3, 3),
                textcoords="offset points",
            )
        front = sorted((r for r in rows if r["pareto"]), key=lambda r: r[time_key])
        ax.plot(
            [r[time_key] for r in front],
            [r["mae"] for r in front],
            "C3--",
            lw=1,
            label="Pareto front",
        )
        ax.axhline(panel["target"], color="gray", lw=0.8, ls=":", label=panel["target_label"])
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.set_xlabel(xlabel)
        ax.set_ylabel(panel["ylabel"])
        ax.set_title(panel["title"])
        ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)
