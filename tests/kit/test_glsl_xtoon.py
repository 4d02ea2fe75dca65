"""The GLSL xtoon pass (backends/glsl/refnpr_glsl/styles/xtoon.py) against refnpr's XToonStyle.

Three levels:

* ``test_shade_matches_refnpr_per_sample``: every golden xtoon case's style and scene at a
  small size, refnpr's own G-buffer uploaded as textures, the GLSL ``shade`` compared per sample
  with ``XToonStyle.shade`` on the same G-buffer (isolates the shading from rasterization);
  ``test_variant_matches_refnpr_per_sample`` does the same for parameter combinations no golden
  case uses.
* ``test_kit_case_passes_its_tolerance``: the style's golden cases exported as a kit, rendered
  by the backend driver (``python -m refnpr_glsl``, analytic derivatives) and compared by
  ``refnpr kit check``'s comparator with each case's own tolerance; ``KNOWN_FAILURES`` lists the
  cases that do not pass, with the reason (none).
* ``test_kit_case_with_quad_derivatives``: the same with ``--derivatives quad``;
  ``QUAD_KNOWN_FAILURES`` lists the cases that do not pass that way, with the reason.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from ._harness import (
    assert_passed,
    assert_samples_match,
    case_params,
    export_cases,
    isolated,
    point_lit,
    render_and_check,
    style_cases,
)

STYLE = "xtoon"

#: Per-sample agreement of the isolated pass: |GLSL - refnpr| on linear RGBA. Most cases agree
#: to float32 rounding (~1e-6); hard toon-texture steps and per-vertex values computed from the
#: float32 glTF vertices may flip single samples, so a small fraction may exceed 2/255.
MAX_FRAC_OVER = 0.002
THRESHOLD = 2.0 / 255.0

#: Kit cases (refnpr kit check, own tolerance) known not to pass, with the reason.
KNOWN_FAILURES: dict[str, str] = {}

#: Kit cases that do not pass with ``--derivatives quad`` (dFdx/dFdy), with the reason. X-Toon
#: reads no screen derivatives, so the choice only reaches it through the rasterizer.
QUAD_KNOWN_FAILURES: dict[str, str] = {}

CASES = style_cases(STYLE)
NAMES = [c.name for c in CASES]


@pytest.mark.parametrize("name", NAMES)
def test_shade_matches_refnpr_per_sample(gl, tmp_path, name):
    from refnpr_glsl.styles import xtoon

    case = CASES[NAMES.index(name)]
    w, h = (48, 36) if case.width >= 192 else (case.width, case.height)
    spp = 1
    got, ref = isolated(gl, case, tmp_path, w, h, spp, xtoon)
    assert_samples_match(got, ref, name, THRESHOLD, MAX_FRAC_OVER)


@pytest.fixture(scope="module")
def exported_kit(tmp_path_factory) -> Path:
    """This style's golden cases exported as a kit (``refnpr kit export --only ...``)."""
    return export_cases(tmp_path_factory, STYLE, NAMES)


@pytest.fixture(scope="module")
def kit_results(exported_kit) -> dict:
    return render_and_check(exported_kit, NAMES)


@pytest.fixture(scope="module")
def kit_results_quad(exported_kit) -> dict:
    return render_and_check(exported_kit, NAMES, "quad")


@pytest.mark.parametrize("name", case_params(NAMES, KNOWN_FAILURES))
def test_kit_case_passes_its_tolerance(kit_results, name):
    """The backend's render (analytic derivatives) passes the case's own tolerance."""
    assert_passed(kit_results, name)


@pytest.mark.parametrize("name", case_params(NAMES, QUAD_KNOWN_FAILURES))
def test_kit_case_with_quad_derivatives(kit_results_quad, name):
    """The same with ``--derivatives quad`` (dFdx/dFdy, what a plain GPU shader gets)."""
    assert_passed(kit_results_quad, name)


def _variants() -> dict:
    """Parameter combinations no golden case uses, on the same scenes (48 x 36 unless noted)."""
    rng = np.random.default_rng(7)
    lit = point_lit("xtoon_teapot", (3.0, 4.0, 1.0), (1.0, 1.0, 1.0))
    return {
        "map-per-pixel": ("xtoon_teapot", dict(texture="toon", detail="map",
                          detail_map=rng.random((36, 48))), 1),
        "map-per-pixel-spp4": ("xtoon_teapot", dict(texture="loa_levels", detail="map",
                               detail_map=rng.random((36, 48))), 4),
        "map-per-sample": ("xtoon_teapot", dict(texture="loa_blur", detail="map",
                           detail_map=rng.random((72, 96))), 4),
        "weight-map": ("xtoon_teapot", dict(texture="toon", detail="none", shape="sphere",
                       shape_blend="pixel", shape_weight=rng.random((36, 48)))),
        "modulate": ("teapot", dict(texture="toon", detail="orientation", modulate=True)),
        "point-light-highlight": (lit, dict(texture="metal", detail="highlight", s=6.0)),
        "point-light-vertex": (lit, dict(texture="plastic", detail="highlight",
                               detail_mode="vertex", tone="half_lambert")),
        "vertex-detail-weight": ("xtoon_row", dict(texture="loa_levels", detail="depth",
                                 detail_mode="vertex", z_min=18.0, r=3.0, shape="ellipsoid",
                                 shape_weight="detail")),
        "vertex-orientation-shape": ("xtoon_teapot", dict(texture="silhouette_fade",
                                     detail="orientation", detail_mode="vertex", r=2.0,
                                     shape="cylinder", shape_weight=0.6)),
        "focus-axis": ("xtoon_row", dict(texture="dof_blur", detail="focus", distance="axis",
                       focus_point=[-6.0, 1.5, -18.0], z_min=3.0, r=4.0)),
        "depth-auto-eye": ("xtoon_row", dict(texture="loa_blur", detail="depth",
                           distance="eye")),
        "shape-objects": ("xtoon_row", dict(texture="toon", detail="none", shape="smoothed",
                          shape_iterations=5, shape_objects=["teapot0", "teapot2"])),
        "flow-weight-detail": ("xtoon_row_floor", dict(texture="loa_receding", detail="flow",
                               flow_min=1.0, flow_max=10.0, shape="sphere",
                               shape_blend="pixel", shape_weight="detail",
                               prev_camera={"eye": [15.0, 12.0, 11.0],
                                            "target": [-6.5, -0.5, -16.0], "fov_y": 36.0})),
        "show-tone": ("xtoon_teapot", dict(texture="toon", detail="none", show="tone",
                      tone="half_lambert")),
    }  # fmt: skip


VARIANTS = _variants()


@pytest.mark.parametrize("name", sorted(VARIANTS))
def test_variant_matches_refnpr_per_sample(gl, tmp_path, name):
    """Detail maps, weights, modes and lights that the golden suite does not exercise."""
    from types import SimpleNamespace

    from refnpr_glsl.styles import xtoon

    from refnpr.styles.xtoon import XToonStyle

    scene, params, *rest = VARIANTS[name]
    spp = rest[0] if rest else 1
    case = SimpleNamespace(name=name, scene=scene, style=XToonStyle(**params))
    got, ref = isolated(gl, case, tmp_path, 48, 36, spp, xtoon)
    assert_samples_match(got, ref, name, THRESHOLD, MAX_FRAC_OVER)
