// threshold style: procedural multi-scale lines (Veryovka sec. 3.2). refnpr:
// refnpr/formulas/threshold/lines.py (line_threshold), compose.py (combine_thresholds,
// layer_whites), refnpr/styles/threshold/noise.py (value_noise).

// F(Frac(v 2^floor(s)), Frac(s)) (eqs. 6-8), then Frac(F + noise)
real line_threshold(real v, float s, real noise) {
    int k = floor_int(s);
    real t = real(s) - floor(real(s));
    real f = multiscale_kernel(scaled_frac_r(v, k), t);
#if HAS_NOISE
    f = frac_r(f + noise);
#endif
    return f;
}

// ---- value noise: splitmix64 lattice hash, quintic fade, two octaves
real hash01(int64_t i, int64_t j, uint seed) {  // seed: Python's seed & 0xFFFFFFFF
    uint64_t h = uint64_t(i) * M1;
    h ^= uint64_t(j) * M2 + uint64_t(seed) * M3;
    return unit64(mix64(h));
}

real fade5(real x) { return x * x * x * (x * (6.0 * x - 15.0) + 10.0); }

real octave(rvec2 p, uint seed) {
    rvec2 fl = floor(p);
    int64_t i0 = int64_t(fl.x);
    int64_t j0 = int64_t(fl.y);
    rvec2 f = p - fl;
    real wu = fade5(f.x), wv = fade5(f.y);
    real h00 = hash01(i0, j0, seed);
    real h10 = hash01(i0 + 1l, j0, seed);
    real h01 = hash01(i0, j0 + 1l, seed);
    real h11 = hash01(i0 + 1l, j0 + 1l, seed);
    real top = h00 + wu * (h10 - h00);
    real bottom = h01 + wu * (h11 - h01);
    return top + wv * (bottom - top);
}

real value_noise(rvec2 p, uint seed) {
    real n = octave(p, seed) + 0.5 * octave(2.0 * p + 17.0, seed + 1u);
    return (n / 1.5) * 2.0 - 1.0;
}

#if N_LAYERS > 1
// ---- composition of layers (water-filling schedule: LAM[N_BP], LEV[N_BP * N_LAYERS])
float lev_at(int b, int i) { return LEV[b * N_LAYERS + i]; }

// lambda*_i(F): largest total darkness at which a sample with layer value F is white
float darkness_of_layer(float f, int i) {
    float q = f > 0.0 ? -log(min(f, 1.0)) : 1e30;
    int k = 0;  // searchsorted(lev_i, q, side="right")
    for (int b = 0; b < N_BP; ++b) k += (lev_at(b, i) <= q) ? 1 : 0;
    int last = N_BP - 1;
    int hi = last >= 1 ? clamp(k, 1, max(last, 1)) : 0;
    int lo = max(hi - 1, 0);
    float dlev = lev_at(hi, i) - lev_at(lo, i);
    float safe = dlev > 0.0 ? dlev : 1.0;
    float inner = LAM[lo] + (q - lev_at(lo, i)) * (LAM[hi] - LAM[lo]) / safe;
    float tail = LAM[last] + (q - lev_at(last, i)) * float(N_LAYERS);
    return k > last ? tail : inner;
}

// white fraction w_i(x) of layer i at intensity x (prod_i w_i = x)
float layer_white(float x, int i) {
    float xc = clamp(x, 0.0, 1.0);
    if (xc <= 0.0) return 0.0;
    float lam = -log(xc);
    float li;
    if (lam > LAM[N_BP - 1]) {
        li = lev_at(N_BP - 1, i) + (lam - LAM[N_BP - 1]) / float(N_LAYERS);
    } else {  // np.interp(lam, LAM, LEV[:, i])
        li = lev_at(0, i);
        for (int b = 0; b + 1 < N_BP; ++b) {
            if (lam >= LAM[b] && lam <= LAM[b + 1]) {
                float w = (lam - LAM[b]) / (LAM[b + 1] - LAM[b]);
                li = lev_at(b, i) + w * (lev_at(b + 1, i) - lev_at(b, i));
                break;
            }
        }
    }
    return exp(-li);
}
#endif
