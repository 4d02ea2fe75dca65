#version 450 core
#extension GL_ARB_gpu_shader_int64 : require
// TAM / RPTAM (the texture-space baseline of TAMISS, Szecsi et al.) in the fragment shader:
// per sample, enumerate the strokes of the nested RPTAM seed field that cover it, draw them
// anti-aliased across and at their ends with a per-sample density decision (clip or fade), and
// composite the ink over the paper. Mirrors refnpr/styles/tamiss/_kernels.py (tam_pass with
// the clip / fade opacity, _enumerate, _smooth_duv), gather.py (field_inputs) and
// refnpr/formulas/tamiss/field.py (darkness, tam_opacity).
// Configuration by #defines after the #version line (styles/tam.py):
//   N_LAYERS, MAX_LEVEL, CAP, FADE_MODE (1 fade, 0 clip), SMOOTH (smooth derivatives),
//   ORIENT (chart orientation), CONSTANT_TONE, HAS_PAPER, N_LIGHTS, N_OBJECTS,
//   M1 M2 M3 SALT_TONE SALT_LENGTH SALT_WIDTH (uint64 literals)
//DEFINES

layout(location = 0) out vec4 frag;

uniform isampler2D g_tri_id;
uniform isampler2D g_mesh_id;
uniform sampler2D g_uv;
uniform sampler2D g_duv_dx;
uniform sampler2D g_duv_dy;
uniform sampler2D g_normal;
uniform sampler2D g_position;
uniform sampler2D g_bary;
uniform sampler2D g_dposition_dx;
uniform sampler2D g_dposition_dy;

// faces: 3 global vertex indices per triangle (tri_id order); verts: 14 floats per vertex:
// frame dP/du (3), dP/dv (3), chart (1), symmetry M row-major (4), offset (2), pad (1)
layout(std430, binding = 0) readonly buffer Faces { int faces[]; };
layout(std430, binding = 1) readonly buffer Verts { float verts[]; };
// objects: 8 floats per object: uv_scale (2), ambient (3), diffuse (3)
layout(std430, binding = 2) readonly buffer Objects { float objects[]; };
// lights: 8 floats per light: kind (0 directional, 1 point), xyz (direction or position),
// colour (3), pad
layout(std430, binding = 3) readonly buffer Lights { float lights[]; };

uniform dvec3 eye;
uniform vec3 ambient;
uniform vec3 luma;
uniform vec3 ink_color;
uniform vec3 paper;
uniform double cos_a[4];
uniform double sin_a[4];
uniform double tone_lo[4];
uniform double density;
uniform double period;
uniform double lam;
uniform double len_jit;
uniform double wid_jit;
uniform double width_px;
uniform double fade;
uniform double constant_tone;

const int KX[7] = int[7](0, 6, 5, 1, 3, 4, 2);
const int64_t CELL_OFF = int64_t(1) << 21;

uint64_t splitmix(uint64_t z) {
    z = z + M1;
    z = (z ^ (z >> 30)) * M2;
    z = (z ^ (z >> 27)) * M3;
    return z ^ (z >> 31);
}

double hash01(int64_t sid, uint64_t salt) {
    uint64_t z = uint64_t(sid) + salt;
    return double(splitmix(z) >> 11) * (1.0LF / 9007199254740992.0LF);
}

int64_t pack_id(int chart, int layer, int level, int64_t gx, int64_t gy, int r) {
    int64_t v = int64_t(chart) * 4 + int64_t(layer);
    v = v * 16 + int64_t(level);
    v = (v << 22) + (gx + CELL_OFF);
    v = (v << 22) + (gy + CELL_OFF);
    return v * 8 + int64_t(r);
}

int64_t floor_div7(int64_t a) {  // Python's a // 7
    return a >= 0 ? a / 7 : -((-a + 6) / 7);
}

double clampd(double x, double lo, double hi) { return min(max(x, lo), hi); }

double hypotd(double a, double b) { return sqrt(a * a + b * b); }

vec3 unit3(vec3 v) {
    float l = length(v);
    return l > 0.0 ? v / l : vec3(0.0);
}

