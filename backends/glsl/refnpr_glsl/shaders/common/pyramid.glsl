// Texture pyramids in a float storage buffer, filtered in the shader exactly as refnpr's
// refnpr/device/sampling.py (GL_REPEAT bilinear per level, texel centres at (i + 0.5) / size,
// linear between levels). Level k of pyramid g is lv = LV0[g] + k: LV_ROWS[lv] x LV_COLS[lv]
// texels, row-major (row 0 = v 0) from LV_OFF[lv] in the buffer (refnpr_glsl/pyramids.py).
// Needs before it: real / rvec2 (float or double) and the constants LV0, NLEV, LV_OFF,
// LV_ROWS, LV_COLS. Shared by the threshold style and the colour maps of smooth and toon.

int wrap_i(int i, int n) {
    int r = i % n;
    return r < 0 ? r + n : r;
}

// The GL_LINEAR / GL_REPEAT sample of level lv at uv: x = frac(u) cols - 0.5, y = frac(v) rows
// - 0.5, i = floor(x), j = floor(y), fx = x - i, fy = y - j; idx holds the texel indices
// (row * cols + col) of t[j][i], t[j][i+1], t[j+1][i], t[j+1][i+1] (columns / rows wrapped),
// to be weighted (1 - fx)(1 - fy), fx (1 - fy), (1 - fx) fy, fx fy and summed in that order.
void bilinear_taps(int lv, rvec2 uv, out ivec4 idx, out real fx, out real fy) {
    int rows = LV_ROWS[lv], cols = LV_COLS[lv];
    real x = (uv.x - floor(uv.x)) * real(cols) - 0.5;
    real y = (uv.y - floor(uv.y)) * real(rows) - 0.5;
    real x0 = floor(x), y0 = floor(y);
    fx = x - x0;
    fy = y - y0;
    int i0 = wrap_i(int(x0), cols), i1 = wrap_i(int(x0) + 1, cols);
    int j0 = wrap_i(int(y0), rows), j1 = wrap_i(int(y0) + 1, rows);
    idx = ivec4(j0 * cols + i0, j0 * cols + i1, j1 * cols + i0, j1 * cols + i1);
}

// The two levels trilinear filtering blends: lambda clamped to [0, L - 1], k0 = floor,
// k1 = min(k0 + 1, L - 1), f = lambda - k0 (the sample is (1 - f) B_k0, then + f B_k1 if f > 0).
void level_weights(int g, float lod, out int k0, out int k1, out float f) {
    float lam = clamp(lod, 0.0, float(NLEV[g] - 1));
    k0 = int(floor(lam));
    k1 = min(k0 + 1, NLEV[g] - 1);
    f = lam - float(k0);
}
