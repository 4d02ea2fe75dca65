"""Temporal coherence of the four papers' built-in sequences, per style.

Usage::

    python benchmarks/bench_coherence.py --json benchmarks/results/coherence.json   # ~2 min
    python benchmarks/bench_coherence.py --quick --json /tmp/c.json                 # < 1 min
    python benchmarks/bench_coherence.py --sequences halftone_light_orbit           # one sequence

Every row renders consecutive frames of a built-in animated scene with one style and measures
each pair (t-1, t) with :func:`refnpr.coherence.measure` (exact motion field from the G-buffer;
``docs/coherence.md`` defines every number). A range that starts after frame 0 passes the
still of the frame before it as ``previous``, so that X-Toon's flow detail sees the true
previous frame. Per row: median and max over the pairs of

* ``E`` (warping error: mean |Y_t - warp(Y_{t-1})| on the valid mask M), ``D`` (plain
  difference on the same M), ``E/D``, ``flip`` (ink/paper changes after motion compensation),
  ``flip_plain`` (at fixed pixels), ``motion_px`` (how far the surface moved);
* ``jump``: the fraction of M where |Y_t - warp(Y_{t-1})| > 0.5 (computed here from the kept
  frames and the same motion field, not part of ``refnpr.coherence``): a pixel that changes by
  more than half the range between two frames after motion compensation, i.e. a *pop*, where
  ``flip`` also counts a smooth edge that moves a little across Y = 0.5;
* TAMISS only, ``jitter`` (``measure(..., strokes=True)``): mean and 95th percentile of the
  stroke ends' distance from where the surface point under them moved (pixels), and strokes
  appearing / vanishing per pair;
* ``s/frame``: the median wall time per frame after the first (render at the row's spp, the
  spp-1 motion G-buffer and the pair's metrics; the TAMISS row also runs the stroke pipeline).
  The machine is shared: read times as rough.

What each sequence's numbers show for its paper's claim (``CLAIMS``, printed MET / NOT MET,
never asserted; ``tests/coherence/test_sequences.py`` holds the bounds):

``veryovka_dolly`` (Veryovka 2002: threshold textures attach to the surface and evolve with
    scale). Lines (``threshold``, ``source = "lines"``) and the CLAHE brick texture (``source =
    "image"``), 240x180 spp 4, frames 6..18: across the dyadic scale change at frame 12, where
    new lines fade in. Attached marks move with the plane, so E << D (E/D < 0.5) and motion
    compensation removes most of the flips (flip < flip_plain / 2); the max shows whether the
    octave's transition pops.
``halftone_light_orbit`` (Freudenberg 2002: the binary threshold pops, the smooth one does
    not). The scene is still (the warp is the identity, E = D, E/D = 1): every change is the
    tone following the light. 240x180 spp 1 (the binary threshold is not antialiased), frames
    0..12 (a quarter orbit). The claim reads as jump(binary) > 3 x jump(smooth) (pops) and
    flip(binary) > 3 x flip(smooth) (ink/paper crossings); toon (three bands) is a baseline
    whose band edges sweep across the body.
``xtoon_flow`` (X-Toon Fig. 6: detail from optical flow abstracts the fast mover). detail =
    flow against depth and none, 256x192 (the mover crosses ~10 px a frame), frames 8..24. The
    coherence claim is that the flow-driven abstraction is steady while the object moves at
    constant speed: E/D(flow) no more than twice E/D(none). The abstraction itself is the
    row's ``detail``: the mean X-Toon detail D (``show = "detail"``) on the mover's pixels and
    on the still teapots' at the middle frame (flow: mover low, still ones 1; depth: by
    distance, the mover nearest; none: 1).
``tamiss_knot_orbit`` (TAMISS: image-space strokes are refitted every frame and jitter; the
    texture-space TAM baseline is markedly steadier). tamiss (the scene's pen style, each frame
    fitted from its own fragments as in the paper: ``average_frames=1``) against tam with the
    same stroke field and contours (golden case ``tamiss-knot-tam``), 480x360 spp 4, frames
    0..6; ``tamiss_avg4`` is refnpr's default, aggregates averaged over 4 frames carried along
    the motion. Claims: E/D(tam) < E/D(tamiss) and flip(tam) < flip(tamiss) / 2; the jitter says
    by how many pixels the tamiss ends slide per frame. The orbit is slow (0.6
    degrees a frame, ``motion_px`` ~0.4 px at 480x360), so the E/D of tamiss is mostly its
    own changes.

``--quick`` uses smaller sizes, spp 1 and three frames per row (two pairs): a smoke run whose
numbers are not the ones quoted (``docs/coherence.md``, "Results", quotes the full run).

Nothing here asserts a number or a time.
"""

