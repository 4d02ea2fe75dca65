// Per-stroke fit, drop rule, drawn extent and image-space extrusion (TAMISS sec. 3.2, 4), one
// invocation per aggregated stroke (in id order). Float32 fit as refnpr's default dtype
// (refnpr/formulas/tamiss/fit.py _solve: Legendre basis, Jacobi scaling, CG); visible segments
// by bisection in double (formulas/tamiss/segments.py); centreline, run-on and extrusion in
// double from the float32 cubic (styles/tamiss/strokes.py). Writes pieces 2 r and 2 r + 1.
layout(local_size_x = 64) in;

struct Piece { uint64_t id; int valid; int level; ivec4 bbox; vec4 color; };

layout(std430, binding = 12) readonly buffer Ids { uint64_t ids[]; };
layout(std430, binding = 15) readonly buffer Counter { uint counter[]; };
layout(std430, binding = 17) readonly buffer Sorted { uint sorted_[]; };
layout(std430, binding = 18) writeonly buffer Pieces { Piece pieces[]; };
layout(std430, binding = 19) writeonly buffer Verts { double verts[]; };  // piece x K x 5
layout(std430, binding = 20) readonly buffer FitParams { double FP[]; };

uniform sampler2D t_s0;
uniform sampler2D t_s1;
uniform sampler2D t_bx;
uniform sampler2D t_by;
uniform sampler2D t_mn;
uniform sampler2D t_mx;

uniform int tw;
uniform int K;
uniform int iterations;
uniform int min_fragments;
uniform int extent;     // 0 visible, 1 range, 2 stroke, 3 overdraw
uniform int view;       // 0 color, 1 ids, 2 fits, 3 strokes, 4 levels
uniform int n_axis;
uniform ivec2 grid;

// FP: 0 prior_weight, 1 min_t_span, 2 max_stretch (< 0: off), 3 px_per_fragment, 4 threshold,
// 5 overdraw, 6 width, 7 taper, 8 wobble, 9 wobble_frequency, 10 end_jitter, 11 width_jitter,
// 12 rtol, 13-15 ink colour, 16.. level colours (7 x 3)

const float LG[16] = float[16](1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, -0.5, 0.0, 1.5, 0.0,
                               0.0, -1.5, 0.0, 2.5);  // row-major LEGENDRE

float cub(float c[4], float s) { return ((c[3] * s + c[2]) * s + c[1]) * s + c[0]; }

// refnpr cg_kernel on a 4 x 4 float32 system
void cg(float A[16], float b[4], int iters, float rtol, out float x[4]) {
    float r[4], p[4], Ap[4];
    for (int i = 0; i < 4; i++) { x[i] = 0.0; r[i] = b[i]; p[i] = b[i]; }
    precise float rr = 0.0;
    for (int i = 0; i < 4; i++) rr += r[i] * r[i];
    precise float stop = rtol * rtol * rr;
    for (int it = 0; it < iters; it++) {
        precise float pAp = 0.0;
        for (int i = 0; i < 4; i++) {
            precise float acc = 0.0;
            for (int j = 0; j < 4; j++) acc += A[4 * i + j] * p[j];
            Ap[i] = acc;
        }
        for (int i = 0; i < 4; i++) pAp += p[i] * Ap[i];
        bool ok = rr > stop && rr > 0.0 && pAp > 0.0;
        precise float alpha = ok ? fdiv(rr, pAp) : 0.0;
        for (int i = 0; i < 4; i++) { x[i] = x[i] + alpha * p[i]; r[i] = r[i] - alpha * Ap[i]; }
        precise float rr_new = 0.0;
        for (int i = 0; i < 4; i++) rr_new += r[i] * r[i];
        precise float beta = ok ? fdiv(rr_new, rr) : 0.0;
        if (ok) for (int i = 0; i < 4; i++) p[i] = r[i] + beta * p[i];
        rr = ok ? rr_new : rr;
    }
}

