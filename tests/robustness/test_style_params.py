"""Catalogue: bad style parameters (messages naming an inner variable, nonsense accepted).

Every case goes through public APIs (``render``, ``required_channels``) or the ``refnpr``
command, so the same catalogue runs against any version of the styles.
"""

from __future__ import annotations

import warnings
from pathlib import Path
from typing import Any

import numpy as np

from refnpr.render import render, required_channels

from .catalogue import Case, Correct, Exits, Raises, cli, parametrize

VE = ValueError
TE = TypeError
ANY = (ValueError, TypeError)
NAN = float("nan")
CAM = {"eye": [0.0, 0.5, 4.0], "target": [0.0, 0.0, 0.0]}


def _render(scene: str, style: str, **params: Any):
    def run(tmp: Path):
        return render(scene, {"name": style, **params}, 16, 16)

    return run


def _cli(scene: str, style: str, *params: str):
    def run(tmp: Path):
        args = ["render", "--scene", scene, "--style", style]
        for p in params:
            args += ["--param", p]
        return cli(*args, "--size", "16x16", "-o", str(tmp / "o.png"))

    return run


def _warned(scene: str, style: str, **params: Any):
    """Render and return the warnings raised (the check looks for the parameter's)."""

    def run(tmp: Path):
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            image = render(scene, {"name": style, **params}, 16, 16)
        assert np.all(np.isfinite(image.rgba))
        return [str(w.message) for w in caught if issubclass(w.category, UserWarning)]

    return run


def _warns(*needles: str):
    def check(messages: list[str], tmp: Path) -> None:
        assert any(all(n in m for n in needles) for m in messages), (
            f"no warning naming {needles}: {messages}"
        )

    return Correct(check)


def _no_uv(result: frozenset, tmp: Path) -> None:
    assert "uv" not in result, f"asks for uv: {sorted(result)}"


def _channels(scene: str, style: str, **params: Any):
    def run(tmp: Path):
        return required_channels(scene, {"name": style, **params})

    return run


