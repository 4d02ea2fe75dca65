// threshold style: analytic box filter of the thresholded lines over the footprint (sec. 4).
// refnpr: refnpr/formulas/threshold/filtering.py (line_coverage).

real h_run(real x, real ln) {  // H(x) - ln x (periodic running integral of the pulses)
    real f = frac_r(x);
    return min(f, ln) - ln * f;
}

real d2_run(real x, real ln) {  // H2(x) - ln x^2 / 2 - mu x
    real f = frac_r(x);
    real m = f <= ln ? f * f / 2.0 : ln * f - ln * ln / 2.0;
    return m - ln * f * f / 2.0 - ln * (1.0 - ln) / 2.0 * f;
}

// integral over z in [0, width] of z * 1[Frac(start + sign z) < ln], width < 1
real ramp_int(real start, real width, real ln, real sgn) {
    real total = 0.0;
    real base = floor(start);
    for (int dn = -1; dn <= 1; ++dn) {
        real n = base + real(dn) * sgn;
        real lo, hi;
        if (sgn > 0.0) {
            lo = n - start;
            hi = n + ln - start;
        } else {
            lo = start - n - ln;
            hi = start - n;
        }
        lo = clamp(lo, 0.0, width);
        hi = clamp(hi, 0.0, width);
        total += (hi - lo) * (hi + lo) / 2.0;
    }
    return total;
}

// E[1[Frac(u + a X + b Y) < ln]], X, Y ~ U(-1/2, 1/2), a >= b >= 0
real pulse_box(real u, real a, real b, real ln) {
    u = frac_r(u);
    bool wide = b >= 1.0;
    real safe_a = a > 0.0 ? a : 1.0;
    real safe_b = b > 0.0 ? b : 1.0;
    if (wide) {
        real ha = a / 2.0, hb = b / 2.0;
        real dd = d2_run(u + ha + hb, ln) - d2_run(u + ha - hb, ln) - d2_run(u - ha + hb, ln)
                  + d2_run(u - ha - hb, ln);
        return ln + dd / (safe_a * safe_b);
    }
    real half_ = (a - b) / 2.0;
    real plateau = (ln * (a - b) + h_run(u + half_, ln) - h_run(u - half_, ln)) / safe_a;
    real left = ramp_int(u - (a + b) / 2.0, b, ln, 1.0);
    real right = ramp_int(u + (a + b) / 2.0, b, ln, -1.0);
    real ramps = b > 0.0 ? (left + right) / (safe_a * safe_b) : 0.0;
    return plateau + ramps;
}

// fraction of the footprint where line_threshold(v, s) <= x (white)
real line_coverage(real v, float s, real x, real gx, real gy) {
    int k = floor_int(s);
    real t = real(s) - floor(real(s));
    real vr = scaled_frac_r(v, k);
    real a = max(abs(gx), abs(gy)) * pow2_r(k);
    real b = min(abs(gx), abs(gy)) * pow2_r(k);
    bool point = a < TINY_A;
    bool huge = !(a < 1e15);
    real a_ok = (point || huge) ? 1.0 : a;
    real b_ok = (point || huge || b < TINY_B) ? 0.0 : b;
    real cover = 0.0, tone = 0.0;
    real c[4], ln[4];
    int np_;
#if UNIFORM
    real aa = (1.0 - t) / (2.0 * (1.0 + t));
    real bb = 1.0 - aa;
    c[0] = 0.0; ln[0] = clamp(x, 0.0, aa);
    c[1] = aa;    ln[1] = clamp((x - aa) / 2.0, 0.0, 0.5 - aa);
    c[2] = 0.5; ln[2] = clamp((x + bb) / 2.0 - 0.5, 0.0, bb - 0.5);
    c[3] = bb;    ln[3] = clamp(x - bb, 0.0, 1.0 - bb);
    np_ = 4;
#else
    c[0] = 0.0; ln[0] = clamp(x / (1.0 + t), 0.0, 0.5);
    c[1] = 0.5; ln[1] = clamp((x + t) / (1.0 + t) - 0.5, 0.0, 0.5);
    np_ = 2;
#endif
    for (int j = 0; j < np_; ++j) {
        cover += pulse_box(vr - c[j], a_ok, b_ok, ln[j]);
        tone += ln[j];
    }
    real smp = x >= multiscale_kernel(vr, t) ? 1.0 : 0.0;
    cover = point ? smp : (huge ? tone : cover);
    cover = x >= 1.0 ? 1.0 : (x < 0.0 ? 0.0 : cover);
    return clamp(cover, 0.0, 1.0);
}
