// threshold style: screen-round jittered multi-scale stipple (Fig. 4). refnpr:
// refnpr/formulas/threshold/stipple.py. Lattice in "real"; the row and dot hashes read the
// float64 bits of the row's exact v and the dot's exact lattice u; the dot areas in float.

real row_phase(real v_row) {
    uint64_t h = bits_d(v_row) * M1 + uint64_t(NOISE_SEED) * M3;
    return unit64(mix64(h));
}

void dot_offsets(real v_row, real u_dot, out real hu, out real hv) {
    uint64_t h = mix64(bits_d(v_row) * M1 + uint64_t(NOISE_SEED) * M3 + 1ul);
    h = mix64(h ^ (bits_d(u_dot) * M2));
    uint64_t g = mix64(h + M1);
    hu = unit64(h);
    hv = unit64(g);
}

float prim_arc(float x, float r) {  // antiderivative of sqrt(r^2 - x^2)
    float root = sqrt(max(r * r - x * x, 0.0));
    return 0.5 * (x * root + r * r * atan(x, root));
}

float quadrant_area(float r, float xh, float yh) {
    float m = min(xh, r);
    float xc = min(sqrt(max(r * r - yh * yh, 0.0)), m);
    return yh * xc + prim_arc(m, r) - prim_arc(xc, r);
}

float round_dot(real u, real v, int ku, int kv, float a_u, float a_v) {
    real big_v = v * pow2_r(kv);
    real j = floor(big_v + 0.5);
    real dv = big_v - j;
    real v_row = j * pow2_r(-kv);
    real phase = JITTER > 0.0 ? row_phase(v_row) : 0.0;
    real big_u = (u - phase) * pow2_r(ku);
    real i = floor(big_u + 0.5);
    real du = big_u - i;
    float ou = 0.0, ov = 0.0;
    if (JITTER > 0.0) {
        real hu, hv;
        dot_offsets(v_row, i * pow2_r(-ku), hu, hv);
        ou = float(real(JITTER) * (2.0 * hu - 1.0));
        ov = float(real(JITTER) * (2.0 * hv - 1.0));
    }
    float r = length(vec2(float(du - real(ou)) * a_u, float(dv - real(ov)) * a_v));
    float xl = (0.5 + ou) * a_u, xr = (0.5 - ou) * a_u;
    float yl = (0.5 + ov) * a_v, yr = (0.5 - ov) * a_v;
    float area = quadrant_area(r, xl, yl) + quadrant_area(r, xr, yl) + quadrant_area(r, xl, yr)
               + quadrant_area(r, xr, yr);
    return clamp(1.0 - area / (a_u * a_v), 0.0, 1.0);
}

#if STIPPLE_TONE
// trilinear lookup of G(f | t_u, t_v) in the tone table (DATA at STIPPLE_OFF)
void split_(float x, int n, out int i, out float f) {
    float y = clamp(x, 0.0, 1.0) * float(n);
    i = int(clamp(floor(y), 0.0, float(n - 1)));
    f = y - float(i);
}

float stipple_cdf(int a, int b, int i) {
    return DATA[STIPPLE_OFF + (a * STIPPLE_NT + b) * STIPPLE_NY + i];
}

float stipple_tone(float f, float tu, float tv) {
    int a, b, i;
    float fa, fb, fi;
    split_(tu, STIPPLE_NT - 1, a, fa);
    split_(tv, STIPPLE_NT - 1, b, fb);
    split_(f, STIPPLE_NY - 1, i, fi);
    float out_ = 0.0;
    for (int da = 0; da <= 1; ++da) {
        float wa = da == 0 ? 1.0 - fa : fa;
        for (int db = 0; db <= 1; ++db) {
            float wb = db == 0 ? 1.0 - fb : fb;
            float g = stipple_cdf(a + da, b + db, i) * (1.0 - fi) + stipple_cdf(a + da, b + db, i + 1) * fi;
            out_ += wa * wb * g;
        }
    }
    return out_;
}
#endif

// the blended (and tone-corrected) stipple threshold at uv with per-axis scales s_u, s_v
float stipple_threshold(rvec2 uv, float s_u, float s_v) {
    int ku = floor_int(s_u), kv = floor_int(s_v);
    float tu = s_u - floor(s_u), tv = s_v - floor(s_v);
    float a_u = exp2(tu), a_v = exp2(tv);
    float f = 0.0;
    for (int bu = 0; bu <= 1; ++bu) {
        float wu = bu == 1 ? tu : 1.0 - tu;
        for (int bv = 0; bv <= 1; ++bv) {
            float wv = bv == 1 ? tv : 1.0 - tv;
            f += wu * wv * round_dot(uv.x, uv.y, ku + bu, kv + bv, a_u / float(1 + bu),
                                     a_v / float(1 + bv));
        }
    }
#if STIPPLE_TONE
    f = stipple_tone(f, tu, tv);
#endif
    return clamp(f, 0.0, 1.0);
}