float darkness_at(ivec2 px, int mid) {
#if CONSTANT_TONE
    return float(constant_tone);
#else
    vec3 n = unit3(texelFetch(g_normal, px, 0).xyz);
    int o = 8 * mid;
    vec3 m_a = vec3(objects[o + 2], objects[o + 3], objects[o + 4]);
    vec3 m_d = vec3(objects[o + 5], objects[o + 6], objects[o + 7]);
    vec3 rgb = m_a * ambient;
    for (int i = 0; i < N_LIGHTS; ++i) {
        int b = 8 * i;
        vec3 xyz = vec3(lights[b + 1], lights[b + 2], lights[b + 3]);
        vec3 col = vec3(lights[b + 4], lights[b + 5], lights[b + 6]);
        vec3 l;
        if (lights[b] > 0.5) {
            l = unit3(xyz - texelFetch(g_position, px, 0).xyz);
        } else {
            l = unit3(xyz);
        }
        float f_d = min(max(dot(n, l), 0.0), 1.0);    // Veryovka eq. 1: f_d
        rgb += m_d * f_d * col;
    }
    float lum = dot(rgb, luma);                        // Rec. 709
    return 1.0 - clamp(lum, 0.0, 1.0);
#endif
}

void main() {
    ivec2 px = ivec2(gl_FragCoord.xy);
    int tri = texelFetch(g_tri_id, px, 0).r;
    if (tri < 0) {
        frag = vec4(0.0);
        return;
    }
    int mid = max(texelFetch(g_mesh_id, px, 0).r, 0);
    dvec2 uv = dvec2(texelFetch(g_uv, px, 0).xy);
    dvec2 dx = dvec2(texelFetch(g_duv_dx, px, 0).xy);
    dvec2 dy = dvec2(texelFetch(g_duv_dy, px, 0).xy);
    dvec2 uv_scale = dvec2(objects[8 * mid], objects[8 * mid + 1]);
    int i0 = faces[3 * tri];
    int chart = int(round(verts[14 * i0 + 6]));

#if SMOOTH
    {
        dvec3 b = dvec3(texelFetch(g_bary, px, 0).xyz);
        dvec3 gu = dvec3(0.0);
        dvec3 gv = dvec3(0.0);
        for (int c = 0; c < 3; ++c) {
            int o = 14 * faces[3 * tri + c];
            gu += b[c] * dvec3(verts[o], verts[o + 1], verts[o + 2]);
            gv += b[c] * dvec3(verts[o + 3], verts[o + 4], verts[o + 5]);
        }
        double a00 = dot(gu, gu);
        double a01 = dot(gu, gv);
        double a11 = dot(gv, gv);
        double det = a00 * a11 - a01 * a01;
        dvec3 D = dvec3(texelFetch(g_position, px, 0).xyz) - eye;
        dvec3 n = dvec3(texelFetch(g_normal, px, 0).xyz);
        double nd = dot(n, D);
        double dlen = length(D);
        double nlen = length(n);
        if (det > 1e-12LF * (a00 * a11) && det > 0.0LF && abs(nd) >= 0.05LF * dlen * nlen
            && dlen > 0.0LF) {
            for (int axis = 0; axis < 2; ++axis) {
                dvec3 dp = dvec3(axis == 0 ? texelFetch(g_dposition_dx, px, 0).xyz
                                           : texelFetch(g_dposition_dy, px, 0).xyz);
                double l = dot(n, dp) / nd;
                dp -= l * D;                           // onto the plane of the shading normal
                double r0 = dot(gu, dp);
                double r1 = dot(gv, dp);
                dvec2 duv = dvec2((a11 * r0 - a01 * r1) / det, (a00 * r1 - a01 * r0) / det);
                if (axis == 0) dx = duv; else dy = duv;
            }
        }
    }
#endif
#if ORIENT
    {
        int o = 14 * i0;
        dmat2 M = dmat2(verts[o + 7], verts[o + 9], verts[o + 8], verts[o + 10]);  // columns
        dvec2 off = dvec2(verts[o + 11], verts[o + 12]);
        uv = M * uv + off;                             // u' = M u + offset
        dx = M * dx;
        dy = M * dy;
        uv_scale = dvec2(abs(M[0][0]) * uv_scale.x + abs(M[1][0]) * uv_scale.y,
                         abs(M[0][1]) * uv_scale.x + abs(M[1][1]) * uv_scale.y);
    }
#endif

    double dark = double(darkness_at(px, mid));
    double u = uv.x * uv_scale.x;
    double v = uv.y * uv_scale.y;
    double ux = dx.x * uv_scale.x;
    double vx = dx.y * uv_scale.y;
    double uy = dy.x * uv_scale.x;
    double vy = dy.y * uv_scale.y;
    double ink = 0.0;
    for (int lay = 0; lay < N_LAYERS; ++lay) {
        double ca = cos_a[lay];
        double sa = sin_a[lay];
        double rho = clampd((dark - tone_lo[lay]) / (1.0LF - tone_lo[lay]) * density, 0.0LF, 1.0LF);
        if (rho <= 0.0LF) continue;
        double p = ca * u + sa * v;
        double q = -sa * u + ca * v;
        double gp = hypotd(ca * ux + sa * vx, ca * uy + sa * vy);
        double gq = hypotd(-sa * ux + ca * vx, -sa * uy + ca * vy);
        if (!(gq > 0.0LF && gp > 0.0LF && gq < 1e30LF && gp < 1e30LF)) continue;
        double d_p = 1.0LF / gp;
        double d_q = 1.0LF / gq;
        double s = double(log2(float(d_q / (7.0LF * period))));
        double hw_px = 0.5LF * width_px * (1.0LF + wid_jit) + 0.5LF;
        double end_px = 0.5LF;
        // levels (RPTAM): L = floor(s), the next level fades in with 2^f - 1
        double big_l = floor(s);
        double f = s - big_l;
        double thin = 1.0LF;
        if (big_l < 0.0LF) {
            thin = double(exp2(float(s)));
            big_l = 0.0LF;
            f = 0.0LF;
        }
        if (big_l >= double(MAX_LEVEL)) {
            big_l = double(MAX_LEVEL);
            f = 0.0LF;
        }
        int top = f > 0.0LF ? int(big_l) + 1 : int(big_l);
        double alpha = double(exp2(float(f))) - 1.0LF;
        int n = 0;
        for (int lev = 0; lev <= top; ++lev) {
            double gain = double(lev) <= big_l ? thin : alpha;
            if (gain * rho <= 0.0LF) continue;
            double scale = double(1 << lev);
            double rows = 7.0LF * scale;
            double hw_q = hw_px / d_q;
            int64_t ry0 = int64_t(floor((q - hw_q) * rows));
            int64_t ry1 = int64_t(floor((q + hw_q) * rows)) + 1;
            for (int64_t ry = ry0; ry <= ry1; ++ry) {
                double q_row = double(ry) / rows;
                double dist = abs(q - q_row) * d_q;
                if (dist > hw_px) continue;
                int64_t gy = floor_div7(ry);
                int r = int(ry - 7 * gy);
                int kx = KX[r];
                double half_cells = 0.5LF * lam * (1.0LF + len_jit) + end_px / d_p * scale;
                double ps = p * scale - double(kx) / 7.0LF;
                int64_t gx0 = int64_t(floor(ps - half_cells));
                int64_t gx1 = int64_t(floor(ps + half_cells)) + 1;
                for (int64_t gx = gx0; gx <= gx1; ++gx) {
                    if (lev > 0 && (gx & 1) == int64_t(kx & 1) && (gy & 1) == int64_t(r & 1))
                        continue;  // inherited: enumerated at its birth level
                    int64_t sid = pack_id(chart, lay, lev, gx, gy, r);
                    double h = hash01(sid, SALT_LENGTH);
                    double length = lam * (1.0LF + len_jit * (2.0LF * h - 1.0LF)) / scale;
                    double p_start = (double(gx) + double(kx) / 7.0LF) / scale - 0.5LF * length;
                    double t = (p - p_start) / length;
                    double beyond = max(-t, t - 1.0LF) * length * d_p;
                    if (beyond > end_px) continue;
                    if (n >= CAP) continue;  // refnpr keeps the first CAP candidates
                    n += 1;
                    double tau = hash01(sid, SALT_TONE);
                    double limit = rho * gain;
#if FADE_MODE
                    double opacity = clampd((limit - tau) / fade, 0.0LF, 1.0LF);
#else
                    double opacity = tau < limit ? 1.0LF : 0.0LF;
#endif
                    if (opacity <= 0.0LF) continue;
                    double wf = 1.0LF + wid_jit * (2.0LF * hash01(sid, SALT_WIDTH) - 1.0LF);
                    double cov_q = clampd(0.5LF * width_px * wf - dist + 0.5LF, 0.0LF, 1.0LF);
                    double cov_p = clampd(0.5LF - beyond, 0.0LF, 1.0LF);
                    double a = cov_q * cov_p * opacity;
                    ink = ink + a * (1.0LF - ink);
                }
            }
        }
    }

    // composite the ink over the paper (or nothing): straight alpha
    float a = clamp(float(ink), 0.0, 1.0);
#if HAS_PAPER
    float a_u = 1.0;
    vec3 under = paper;
#else
    float a_u = 0.0;
    vec3 under = vec3(0.0);
#endif
    float alpha = a + a_u * (1.0 - a);
    vec3 premult = ink_color * a + under * (a_u * (1.0 - a));
    vec3 rgb = alpha > 0.0 ? premult / alpha : vec3(0.0);
    frag = vec4(clamp(rgb, 0.0, 1.0), alpha);
}