// refnpr fit._solve with basis "legendre"
void solve(float A[16], float b[4], out float c[4]) {
    float LA[16], AL[16], As[16];
    for (int i = 0; i < 4; i++)
        for (int j = 0; j < 4; j++) {
            precise float acc = 0.0;
            for (int k = 0; k < 4; k++) acc += LG[4 * i + k] * A[4 * k + j];
            LA[4 * i + j] = acc;
        }
    for (int i = 0; i < 4; i++)
        for (int j = 0; j < 4; j++) {
            precise float acc = 0.0;
            for (int k = 0; k < 4; k++) acc += LA[4 * i + k] * LG[4 * j + k];
            AL[4 * i + j] = acc;
        }
    float S[16];
    for (int i = 0; i < 4; i++)
        for (int j = 0; j < 4; j++) S[4 * i + j] = (AL[4 * i + j] + AL[4 * j + i]) * 0.5;
    float d[4], bL[4], y[4];
    for (int i = 0; i < 4; i++) {
        d[i] = S[5 * i] > 0.0 ? fdiv(1.0, fsqrt(S[5 * i])) : 0.0;
        precise float acc = 0.0;
        for (int j = 0; j < 4; j++) acc += LG[4 * i + j] * b[j];
        bL[i] = acc;
    }
    for (int i = 0; i < 4; i++)
        for (int j = 0; j < 4; j++) As[4 * i + j] = S[4 * i + j] * d[i] * d[j];
    float bd[4];
    for (int i = 0; i < 4; i++) bd[i] = bL[i] * d[i];
    cg(As, bd, iterations, float(FP[12]), y);
    for (int i = 0; i < 4; i++) {
        precise float acc = 0.0;
        for (int j = 0; j < 4; j++) acc += LG[4 * j + i] * (y[j] * d[j]);
        c[i] = acc;
    }
}

float cx[4], cy[4], cv[4];
float f_lo, f_hi;

float param_(double t) {  // StrokeFit.param in float32
    float tt = float(t);
    float half_ = (f_hi - f_lo) * 0.5;
    return half_ > 0.0 ? fdiv(tt - (f_lo + half_), half_) : 0.0;
}

dvec2 eval_(double t) {
    float s = param_(t);
    return dvec2(double(cub(cx, s)), double(cub(cy, s)));
}

dvec2 deriv_(double t) {
    float s = param_(t);
    float w = f_hi - f_lo;
    float ds = w > 0.0 ? fdiv(2.0, w) : 0.0;
    float dx[4] = float[4](cx[1], 2.0 * cx[2], 3.0 * cx[3], 0.0);
    float dy[4] = float[4](cy[1], 2.0 * cy[2], 3.0 * cy[3], 0.0);
    return dvec2(double(cub(dx, s) * ds), double(cub(dy, s) * ds));
}

double mean_speed() {
    double lo = double(f_lo), hi = double(f_hi);
    double seg[16];
    dvec2 prev = eval_(lo + (hi - lo) * 0.0LF);
    for (int k = 1; k <= 16; k++) {
        double u = k == 16 ? 1.0LF : double(k) * (1.0LF / 16.0LF);
        dvec2 cur = eval_(lo + (hi - lo) * u);
        seg[k - 1] = dhypot(cur.x - prev.x, cur.y - prev.y);
        prev = cur;
    }
    double r[8];  // numpy pairwise sum of 16 values
    for (int j = 0; j < 8; j++) r[j] = seg[j] + seg[j + 8];
    double arc = ((r[0] + r[1]) + (r[2] + r[3])) + ((r[4] + r[5]) + (r[6] + r[7]));
    double span = hi - lo;
    return span > 0.0LF ? arc / span : 0.0LF;
}

double dcub(double c[4], double s) { return ((c[3] * s + c[2]) * s + c[1]) * s + c[0]; }

double nan_d() { return packDouble2x32(uvec2(0u, 0x7FF80000u)); }