from __future__ import annotations

import argparse
import dataclasses
import datetime
import json
import math
import platform
import statistics
import sys
import time
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parent))

from refnpr.coherence import (  # noqa: E402
    MOTION_CHANNELS,
    luminance,
    measure,
    motion_field,
    render_frame,
    warp,
)
from refnpr.image import linear_to_srgb  # noqa: E402
from refnpr.raster import rasterize  # noqa: E402
from refnpr.scenes import load_scene  # noqa: E402
from refnpr.styles import style_from_spec  # noqa: E402

#: A pixel "jumps" when its luminance changes by more than this after motion compensation.
JUMP = 0.5

TAM_KNOT = {
    "name": "tam",
    "directions": ["v"],
    "period": 4.0,
    "density": 1.0,
    "contours": {"width": 1.2},
}  # golden case tamiss-knot-tam: the tamiss-knot-pen field drawn in texture space

#: sequence -> (variants, full settings, quick settings). A variant is (label, style, strokes):
#: style a dict of parameters merged into the scene's own style table, or a full spec with a
#: "name" (replaces it). Settings: (width, height, spp, first frame, end frame).
SEQUENCES: dict[str, dict] = {
    "veryovka_dolly": {
        "variants": [("lines", {}, False), ("clahe", {"source": "image"}, False)],
        "full": (240, 180, 4, 6, 19),
        "quick": (120, 90, 1, 11, 14),
    },
    "halftone_light_orbit": {
        "variants": [
            ("smooth", {}, False),
            ("binary", {"threshold": "binary"}, False),
            ("toon", {"name": "toon"}, False),
        ],
        "full": (240, 180, 1, 0, 13),
        "quick": (120, 90, 1, 0, 3),
    },
    "xtoon_flow": {
        "variants": [
            ("flow", {}, False),
            ("depth", {"detail": "depth"}, False),
            ("none", {"detail": "none"}, False),
        ],
        "full": (256, 192, 1, 8, 25),
        "quick": (192, 144, 1, 14, 17),
    },
    "tamiss_knot_orbit": {
        "variants": [
            ("tamiss", {"average_frames": 1}, True),  # the paper's: per-frame fits
            ("tamiss_avg4", {}, True),  # refnpr's default: 4 frames carried along the motion
            ("tam", TAM_KNOT, False),
        ],
        "full": (480, 360, 4, 0, 7),
        "quick": (160, 120, 1, 0, 3),
    },
}

#: (sequence, description, test on {label: summary}) -- the papers' claims as inequalities.
CLAIMS = [
    (
        "veryovka_dolly",
        "lines and CLAHE attached: median E/D < 0.5",
        lambda r: all(r[v]["ratio"]["median"] < 0.5 for v in ("lines", "clahe")),
    ),
    (
        "veryovka_dolly",
        "motion compensation removes flips: flip < flip_plain / 2 (both)",
        lambda r: all(
            r[v]["flip"]["median"] < 0.5 * r[v]["flip_plain"]["median"] for v in ("lines", "clahe")
        ),
    ),
    (
        "halftone_light_orbit",
        "binary pops: median jump(binary) > 3 x jump(smooth)",
        lambda r: r["binary"]["jump"]["median"] > 3 * r["smooth"]["jump"]["median"],
    ),
    (
        "halftone_light_orbit",
        "binary flips: median flip(binary) > 3 x flip(smooth)",
        lambda r: r["binary"]["flip"]["median"] > 3 * r["smooth"]["flip"]["median"],
    ),
    (
        "xtoon_flow",
        "flow detail steady: median E/D(flow) <= 2 x E/D(none)",
        lambda r: r["flow"]["ratio"]["median"] <= 2 * r["none"]["ratio"]["median"],
    ),
    (
        "xtoon_flow",
        "flow abstracts the mover: detail(mover) < detail(still) - 0.2 (flow only)",
        lambda r: r["flow"]["detail"]["mover"] < r["flow"]["detail"]["still"] - 0.2,
    ),
    (
        "tamiss_knot_orbit",
        "TAM steadier: median E/D(tam) < E/D(tamiss)",
        lambda r: r["tam"]["ratio"]["median"] < r["tamiss"]["ratio"]["median"],
    ),
    (
        "tamiss_knot_orbit",
        "TAM flips less: median flip(tam) < flip(tamiss) / 2",
        lambda r: r["tam"]["flip"]["median"] < 0.5 * r["tamiss"]["flip"]["median"],
    ),
]