M, N = "messages", "nonsense"
CASES = [
    # --- messages that once named an inner variable instead of the parameter -----------------
    Case(
        "halftone-uv-scale-1e300",
        M,
        "halftone uv_scale=1e300",
        _render("halftone_sphere", "halftone", uv_scale=1e300),
        Raises(VE, r"uv_scale: .*\[1e-06, 1e\+06\].*got 1e\+300"),
    ),
    Case(
        "halftone-object-uv-scale-1e300",
        M,
        "halftone objects.uv_sphere.uv_scale=[1, 1e300]",
        _render("halftone_sphere", "halftone", objects={"uv_sphere": {"uv_scale": [1, 1e300]}}),
        Raises(VE, r"objects\.uv_sphere\.uv_scale: .*1e\+300"),
    ),
    Case(
        "halftone-binary-uv-scale-1e300",
        M,
        "halftone threshold='binary' uv_scale=1e300",
        _render("halftone_sphere", "halftone", threshold="binary", uv_scale=1e300),
        Raises(VE, r"uv_scale: .*got 1e\+300"),
    ),
    Case(
        "tamiss-prior-weight-1e300",
        M,
        "tamiss prior_weight=1e300",
        _render("tamiss_sphere", "tamiss", prior_weight=1e300),
        Raises(VE, r"prior_weight: expected a value in \[0, 1e\+06\], got 1e\+300"),
    ),
    Case(
        "xtoon-focus-point-0",
        M,
        "xtoon focus_point=0 (default detail='depth')",
        _warned("sphere", "xtoon", focus_point=0),
        _warns("focus_point: 0 is ignored with detail='depth'", "detail='focus'"),
    ),
    Case(
        "threshold-period-constant",
        M,
        "threshold source='constant' period=4 (no lines or dots to space)",
        _warned("sphere", "threshold", source="constant", period=4.0),
        _warns(
            "period: 4.0 is ignored with source='constant'", "source='lines' or source='stipple'"
        ),
    ),
    Case(
        "threshold-clahe-window-lines",
        M,
        "threshold source='lines' window=8 (CLAHE of an image texture only)",
        _warned("sphere", "threshold", source="lines", window=8),
        _warns("window: 8 is ignored with source='lines'", "use source='image'"),
    ),
    Case(
        "threshold-mip-unfiltered-image",
        M,
        "threshold source='image' mip='trilinear' (the mip mode of pcf only)",
        _warned("sphere", "threshold", source="image", mip="trilinear"),
        _warns("mip: 'trilinear' is ignored with filter='none'", "use filter='pcf'"),
    ),
    Case(
        "xtoon-focus-point-0-focus",
        M,
        "xtoon detail='focus' focus_point=0",
        _render("sphere", "xtoon", detail="focus", focus_point=0),
        Raises(VE, r"focus_point: expected 3 finite numbers .*got 0"),
    ),
    Case(
        "xtoon-shape-objects-int",
        M,
        "xtoon shape='smoothed' shape_objects=0",
        _render("sphere", "xtoon", shape="smoothed", shape_objects=0),
        Raises(TE, r"shape_objects: expected a list of object names, got int 0"),
    ),
    Case(
        "threshold-noise-scale-1e20",
        M,
        "threshold noise=0.5 noise_scale=1e20",
        _render("room", "threshold", noise=0.5, noise_scale=1e20),
        Raises(VE, r"noise_scale: expected a value in \(0, 1e\+06\], got 1e\+20"),
    ),
    Case(
        "threshold-noise-uv-scale-1e300",
        M,
        "threshold noise=0.5 uv_scale=1e300",
        _render("room", "threshold", noise=0.5, uv_scale=1e300),
        Raises(VE, r"uv_scale: .*got 1e\+300"),
    ),
    Case(
        "tamiss-ink-none",
        M,
        "tamiss ink=None",
        _render("tamiss_sphere", "tamiss", ink=None),
        Raises(TE, r"ink: expected 3 numbers .*got None"),
    ),
    Case(
        "tam-ink-none",
        M,
        "tam ink=None",
        _render("tamiss_sphere", "tam", ink=None),
        Raises(TE, r"ink: expected 3 numbers .*got None"),
    ),
    Case(
        "tam-base-int",
        M,
        "tam base=0",
        _render("tamiss_sphere", "tam", base=0),
        Raises(TE, r"base: expected a style name.*got int 0"),
    ),
    Case(
        "tamiss-base-unknown",
        M,
        "tamiss base='x'",
        _render("tamiss_sphere", "tamiss", base="x"),
        Raises(VE, r"base: .*unknown style 'x'"),
    ),
    Case(
        "contoured-base-empty-table",
        M,
        "contoured base={}",
        _render("sphere", "contoured", base={}),
        Raises(VE, r"base: .*needs a 'name' key.*\{\}"),
    ),
    Case(
        "contoured-base-nested-error",
        M,
        "contoured base={name='toon', n=0}",
        _render("sphere", "contoured", base={"name": "toon", "n": 0}),
        Raises(VE, r"base: n: expected an integer in \[1, 256\], got 0"),
    ),
    Case(
        "contours-width-nan",
        M,
        "toon with contours={width=nan}",
        _render("sphere", "toon", contours={"width": float("nan")}),
        Raises(VE, r"contours\.width: expected a finite number, got nan"),
    ),
    Case(
        "cli-halftone-uv-scale-1e300",
        M,
        "refnpr render --style halftone --param uv_scale=1e300",
        _cli("halftone_sphere", "halftone", "uv_scale=1e300"),
        Exits(2, r"error: uv_scale: .*got 1e\+300"),
    ),
    Case(
        "cli-tamiss-prior-weight-1e300",
        M,
        "refnpr render --style tamiss --param prior_weight=1e300",
        _cli("tamiss_sphere", "tamiss", "prior_weight=1e300"),
        Exits(2, r"error: prior_weight: .*got 1e\+300"),
    ),
    Case(
        "cli-xtoon-focus-point-0",
        M,
        "refnpr render --style xtoon --param focus_point=0",
        _cli("sphere", "xtoon", "focus_point=0"),
        Exits(0, r"refnpr render: warning: focus_point: 0 is ignored with detail='depth'"),
    ),
    Case(
        "cli-threshold-noise-scale-1e20",
        M,
        "refnpr render --style threshold --param noise=0.5 --param noise_scale=1e20",
        _cli("room", "threshold", "noise=0.5", "noise_scale=1e20"),
        Exits(2, r"error: noise_scale: .*got 1e\+20"),
    ),
    Case(
        "cli-tam-base-int",
        M,
        "refnpr render --style tam --param base=3",
        _cli("tamiss_sphere", "tam", "base=3"),
        Exits(2, r"error: .*base: expected a style name.*got int 3"),
    ),
    # --- nonsense accepted: parameters the chosen mode ignores, absurd sizes ---------------
    Case(
        "xtoon-detail-map-nan-depth",
        N,
        "xtoon detail_map=nan with detail='depth'",
        _warned("sphere", "xtoon", detail_map=float("nan")),
        _warns("detail_map: nan is ignored with detail='depth'"),
    ),
    Case(
        "xtoon-prev-camera-depth",
        N,
        "xtoon prev_camera={eye, target} with detail='depth'",
        _warned("sphere", "xtoon", prev_camera=CAM),
        _warns("prev_camera: {'eye'", "is ignored with detail='depth'"),
    ),
    Case(
        "xtoon-z-min-highlight",
        N,
        "xtoon detail='highlight' z_min=2.0",
        _warned("sphere", "xtoon", detail="highlight", z_min=2.0),
        _warns("z_min: 2.0 is ignored with detail='highlight'"),
    ),
    Case(
        "xtoon-r-none",
        N,
        "xtoon detail='none' r=3.0",
        _warned("sphere", "xtoon", detail="none", r=3.0),
        _warns("r: 3.0 is ignored with detail='none'"),
    ),
    Case(
        "xtoon-shape-objects-no-shape",
        N,
        "xtoon shape_objects=['uv_sphere'] without a shape",
        _warned("sphere", "xtoon", shape_objects=["uv_sphere"]),
        _warns("shape_objects: ['uv_sphere'] is ignored with shape=None"),
    ),
    Case(
        "threshold-uv-scale-1e300",
        N,
        "threshold uv_scale=1e300 (lines a 1e-300 texel apart)",
        _render("room", "threshold", uv_scale=1e300),
        Raises(VE, r"uv_scale: .*got 1e\+300"),
    ),
    Case(
        "threshold-directions-10000",
        N,
        "threshold directions=[0.5] * 10000 (10000 hatching layers)",
        _render("room", "threshold", directions=[0.5] * 10_000),
        Raises(VE, r"directions: expected at most 64 values .*got a list of 10000"),
    ),
    Case(
        "halftone-c-binary",
        N,
        "halftone threshold='binary' c=8 (the binary threshold has no slope)",
        _warned("halftone_sphere", "halftone", threshold="binary", c=8.0),
        _warns("c: 8.0", "threshold='binary'"),
    ),
    Case(
        "halftone-centred-binary",
        N,
        "halftone threshold='binary' centred=true",
        _warned("halftone_sphere", "halftone", threshold="binary", centred=True),
        _warns("centred: True", "threshold='binary'"),
    ),
    Case(
        "threshold-texture-lines",
        N,
        "threshold source='lines' texture='brick'",
        _warned("room", "threshold", texture="brick"),
        _warns("texture: 'brick'", "source='lines'"),
    ),
    Case(
        "threshold-onsets-stipple",
        N,
        "threshold source='stipple' onsets=[1.0]",
        _warned("room", "threshold", source="stipple", onsets=[1.0]),
        _warns("onsets: [1.0]", "source='stipple'"),
    ),
    Case(
        "threshold-samples-no-filter",
        N,
        "threshold samples=9 with filter='none'",
        _warned("room", "threshold", samples=9),
        _warns("samples: 9", "filter='none'"),
    ),
    Case(
        "threshold-image-untextured-uv",
        N,
        "threshold source='image' on an untextured scene asks for uv",
        _channels("sphere", "threshold", source="image"),
        Correct(_no_uv),
        notes="every object gets the constant t: the skip rule says no uv",
    ),
    Case(
        "halftone-c-huge-int",
        M,
        "halftone c=10**400 (an integer beyond the float range)",
        _render("halftone_sphere", "halftone", c=10**400),
        Raises(VE, r"c: expected a finite number, got an integer beyond the float range"),
    ),
    Case(
        "halftone-engraving-angle-huge-int",
        M,
        "halftone screen={kind='engraving', angle=10**400}",
        _render("halftone_sphere", "halftone", screen={"kind": "engraving", "angle": 10**400}),
        Raises(VE, r"screen\.angle: expected a finite number, got an integer beyond"),
    ),
    Case(
        "halftone-engraving-angle-nan",
        M,
        "halftone screen={kind='engraving', angle=nan}",
        _render("halftone_sphere", "halftone", screen={"kind": "engraving", "angle": NAN}),
        Raises(VE, r"screen\.angle: expected a finite number of degrees, got nan"),
    ),
    Case(
        "halftone-dither-rank-equalize-1",
        M,
        "halftone screen={kind='dither', rank_equalize=1}",
        _render(
            "halftone_sphere",
            "halftone",
            screen={"kind": "dither", "texture": "brick", "rank_equalize": 1},
        ),
        Raises(TE, r"screen\.rank_equalize: expected a bool, got 1"),
    ),
    Case(
        "halftone-dither-window-0",
        M,
        "halftone screen={kind='dither', window=0}",
        _render(
            "halftone_sphere",
            "halftone",
            screen={"kind": "dither", "texture": "brick", "window": 0},
        ),
        Raises(VE, r"screen\.window: expected an integer >= 2, got 0"),
    ),
    Case(
        "xtoon-complex-texture",
        M,
        "xtoon texture=<complex array>",
        _render("sphere", "xtoon", texture=np.zeros((4, 8, 3), complex)),
        Raises(TE, r"texture: expected a real texture array, got a complex one"),
    ),
    Case(
        "toon-contours-0",
        N,
        "toon contours=0 (an integer, not False)",
        _render("sphere", "toon", contours=0),
        Raises(TE, r"contours: expected a ContourLayer, a table or True, got 0"),
    ),
    Case(
        "threshold-t-lines",
        N,
        "threshold source='lines' t=0.1 (the constant threshold of source constant and image)",
        _warned("room", "threshold", source="lines", t=0.1),
        _warns("t: 0.1 is ignored with source='lines'", "source='constant'"),
    ),
    Case(
        "cli-xtoon-detail-map-nan",
        N,
        "refnpr render --style xtoon --param detail_map=nan",
        _cli("sphere", "xtoon", "detail_map=nan"),
        Exits(0, r"refnpr render: warning: detail_map: nan is ignored with detail='depth'"),
    ),
]

test_case = parametrize(CASES)