// refnpr segments.visible_segments on [-1, 1]; returns count, fills seg (start, end) x 2
int visible(double thr, out double seg[4]) {
    double c[4];
    for (int i = 0; i < 4; i++) c[i] = double(cv[i]);
    c[0] -= thr;
    double sc = max(max(abs(c[0]), abs(c[1])), max(abs(c[2]), abs(c[3])));
    if (sc > 0.0LF) for (int i = 0; i < 4; i++) c[i] = c[i] / sc;
    double lo = -1.0LF, hi = 1.0LF;
    double A = 3.0LF * c[3], B = 2.0LF * c[2], C = c[1];
    double disc = B * B - 4.0LF * A * C;
    double sq = sqrt(max(disc, 0.0LF));
    double q = -0.5LF * (B + (B >= 0.0LF ? sq : -sq));
    bool r1ok = true, r2ok = true;
    double r1 = 0.0LF, r2 = 0.0LF;
    if (A != 0.0LF) r1 = q / A; else if (B != 0.0LF) r1 = -C / B; else r1ok = false;
    if (A != 0.0LF && q != 0.0LF) r2 = C / q; else r2ok = false;
    bool real_ = disc >= 0.0LF;
    if (!(real_ || A == 0.0LF)) r1ok = false;
    if (!real_) r2ok = false;
    // division by zero gives +-inf in numpy: outside the range, as here
    double k1 = (r1ok && r1 > lo && r1 < hi) ? r1 : hi;
    double k2 = (r2ok && r2 > lo && r2 < hi) ? r2 : hi;
    double knots[4] = double[4](lo, min(k1, k2), max(k1, k2), hi);
    double roots[3];
    for (int j = 0; j < 3; j++) {
        double a = knots[j], b = knots[j + 1];
        double fa = dcub(c, a), fb = dcub(c, b);
        bool cross = (fa < 0.0LF) != (fb < 0.0LF);
        double left = a, right = b, fl = fa;
        for (int it = 0; it < 64; it++) {
            double mid = 0.5LF * (left + right);
            double fm = dcub(c, mid);
            bool same = (fm < 0.0LF) == (fl < 0.0LF);
            if (same) { left = mid; fl = fm; } else { right = mid; }
        }
        roots[j] = cross ? 0.5LF * (left + right) : hi;
    }
    // sort 3 roots
    for (int a = 0; a < 2; a++)
        for (int b = 0; b < 2 - a; b++)
            if (roots[b] > roots[b + 1]) { double tmp = roots[b]; roots[b] = roots[b + 1]; roots[b + 1] = tmp; }
    double bps[5] = double[5](lo, roots[0], roots[1], roots[2], hi);
    for (int j = 0; j < 4; j++) seg[j] = nan_d();
    int count = 0;
    bool open_ = false;
    for (int j = 0; j < 4; j++) {
        double st = bps[j], en = bps[j + 1];
        bool pos_ = dcub(c, 0.5LF * (st + en)) >= 0.0LF;
        bool len = en > st;
        bool pos = pos_ && len;
        bool neg = !pos_ && len;
        bool nw = pos && !open_ && count < 2;
        int idx = min(count, 1);
        if (nw) seg[2 * idx] = st;
        if (nw) count++;
        int last = max(count - 1, 0);
        if (pos) seg[2 * last + 1] = en;
        open_ = (open_ || pos) && !neg;
    }
    return count;
}

