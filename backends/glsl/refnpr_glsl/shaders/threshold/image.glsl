// threshold style: image threshold pyramids (sec. 3.1) and the bump height pyramid, sampled
// exactly as refnpr/texture/_kernels.py does (GL_REPEAT bilinear per level, texel centres at
// (i + 0.5) / size, linear between levels) from texels in the DATA buffer (common/pyramid.glsl:
// level k of pyramid g: rows LV_ROWS[LV0[g] + k], cols LV_COLS[...], row-major at DATA[LV_OFF[...]]).
// refnpr: refnpr/styles/threshold/images.py, refnpr/texture/sample.py.
// HW_SAMPLING 1: the sampler hardware instead (textureLod on the kit's mip levels, GL_REPEAT,
// LINEAR_MIPMAP_LINEAR; hw_sample(g, uv, lod) is generated), to measure what a plain GPU
// texture fetch changes.

// bilinear GL_REPEAT sample of level k of pyramid g (k clamped to the pyramid); the taps and
// level weights are common/pyramid.glsl's
real sample_level(int g, rvec2 uv, int k) {
#if HW_SAMPLING
    return real(hw_sample(g, vec2(uv), float(clamp(k, 0, NLEV[g] - 1))));
#endif
    int lv = LV0[g] + clamp(k, 0, NLEV[g] - 1);
    int o = LV_OFF[lv];
    ivec4 t;
    real fx, fy;
    bilinear_taps(lv, uv, t, fx, fy);
    real s = (1.0 - fx) * (1.0 - fy) * real(DATA[o + t.x])
             + fx * (1.0 - fy) * real(DATA[o + t.y])
             + (1.0 - fx) * fy * real(DATA[o + t.z])
             + fx * fy * real(DATA[o + t.w]);
    return s;
}

real sample_trilinear(int g, rvec2 uv, float lod) {
    int k0, k1;
    float f;
    level_weights(g, lod, k0, k1, f);
#if HW_SAMPLING
    return real(hw_sample(g, vec2(uv), clamp(lod, 0.0, float(NLEV[g] - 1))));
#endif
    real s = (1.0 - real(f)) * sample_level(g, uv, k0);
    if (f > 0.0) s += real(f) * sample_level(g, uv, k1);
    return s;
}

// GL isotropic LOD from per-pixel uv derivatives (texels of level 0) + bias
float texture_lod(int g, vec2 gx, vec2 gy, float bias) {
    int lv = LV0[g];
    vec2 size = vec2(float(LV_COLS[lv]), float(LV_ROWS[lv]));
    float rho = max(length(gx * size), length(gy * size));
    return log2(max(rho, exp2(-64.0))) + bias;
}

#if TONE_CORRECT
// np.interp(t, q_k, linspace(0, 1, 1025)) with q_k the level's interpolant quantiles
float tone_map(int g, int k, float t) {
    int base = TM_OFF[g] + clamp(k, 0, NLEV[g] - 1) * 1025;
    float q0 = DATA[base], qn = DATA[base + 1024];
    if (qn - q0 <= 0.0) return 0.5;
    if (t < q0) return 0.0;
    if (t >= qn) return 1.0;
    int lo = 0, hi = 1024;  // largest lo with q[lo] <= t
    while (hi - lo > 1) {
        int mid = (lo + hi) / 2;
        if (DATA[base + mid] <= t) lo = mid; else hi = mid;
    }
    float a = DATA[base + lo], b = DATA[base + lo + 1];
    float w = b > a ? (t - a) / (b - a) : 0.0;
    return (float(lo) + w) / 1024.0;
}
#endif