def stills_and_style(scene_name: str, style: dict, a: int, b: int):
    """(stills of frames a..b-1, the still of frame a-1 or None, style for ``measure``)."""
    anim = load_scene(scene_name)
    stills = [anim.at(f) for f in range(a, b)]
    previous = anim.at(a - 1) if a > 0 else None
    if "name" in style:
        return stills, previous, dict(style)
    stills = [dataclasses.replace(s, style={**s.style, **style}) for s in stills]
    if previous is not None:
        previous = dataclasses.replace(previous, style={**previous.style, **style})
    return stills, previous, None


def jump_fractions(stills, images) -> list[float]:
    """Per pair, the fraction of M where |Y_t - warp(Y_{t-1})| > JUMP."""
    out, prev_gb = [], None
    h, w = images[0].shape[:2]
    for t, scene in enumerate(stills):
        gb = rasterize(scene, None, w, h, MOTION_CHANNELS, 1, dtype=np.float64)
        if prev_gb is not None:
            m = motion_field(gb, prev_gb, scene, stills[t - 1])
            n = int(m.valid.sum())
            y, y_hat = luminance(images[t]), warp(luminance(images[t - 1]), m)
            out.append(
                float(np.count_nonzero((np.abs(y - y_hat) > JUMP)[m.valid]) / n) if n else math.nan
            )
        prev_gb = gb
    return out


def flow_detail(stills, previous, style, w: int, h: int) -> dict[str, float]:
    """Mean X-Toon detail D (``show = "detail"``) on the mover and on the still teapots, at the
    middle frame of the range (its previous frame from the animation)."""
    k = len(stills) // 2
    scene, prev = stills[k], stills[k - 1] if k > 0 else previous
    spec = {**(style or scene.style), "show": "detail"}
    frame_style = style_from_spec(spec).for_frame(scene, prev)
    rgba, _ = render_frame(frame_style, scene, w, h, 1, None)
    d = linear_to_srgb(rgba[..., 0].astype(np.float64))  # show="detail": displayed value = D
    gb = rasterize(scene, None, w, h, ["mesh_id"], 1)
    names = [o.name for o in scene.objects]
    ids = np.asarray(gb["mesh_id"]).reshape(h, w)
    mover = ids == names.index("mover")
    still = np.isin(ids, [i for i, n in enumerate(names) if n.startswith("teapot")])
    return {
        "frame": k,
        "mover": float(d[mover].mean()) if mover.any() else math.nan,
        "still": float(d[still].mean()) if still.any() else math.nan,
        "mover_px": int(mover.sum()),
    }


def run_row(scene_name: str, label: str, style: dict, strokes: bool, settings) -> dict:
    w, h, spp, a, b = settings
    stills, previous, spec = stills_and_style(scene_name, style, a, b)
    stamps: list[float] = []
    t0 = time.perf_counter()
    report = measure(
        stills,
        spec,
        w,
        h,
        spp,
        frames=list(range(a, b)),
        keep_images=True,
        strokes=strokes,
        previous=previous,
        progress=lambda done, total: stamps.append(time.perf_counter()),
    )
    total = time.perf_counter() - t0
    steps = [t1 - t0_ for t0_, t1 in zip(stamps, stamps[1:], strict=False)]
    summary = report.summary()
    jumps = jump_fractions(stills, report.images)
    summary["jump"] = {"median": float(np.median(jumps)), "max": float(np.max(jumps))}
    row = {
        "sequence": scene_name,
        "variant": label,
        "style": report.meta["style"],
        "style_override": style,
        "size": [w, h],
        "spp": spp,
        "frames": [a, b - 1],
        "summary": summary,
        "pairs": [r.as_dict() for r in report.rows],
        "jump": jumps,
        "s_per_frame": statistics.median(steps) if steps else total,
        "total_s": total,
    }
    if strokes:
        row["strokes"] = [r.as_dict() for r in report.strokes]
    if scene_name == "xtoon_flow":
        row["summary"]["detail"] = flow_detail(stills, previous, spec, w, h)
    return row


def _f(v) -> str:
    return "     -" if v is None or (isinstance(v, float) and math.isnan(v)) else f"{v:6.4f}"