void main() {
    uint r = gl_GlobalInvocationID.x;
    uint n_strokes = counter[2];
    if (r >= n_strokes) return;
    uint slot = sorted_[r];
    uint64_t sid = ids[slot];
    ivec2 tp = ivec2(int(slot) % tw, int(slot) / tw);
    vec4 s0 = texelFetch(t_s0, tp, 0), s1 = texelFetch(t_s1, tp, 0);
    vec4 bx = texelFetch(t_bx, tp, 0), by = texelFetch(t_by, tp, 0);
    vec4 mn = texelFetch(t_mn, tp, 0), mx = texelFetch(t_mx, tp, 0);
    float Pw[7] = float[7](s0.x, s0.y, s0.z, s0.w, s1.x, s1.y, s1.z);
    float A[16];
    for (int i = 0; i < 4; i++)
        for (int j = 0; j < 4; j++) A[4 * i + j] = Pw[i + j];
    f_lo = mn.x;
    f_hi = mx.x;
    float ox = (mn.y + mx.y) * 0.5, oy = (mn.z + mx.z) * 0.5;
    float b_x[4] = float[4](bx.x, bx.y, bx.z, bx.w);
    float b_y[4] = float[4](by.x, by.y, by.z, by.w);
    solve(A, b_x, cx);
    solve(A, b_y, cy);
    cx[0] += ox;
    cy[0] += oy;
    float cnt = s0.x;
    float nprior = cnt * float(FP[0]);
    float AD[16];
    for (int i = 0; i < 4; i++)
        for (int j = 0; j < 4; j++) AD[4 * i + j] = A[4 * i + j] + nprior * (((i + j) & 1) == 0 ? fdiv(1.0, float(i + j + 1)) : 0.0);
    float b_v[4] = float[4](s0.x, s0.y, s0.z, s0.w);
    solve(AD, b_v, cv);

    double lo = double(f_lo), hi = double(f_hi);
    double span = hi - lo;
    bool finite_ = true;
    for (int i = 0; i < 4; i++) finite_ = finite_ && !isinf(cx[i]) && !isnan(cx[i]) && !isinf(cy[i]) && !isnan(cy[i]);
    bool keep = cnt >= float(max(min_fragments, 4)) && span >= FP[1] && finite_;
    double speed = mean_speed();
    if (FP[2] >= 0.0LF && keep) {
        double arc = speed * span;
        keep = keep && arc <= FP[2] * (double(cnt) * FP[3]) + 4.0LF;
    }
    // drawn intervals (t)
    double seg[4];
    for (int j = 0; j < 4; j++) seg[j] = nan_d();
    int nseg = 0;
    if (keep) {
        int ext = view == 2 ? 1 : extent;
        if (ext == 1) { seg[0] = lo; seg[1] = hi; nseg = 1; }
        else if (ext == 2) { seg[0] = 0.0LF; seg[1] = 1.0LF; nseg = 1; }
        else {
            double sv[4];
            nseg = visible(FP[4], sv);
            float half_ = fdiv(f_hi - f_lo, 2.0);
            for (int j = 0; j < 4; j++) {
                float v = float(sv[j]);
                seg[j] = isnan(sv[j]) ? nan_d() : double((f_lo + half_) + v * half_);
            }
            if (ext == 3 && nseg >= 1) {
                double dt = speed > 0.0LF ? FP[5] / speed : 0.0LF;
                int last = nseg - 1;
                seg[0] = max(0.0LF, seg[0] - dt);
                seg[2 * last + 1] = min(1.0LF, seg[2 * last + 1] + dt);
            }
        }
    }
    bool fits = view == 2;
    double width = fits ? 1.0LF : FP[6];
    double taper = fits ? 0.0LF : FP[7];
    double wobble = fits ? 0.0LF : FP[8];
    double end_jitter = fits ? 0.0LF : FP[10];
    bool has0 = !isnan(seg[0]), has1 = !isnan(seg[2]);
    int n_has = int(has0) + int(has1);
    if (end_jitter > 0.0LF && n_has > 0) {
        int last = n_has - 1;
        double first_start = seg[0], last_end = seg[2 * last + 1];
        double sp = last_end - first_start;
        double ja = end_jitter * (2.0LF * hash01(sid, 13) - 1.0LF) * 0.5LF * sp;
        double jb = end_jitter * (2.0LF * hash01(sid, 14) - 1.0LF) * 0.5LF * sp;
        seg[0] = min(first_start - ja, seg[1] - 1e-6LF);
        seg[2 * last + 1] = max(last_end + jb, seg[2 * last] + 1e-6LF);
    }
    double wf = 1.0LF + FP[11] * (2.0LF * hash01(sid, 3) - 1.0LF);
    double w = width * wf;
    double amp = wobble * (0.5LF + hash01(sid, 11));
    double phase = hash01(sid, 12);
    dvec2 p_lo = eval_(lo), p_hi = eval_(hi);
    double chx = p_hi.x - p_lo.x, chy = p_hi.y - p_lo.y;
    int level = id_level(sid);
    vec4 color = vec4(float(FP[13]), float(FP[14]), float(FP[15]), 1.0);
    if (view == 2 || view == 3) {
        double h6 = hash01(sid, 11) * 6.0LF;
        dvec3 kk = mod(dvec3(5.0LF, 3.0LF, 1.0LF) + h6, 6.0LF);
        dvec3 ramp = clamp(min(kk, 4.0LF - kk), 0.0LF, 1.0LF);
        color = vec4(vec3(0.7LF * (1.0LF - 0.9LF * ramp)), 1.0);
    } else if (view == 4) {
        int l = min(level, 6);
        color = vec4(float(FP[16 + 3 * l]), float(FP[17 + 3 * l]), float(FP[18 + 3 * l]), 1.0);
    }
    for (int j = 0; j < 2; j++) {
        uint pc = 2u * r + uint(j);
        bool has = j == 0 ? has0 : has1;
        Piece pe;
        pe.id = sid;
        pe.valid = has ? 1 : 0;
        pe.level = level;
        pe.color = color;
        pe.bbox = ivec4(0, 0, -1, -1);
        if (!has) { pieces[pc] = pe; continue; }
        double t0 = seg[2 * j], t1 = seg[2 * j + 1];
        double mnx = 1e300LF, mny = 1e300LF, mxx = -1e300LF, mxy = -1e300LF;
        bool fin = true;
        for (int k = 0; k < K; k++) {
            double u = k == K - 1 ? 1.0LF : double(k) * (1.0LF / double(K - 1));
            double t = t0 + (t1 - t0) * u;
            double tc = clamp(t, lo, hi);
            dvec2 pt = eval_(tc);
            dvec2 dd = deriv_(tc);
            double nd = dhypot(dd.x, dd.y), nc = dhypot(chx, chy);
            double tx, ty;
            if (nd > 1e-12LF) { tx = dd.x / nd; ty = dd.y / nd; }
            else if (nc > 1e-12LF) { tx = chx / nc; ty = chy / nc; }
            else { tx = 1.0LF; ty = 0.0LF; }
            double d_out = (t < lo ? t - lo : (t > hi ? t - hi : 0.0LF)) * speed;
            double x = pt.x + d_out * tx, y = pt.y + d_out * ty;
            double nx = -ty, ny = tx;
            double prof = taper > 0.0LF ? min(1.0LF, min(u, 1.0LF - u) / taper) : 1.0LF;
            double h = 0.5LF * w * prof;
            if (wobble > 0.0LF) {
                double off = amp * dsin(2.0LF * PI_D * (FP[9] * t + phase));
                x = x + off * nx;
                y = y + off * ny;
            }
            double n = double(n_axis);
            double lx = (x + h * nx) * n, ly = (y + h * ny) * n;
            double rx = (x - h * nx) * n, ry = (y - h * ny) * n;
            uint o = (pc * uint(K) + uint(k)) * 5u;
            verts[o] = lx; verts[o + 1u] = ly; verts[o + 2u] = rx; verts[o + 3u] = ry;
            verts[o + 4u] = t;
            fin = fin && !isnan(lx) && !isnan(ly) && !isnan(rx) && !isnan(ry) && !isinf(lx)
                  && !isinf(ly) && !isinf(rx) && !isinf(ry);
            mnx = min(mnx, min(lx, rx)); mxx = max(mxx, max(lx, rx));
            mny = min(mny, min(ly, ry)); mxy = max(mxy, max(ly, ry));
        }
        if (fin) {
            int x0 = int(clamp(floor(mnx), -1.0LF, double(grid.x)));
            int y0 = int(clamp(floor(mny), -1.0LF, double(grid.y)));
            int x1 = int(clamp(floor(mxx), -1.0LF, double(grid.x)));
            int y1 = int(clamp(floor(mxy), -1.0LF, double(grid.y)));
            pe.bbox = ivec4(max(x0, 0), max(y0, 0), min(x1, grid.x - 1), min(y1, grid.y - 1));
        }
        pieces[pc] = pe;
    }
}
