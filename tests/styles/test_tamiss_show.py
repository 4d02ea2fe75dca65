"""The ``show`` views of the tamiss style: the pipeline stages of Figs. 5 and 6, the nesting of Fig. 2.

Each view is checked against the pipeline's own intermediate results (fragments, strips, ids),
not against stored pictures.
"""

from __future__ import annotations

import numpy as np
import pytest

from refnpr.raster import rasterize
from refnpr.scenes import load_scene
from refnpr.styles import get_style
from refnpr.styles.base import ShadeContext
from refnpr.styles.tamiss import unpack_id
from refnpr.styles.tamiss.show import LEVEL_COLORS, id_colors, level_colors, show_layers

FIELD = {"directions": ["u", "v"], "period": 4.0, "extent": "overdraw"}


def _ctx(scene="tamiss_teapot", w=160, h=120, **params):
    sc = load_scene(scene)
    st = get_style("tamiss", **FIELD, **params)
    gb = rasterize(sc, sc.camera, w, h, sorted(st.requires(sc)), 1, **st.raster_options(sc))
    return st, ShadeContext(gb, sc)


def test_id_colors_are_deterministic_distinct_and_visible():
    ids = np.arange(1000, dtype=np.int64) * 7919
    c = id_colors(ids)
    assert c.shape == (1000, 3) and np.all((c >= 0.06) & (c <= 0.71))
    np.testing.assert_array_equal(c, id_colors(ids))
    assert len({tuple(np.round(x, 6)) for x in c}) > 990
    assert np.all(c.max(axis=1) - c.min(axis=1) > 0.5)  # saturated: never grey


def test_ids_view_shows_the_first_fragment_of_each_sample():
    st, ctx = _ctx(show="ids")
    r = st.run(ctx)
    cover, rgb = show_layers(r)
    f = r.fragments
    first = np.r_[True, f.sample[1:] != f.sample[:-1]]
    flat_c = cover.ravel()
    assert set(np.flatnonzero(flat_c)) == set(f.sample)
    np.testing.assert_array_equal(rgb.reshape(-1, 3)[f.sample[first]], id_colors(f.id[first]))


def test_strokes_and_levels_views_cover_exactly_the_ink():
    st, ctx = _ctx(show="strokes")
    r = st.run(ctx)
    for show in ("strokes", "levels"):
        st2, _ = _ctx(show=show)
        cover, rgb = show_layers(st2.run(ctx))
        np.testing.assert_allclose(cover, r.ink, atol=1e-12)  # same strips, colour only
    # where one stroke alone covers a sample fully, it shows its own colour
    cover, rgb = show_layers(st.run(ctx))
    solo = (r.pieces == 1) & (cover > 0.999)
    assert solo.sum() > 50
    colours = {tuple(np.round(c, 9)) for c in id_colors(r.strips.ids)}
    assert all(tuple(np.round(c, 9)) in colours for c in rgb[solo][:200])
    st3, _ = _ctx(show="levels")
    _, rgb_l = show_layers(st3.run(ctx))
    palette = {tuple(c) for c in LEVEL_COLORS}
    assert all(tuple(c) in palette for c in np.round(rgb_l[solo], 12).tolist())
    levels = unpack_id(r.strips.ids)["level"]
    np.testing.assert_array_equal(level_colors(r.strips.ids), LEVEL_COLORS[np.minimum(levels, 6)])


def test_fits_view_draws_every_kept_stroke_thin():
    st, ctx = _ctx(show="fits")
    r = st.run(ctx)
    cover, _ = show_layers(r)
    assert 0 < cover.sum() < r.ink.sum()  # one pixel wide over [t_min, t_max], vs 1.5 px strokes
    assert np.count_nonzero(cover) > 0.5 * np.count_nonzero(r.ink > 0.5)


def test_show_color_is_the_default_and_unchanged():
    st, ctx = _ctx()
    st2, _ = _ctx(show="color")
    np.testing.assert_array_equal(st.shade(ctx), st2.shade(ctx))
    assert st.params()["show"] == "color"


def test_show_errors():
    with pytest.raises(ValueError, match=r"show: expected one of \['color', 'ids', 'fits'"):
        get_style("tamiss", show="fragments")


def test_fig2_nesting_scene_changes_level_with_depth():
    """Fig. 2's property on its case: the far plane shows only coarse strokes, the near plane
    adds every finer level while keeping the coarse ones (per birth level, strokes per row of
    the image grow towards the camera)."""
    sc = load_scene("tamiss_tonal_art_map")
    st = get_style("tamiss", directions=["u"], density=1.0, show="levels")
    gb = rasterize(sc, sc.camera, 480, 270, sorted(st.requires(sc)), 1, **st.raster_options(sc))
    r = st.run(ShadeContext(gb, sc))
    levels = unpack_id(r.strips.ids)["level"]
    y_mid = np.array([np.nanmean(s[..., 1]) for s in r.strips.strip.left])
    top, bottom = y_mid < 100, y_mid > 200
    assert levels[top].max() < levels[bottom].max() and levels[bottom].max() >= 3  # finer near
    assert np.any(levels[bottom] == levels[top].min())  # the coarse strokes persist near