def print_table(rows: list[dict]) -> None:
    cols = ("warp_error", "plain_diff", "ratio", "flip", "flip_plain", "jump", "motion_px")
    head = "E", "D", "E/D", "flip", "flip_pl", "jump", "motion"
    print(
        f"{'sequence':22s} {'variant':7s} {'size':>9s} spp frames "
        + " ".join(f"{h:>13s}" for h in head)
        + "  s/frame  extra"
    )
    print(f"{'':51s}" + " ".join(f"{'median  max':>13s}" for _ in head))
    for r in rows:
        s = r["summary"]
        cells = " ".join(f"{_f(s[c]['median'])} {_f(s[c]['max'])}" for c in cols)
        extra = ""
        if "jitter_mean" in s:
            extra = (
                f"jitter {_f(s['jitter_mean']['median'])} px (p95 {_f(s['jitter_p95']['median'])}),"
                f" appeared {s['appeared']['median']:.0f} / vanished {s['vanished']['median']:.0f}"
                f" of {s['n_strokes']['median']:.0f}"
            )
        if "detail" in s:
            d = s["detail"]
            extra = f"detail mover {_f(d['mover'])} still {_f(d['still'])}"
        size = f"{r['size'][0]}x{r['size'][1]}"
        frames = f"{r['frames'][0]}-{r['frames'][1]}"
        print(
            f"{r['sequence']:22s} {r['variant']:7s} {size:>9s} {r['spp']:3d} {frames:>6s} "
            f"{cells}  {r['s_per_frame']:7.2f}  {extra}"
        )


def check_claims(rows: list[dict]) -> list[dict]:
    by_seq: dict[str, dict] = {}
    for r in rows:
        by_seq.setdefault(r["sequence"], {})[r["variant"]] = r["summary"]
    out = []
    for seq, text, test in CLAIMS:
        if seq not in by_seq:
            continue
        try:
            ok = bool(test(by_seq[seq]))
        except (KeyError, TypeError):
            ok = False
        out.append({"sequence": seq, "claim": text, "met": ok})
    return out


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="smaller sizes, 2 pairs each (< 1 min)")
    ap.add_argument("--sequences", default=",".join(SEQUENCES), help="comma-separated subset")
    ap.add_argument("--json", type=Path, default=None, help="write every row and pair as JSON")
    args = ap.parse_args(argv)
    names = [n.strip() for n in args.sequences.split(",") if n.strip()]
    unknown = sorted(set(names) - set(SEQUENCES))
    if unknown:
        ap.error(f"--sequences: unknown {unknown}; choose from {list(SEQUENCES)}")
    mode = "quick" if args.quick else "full"
    t0 = time.perf_counter()
    rows = []
    for name in names:
        cfg = SEQUENCES[name]
        for label, style, strokes in cfg["variants"]:
            rows.append(run_row(name, label, style, strokes, cfg[mode]))
            print(f"  {name} {label}: {rows[-1]['total_s']:.1f} s", file=sys.stderr, flush=True)
    print(f"temporal coherence ({mode}), luminance Y, medians and maxima over the pairs")
    print_table(rows)
    claims = check_claims(rows)
    for c in claims:
        print(f"  {'MET    ' if c['met'] else 'NOT MET'} {c['sequence']}: {c['claim']}")
    elapsed = time.perf_counter() - t0
    print(f"total {elapsed:.1f} s")
    if args.json:
        doc = {
            "meta": {
                "date": datetime.datetime.now(datetime.UTC).isoformat(timespec="seconds"),
                "python": platform.python_version(),
                "machine": platform.machine(),
                "mode": mode,
                "jump_threshold": JUMP,
                "total_s": elapsed,
                "command": "python benchmarks/bench_coherence.py " + " ".join(argv or sys.argv[1:]),
            },
            "rows": rows,
            "claims": claims,
        }
        args.json.parent.mkdir(parents=True, exist_ok=True)
        args.json.write_text(json.dumps(_no_nan(doc), indent=2, allow_nan=False) + "\n")
    return 0


def _no_nan(v):
    """``v`` with every NaN float replaced by None (strict JSON)."""
    if isinstance(v, float) and math.isnan(v):
        return None
    if isinstance(v, dict):
        return {k: _no_nan(x) for k, x in v.items()}
    if isinstance(v, (list, tuple)):
        return [_no_nan(x) for x in v]
    return v


if __name__ == "__main__":
    raise SystemExit(main())
