"""The tam and tamiss defaults give a readable drawing at common sizes.

Measured on the teapot-on-a-floor scene at 256 x 192 and 768 x 576, per covered sample, against
the darkness the strokes reproduce (1 - diffuse luminance, the styles' tone): ink on the shadowed
side of the teapot, on its lit side and on the floor. The old defaults (one layer, density 1,
strokes clipped at silhouettes) left the shadow at about a fifth ink, hardly darker than the
floor: the same measure fails them.
"""

from __future__ import annotations

import pytest

from refnpr.raster import rasterize
from refnpr.scenes import load_scene
from refnpr.styles import get_style
from refnpr.styles.base import ShadeContext
from refnpr.styles.tamiss import field_inputs

SIZES = [(256, 192), (768, 576)]


def measure(spec: dict, width: int, height: int) -> dict[str, float]:
    """Mean ink coverage of the teapot's shadowed (darkness > 0.7) and lit (< 0.3) samples, of
    the floor, and of three darkness bands on the teapot."""
    sc = load_scene("teapot")
    st = get_style(**spec)
    chans = sorted(st.requires(sc))
    gb = rasterize(sc, sc.camera, width, height, chans, 1, **st.raster_options(sc))
    ctx = ShadeContext(gb, sc)
    ink = st.run(ctx).ink if st.name == "tamiss" else st.ink_coverage(ctx)
    inp = field_inputs(gb, sc)
    d = inp.darkness
    i = ink.ravel()[inp.sample]
    pot = gb["mesh_id"][gb["tri_id"] >= 0] == 0
    out = {
        "shadow": i[pot & (d > 0.7)].mean(),
        "lit": i[pot & (d < 0.3)].mean(),
        "floor": i[~pot].mean(),
    }
    for k, (lo, hi) in enumerate(((0.0, 0.3), (0.3, 0.6), (0.6, 1.01))):
        out[f"band{k}"] = i[pot & (d >= lo) & (d < hi)].mean()
    return {k: float(v) for k, v in out.items()}


# (style, the least shadow ink, the least shadow - lit contrast, shadow / floor at least)
TARGETS = [("tamiss", 0.35, 0.22, 1.8), ("tam", 0.33, 0.22, 2.0)]


@pytest.mark.parametrize(("width", "height"), SIZES)
@pytest.mark.parametrize(("name", "dark", "contrast", "over_floor"), TARGETS)
def test_defaults_read_as_a_drawing(name, dark, contrast, over_floor, width, height):
    m = measure({"name": name}, width, height)
    assert m["shadow"] >= dark, m
    assert m["shadow"] - m["lit"] >= contrast, m
    assert m["shadow"] >= over_floor * m["floor"], m  # the teapot does not dissolve into the floor
    assert m["lit"] < m["floor"] < m["shadow"], m  # it stands out on both sides
    assert m["band0"] + 0.05 < m["band1"] < m["band2"] - 0.05, m  # tone follows the darkness


@pytest.mark.parametrize(("name", "dark", "contrast", "over_floor"), TARGETS)
def test_the_old_defaults_fail_the_same_measure(name, dark, contrast, over_floor):
    old = {"directions": ["u"], "density": 1.0} | (
        {"extent": "visible"} if name == "tamiss" else {}
    )
    m = measure({"name": name, **old}, *SIZES[0])
    assert m["shadow"] < dark or m["shadow"] < over_floor * m["floor"], m


def test_defaults_are_cross_hatching_with_density_two():
    for name in ("tam", "tamiss"):
        p = get_style(name).params()
        assert p["directions"] == [0.0, 90.0] and p["layer_tones"] == [0.0, 0.5], p
        assert p["density"] == 2.0 and p["period"] == 4.0
    assert get_style("tamiss").params()["extent"] == "overdraw"  # Fig. 4: no clipped strokes
