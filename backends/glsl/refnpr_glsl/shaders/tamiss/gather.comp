// TAMISS fragment gathering (Szecsi et al. sec. 3.1, fig. 6), one invocation per G-buffer sample.
// mode 0: counts[i] = fragments of sample i; mode 1: write them at offsets[i] (refnpr's order:
// layer, birth level, row, cell). Reproduces refnpr/styles/tamiss/gather.py field_inputs and
// _kernels.py _smooth_duv / sample_inputs / _enumerate / field_gather in double precision.
layout(local_size_x = 64) in;

struct Frag { uint64_t id; float t; float x; float y; uint meta; };

layout(std430, binding = 0) buffer Counts { uint counts[]; };
layout(std430, binding = 1) readonly buffer Offsets { uint offsets[]; };
layout(std430, binding = 2) writeonly buffer Frags { Frag frags[]; };
layout(std430, binding = 3) readonly buffer Faces { int faces[]; };
layout(std430, binding = 4) readonly buffer Frames { double frames[]; };   // V x 6
layout(std430, binding = 5) readonly buffer Charts { float charts[]; };    // V x 8
layout(std430, binding = 6) readonly buffer Objects { double objs[]; };    // objects x 8
layout(std430, binding = 7) readonly buffer Layers { double layers[]; };   // layers x 4
layout(std430, binding = 8) readonly buffer Lights { double lights[]; };   // lights x 8
layout(std430, binding = 9) readonly buffer Params { double P[]; };

uniform sampler2D t_uv;
uniform sampler2D t_duv_dx;
uniform sampler2D t_duv_dy;
uniform isampler2D t_tri_id;
uniform isampler2D t_mesh_id;
uniform sampler2D t_normal;
uniform sampler2D t_position;
uniform sampler2D t_bary;
uniform sampler2D t_dpos_dx;
uniform sampler2D t_dpos_dy;

uniform int mode;
uniform ivec2 grid;        // (nW, nH)
uniform int n_axis;
uniform int n_layers;
uniform int n_lights;
uniform int max_level;
uniform int use_smooth;
uniform int orient;
uniform int use_constant_tone;
uniform int salt_tone;
uniform int salt_len;

// P: 0 density, 1 period, 2 lam, 3 len_jit, 4 hw_px, 5 constant_tone, 6-8 eye, 9-11 ambient

dvec3 fetch3(sampler2D s, ivec2 p) { return dvec3(texelFetch(s, p, 0).xyz); }

dvec3 frame(int v, int c) {
    return dvec3(frames[6 * v + 3 * c], frames[6 * v + 3 * c + 1], frames[6 * v + 3 * c + 2]);
}

double darkness_at(ivec2 p, int obj) {
    if (use_constant_tone != 0) return P[5];
    dvec3 n = fetch3(t_normal, p);
    double nl = length(n);
    dvec3 nn = nl > 0.0LF ? n / nl : dvec3(0.0LF);
    dvec3 m_a = dvec3(objs[8 * obj], objs[8 * obj + 1], objs[8 * obj + 2]);
    dvec3 m_d = dvec3(objs[8 * obj + 3], objs[8 * obj + 4], objs[8 * obj + 5]);
    dvec3 rgb = m_a * dvec3(P[9], P[10], P[11]);
    for (int k = 0; k < n_lights; k++) {
        dvec3 l = dvec3(lights[8 * k + 1], lights[8 * k + 2], lights[8 * k + 3]);
        if (lights[8 * k] > 0.5LF) {  // point light: towards the light from the sample
            l = l - fetch3(t_position, p);
        }
        double ll = length(l);
        l = ll > 0.0LF ? l / ll : dvec3(0.0LF);
        double fd = min(max(dot(nn, l), 0.0LF), 1.0LF);
        rgb = rgb + m_d * fd * dvec3(lights[8 * k + 4], lights[8 * k + 5], lights[8 * k + 6]);
    }
    double lum = rgb.r * 0.2126LF + rgb.g * 0.7152LF + rgb.b * 0.0722LF;
    return 1.0LF - clamp(lum, 0.0LF, 1.0LF);
}

void main() {
    uint i = gl_GlobalInvocationID.x;
    if (i >= uint(grid.x * grid.y)) return;
    ivec2 p = ivec2(int(i) % grid.x, int(i) / grid.x);
    int tri = texelFetch(t_tri_id, p, 0).r;
    if (tri < 0) {
        if (mode == 0) counts[i] = 0u;
        return;
    }
    int obj = max(texelFetch(t_mesh_id, p, 0).r, 0);
    dvec2 uv = dvec2(texelFetch(t_uv, p, 0).xy);
    dvec2 dx = dvec2(texelFetch(t_duv_dx, p, 0).xy);
    dvec2 dy = dvec2(texelFetch(t_duv_dy, p, 0).xy);
    dvec2 sc = dvec2(objs[8 * obj + 6], objs[8 * obj + 7]);
    int v0 = faces[3 * tri];
    int chart = int(charts[8 * v0 + 7]);
    if (use_smooth != 0) {
        dvec3 bary = fetch3(t_bary, p);
        dvec3 gu = dvec3(0.0LF), gv = dvec3(0.0LF);
        for (int c = 0; c < 3; c++) {
            int v = faces[3 * tri + c];
            double b = bary[c];
            gu += b * frame(v, 0);
            gv += b * frame(v, 1);
        }
        double a00 = dot(gu, gu), a01 = dot(gu, gv), a11 = dot(gv, gv);
        double det = a00 * a11 - a01 * a01;
        if (det > 1e-12LF * (a00 * a11) && det > 0.0LF) {
            dvec3 d = fetch3(t_position, p) - dvec3(P[6], P[7], P[8]);
            dvec3 nrm = fetch3(t_normal, p);
            double nd = dot(nrm, d);
            double dlen = length(d), nlen = length(nrm);
            if (abs(nd) >= 0.05LF * dlen * nlen && dlen > 0.0LF) {
                for (int axis = 0; axis < 2; axis++) {
                    dvec3 dp = axis == 0 ? fetch3(t_dpos_dx, p) : fetch3(t_dpos_dy, p);
                    double lam = dot(nrm, dp) / nd;
                    dp -= lam * d;
                    double r0 = dot(gu, dp), r1 = dot(gv, dp);
                    dvec2 duv = dvec2((a11 * r0 - a01 * r1) / det, (a00 * r1 - a01 * r0) / det);
                    if (axis == 0) dx = duv; else dy = duv;
                }
            }
        }
    }
    if (orient != 0) {
        dmat2 m = dmat2(charts[8 * v0], charts[8 * v0 + 2], charts[8 * v0 + 1], charts[8 * v0 + 3]);
        dvec2 off = dvec2(charts[8 * v0 + 4], charts[8 * v0 + 5]);
        uv = m * uv + off;
        dx = m * dx;
        dy = m * dy;
        sc = dmat2(abs(m[0]), abs(m[1])) * sc;
        chart = int(charts[8 * v0 + 6]);
    }
    double dark = darkness_at(p, obj);
    double u = uv.x * sc.x, v = uv.y * sc.y;
    double ux = dx.x * sc.x, vx = dx.y * sc.y, uy = dy.x * sc.x, vy = dy.y * sc.y;
    double density = P[0], period = P[1], lam = P[2], len_jit = P[3], hw_px = P[4];
    float fx = float((double(p.x) + 0.5LF) / double(n_axis));
    float fy = float((double(p.y) + 0.5LF) / double(n_axis));
    uint base = mode == 1 ? offsets[i] : 0u;
    uint k = 0u;
    for (int lay = 0; lay < n_layers; lay++) {
        double ca = layers[4 * lay], sa = layers[4 * lay + 1], tone_lo = layers[4 * lay + 2];
        double rho = (dark - tone_lo) / (1.0LF - tone_lo) * density;
        rho = min(max(rho, 0.0LF), 1.0LF);
        if (rho <= 0.0LF) continue;
        double pp = ca * u + sa * v;
        double q = -sa * u + ca * v;
        double gp = dhypot(ca * ux + sa * vx, ca * uy + sa * vy);
        double gq = dhypot(-sa * ux + ca * vx, -sa * uy + ca * vy);
        if (!(gq > 0.0LF && gp > 0.0LF && gq < 1e30LF && gp < 1e30LF)) continue;
        double d_p = 1.0LF / gp;
        double d_q = 1.0LF / gq;
        double s = dlog2(d_q / (7.0LF * period));
        double big_l = floor(s);
        double f = s - big_l;
        double thin = 1.0LF;
        if (big_l < 0.0LF) { thin = dexp2(s); big_l = 0.0LF; f = 0.0LF; }
        if (big_l >= double(max_level)) { big_l = double(max_level); f = 0.0LF; }
        int bl = int(big_l);
        int top = f > 0.0LF ? bl + 1 : bl;
        double alpha = dexp2(f) - 1.0LF;
        for (int lev = 0; lev <= top; lev++) {
            double gain = lev <= bl ? thin : alpha;
            if (gain * rho <= 0.0LF) continue;
            double scale = double(1 << lev);
            double rows = 7.0LF * scale;
            double hw_q = hw_px / d_q;
            int ry0 = int(floor((q - hw_q) * rows));
            int ry1 = int(floor((q + hw_q) * rows)) + 1;
            for (int ry = ry0; ry <= ry1; ry++) {
                double q_row = double(ry) / rows;
                double dist = abs(q - q_row) * d_q;
                if (dist > hw_px) continue;
                int gy = int(floor(double(ry) / 7.0LF));
                int r = ry - 7 * gy;
                int kx = KX[r];
                double half_cells = 0.5LF * lam * (1.0LF + len_jit) + 0.0LF / d_p * scale;
                double ps = pp * scale - double(kx) / 7.0LF;
                int gx0 = int(floor(ps - half_cells));
                int gx1 = int(floor(ps + half_cells)) + 1;
                for (int gx = gx0; gx <= gx1; gx++) {
                    if (lev > 0 && (gx & 1) == (kx & 1) && (gy & 1) == (r & 1)) continue;
                    uint64_t sid = pack_id(chart, lay, lev, gx, gy, r);
                    double h = hash01(sid, salt_len);
                    double length_ = lam * (1.0LF + len_jit * (2.0LF * h - 1.0LF)) / scale;
                    double p_start = (double(gx) + double(kx) / 7.0LF) / scale - 0.5LF * length_;
                    double t = (pp - p_start) / length_;
                    double beyond = max(-t, t - 1.0LF) * length_ * d_p;
                    if (beyond > 0.0LF) continue;
                    double tau = hash01(sid, salt_tone);
                    if (!(tau < rho * gain && t >= 0.0LF && t <= 1.0LF)) continue;
                    if (mode == 1) {
                        Frag fr;
                        fr.id = sid;
                        fr.t = float(t);
                        fr.x = fx;
                        fr.y = fy;
                        fr.meta = uint(lay) | (uint(lev) << 4);
                        frags[base + k] = fr;
                    }
                    k++;
                }
            }
        }
    }
    if (mode == 0) counts[i] = k;
}
