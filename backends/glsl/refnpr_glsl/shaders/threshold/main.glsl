// threshold style (Veryovka 2002): per-sample shading pass. refnpr:
// refnpr/styles/threshold/style.py (shade), _kernels.py, images.py, bump.py;
// refnpr/formulas/threshold/strength.py.
// Generated constants (see refnpr_glsl/styles/threshold.py) come before this file.

uniform isampler2D g_mesh_id;
uniform sampler2D g_normal;
#if HAS_POSITION
uniform sampler2D g_position;
#endif
#if HAS_UV
uniform sampler2D g_uv;
#endif
#if HAS_DUV
uniform sampler2D g_duv_dx;
uniform sampler2D g_duv_dy;
#endif
#if HAS_DYADIC
uniform sampler2D g_dyadic_scale;
#endif
#if BUMP
uniform sampler2D g_dposition_dx;
uniform sampler2D g_dposition_dy;
#endif

layout(location = 0) out vec4 frag;

#define SRC_CONSTANT 0
#define SRC_IMAGE 1
#define SRC_LINES 2
#define SRC_STIPPLE 3
#define FILTER_NONE 0
#define FILTER_PCF 1
#define FILTER_ANALYTIC 2

// ---- sampled thresholds (refnpr/styles/threshold/_kernels.py shade_threshold_for): T_n per threshold, weighted mean
float T[NT_MAX];
float W[NT_MAX];
int n_t = 1;
bool weighted = false;

float apply_sampled(float x) {
    if (n_t == 1 && !weighted) return step_n(x, T[0]);
    real num = 0.0, den = 0.0;
    for (int j = 0; j < n_t; ++j) {
        real w = weighted ? real(W[j]) : 1.0;
        num += w * real(step_n(x, T[j]));
        den += w;
    }
    return float(num / den);
}

// grid_offsets(k) / n: ((i + 0.5) / k - 0.5, (j + 0.5) / k - 0.5) / n, j (y) outer, i (x) inner
rvec2 grid_offset(int idx) {
    int iy = idx / KGRID, ix = idx % KGRID;
    real ox = (real(ix) + 0.5) / real(KGRID) - 0.5;
    real oy = (real(iy) + 0.5) / real(KGRID) - 0.5;
    return rvec2(ox, oy) / real(SPP_N);
}

#if SOURCE == SRC_LINES
real lv_v[N_LAYERS];
real lv_dx[N_LAYERS];
real lv_dy[N_LAYERS];
float lv_s[N_LAYERS];
real lv_noise = 0.0;

#if FILTER == FILTER_ANALYTIC
real cov_layer(int i, real y) {
    real gx = lv_dx[i] / real(SPP_N), gy = lv_dy[i] / real(SPP_N);
#if HAS_NOISE
    real z = lv_noise - floor(lv_noise);
    return line_coverage(lv_v[i], lv_s[i], y - z, gx, gy)
         + line_coverage(lv_v[i], lv_s[i], y + 1.0 - z, gx, gy)
         - line_coverage(lv_v[i], lv_s[i], 1.0 - z, gx, gy);
#else
    return line_coverage(lv_v[i], lv_s[i], y, gx, gy);
#endif
}

float apply_analytic(float xf) {
    real x = real(xf);
    real xn = x * real(N_STEPS);
    real base = floor(xn);
    real r = xn - base;
    real cover = 1.0;
    for (int i = 0; i < N_LAYERS; ++i) {
#if N_LAYERS > 1
        real w = real(layer_white(float(r), i));
#else
        real w = r;
#endif
        cover *= cov_layer(i, w);
    }
    cover = r >= 1.0 ? 1.0 : clamp(cover, 0.0, 1.0);
    return float(min(base + cover, ceil(xn)) / real(N_STEPS));
}
#endif
#endif

float apply_thr(float x) {
#if SOURCE == SRC_LINES && FILTER == FILTER_ANALYTIC
    return apply_analytic(x);
#else
    return apply_sampled(x);
#endif
}

float apply_thr_s(float x) {
#if SPEC_CONST
    return step_n(x, SPEC_T);
#else
    return apply_thr(x);
#endif
}

float smooth01(float x) {
    float c = clamp(x, 0.0, 1.0);
    return c * c * (3.0 - 2.0 * c);
}

// sec. 5 strength: B(x) = x + strength * s_o * s_i * (T(x) - x)
float term(float x, float tx, float orient) {
    float st = STRENGTH * orient;
    if (TONE_DARK > 0.0) st *= smooth01(x / TONE_DARK);
    if (TONE_BRIGHT > 0.0) st *= smooth01((1.0 - x) / TONE_BRIGHT);
    return x + st * (tx - x);
}

void build_thresholds(int mid, rvec2 uv, rvec2 gx, rvec2 gy, ivec2 p) {
#if SOURCE == SRC_CONSTANT
    T[0] = T_CONST;
#elif SOURCE == SRC_IMAGE
    int g = GROUP[mid];
#if FILTER == FILTER_PCF
    const int kk = KGRID * KGRID;
    const int width = MIP_PER_LEVEL != 0 ? 2 * kk : kk;
    weighted = true;
#else
    const int kk = 1;
    const int width = 1;
#endif
    n_t = width;
    for (int j = 0; j < width; ++j) {
        T[j] = T_CONST;
        W[j] = 1.0 / float(width);
    }
    if (g < 0) return;
    float lod = texture_lod(g, vec2(gx), vec2(gy), LOD_BIAS);
    int k0, k1;
    float f;
    level_weights(g, lod, k0, k1, f);
    for (int j = 0; j < kk; ++j) {
#if FILTER == FILTER_PCF
        rvec2 o = grid_offset(j);
        rvec2 uvj = uv + o.x * gx + o.y * gy;
#else
        rvec2 uvj = uv;
#endif
#if !MIP_PER_LEVEL && !TONE_CORRECT
        T[j] = float(sample_trilinear(g, uvj, lod));
#else
        real t0 = sample_level(g, uvj, k0);
        real t1 = sample_level(g, uvj, k1);
#if TONE_CORRECT
        t0 = real(tone_map(g, k0, float(t0)));
        t1 = real(tone_map(g, k1, float(t1)));
#endif
#if !MIP_PER_LEVEL
        T[j] = float((1.0 - real(f)) * t0 + real(f) * t1);
#else
        T[j] = float(t0);
        T[kk + j] = float(t1);
        W[j] = float((1.0 - real(f)) / real(kk));
        W[kk + j] = float(real(f) / real(kk));
#endif
#endif
    }
#elif SOURCE == SRC_LINES
    for (int i = 0; i < N_LAYERS; ++i) {
        real sa = SIN_A[i], ca = COS_A[i];
        lv_v[i] = -uv.x * sa + uv.y * ca;
        lv_dx[i] = -gx.x * sa + gx.y * ca;
        lv_dy[i] = -gy.x * sa + gy.y * ca;
        float s;
#if CHANNEL_SCALE
        s = texelFetch(g_dyadic_scale, p, 0).r - LOG2_SV[mid];
#else
        s = dyadic_scale_from_gradient(float(lv_dx[i]), float(lv_dy[i]), PERIOD);
#endif
#if !MULTISCALE
        s = floor(s);
#endif
        lv_s[i] = s;
    }
#if HAS_NOISE
    lv_noise = real(NOISE_AMP) * value_noise(uv * real(NOISE_SCALE), NOISE_SEED);
#endif
#if FILTER != FILTER_ANALYTIC
#if FILTER == FILTER_PCF
    const int kk = KGRID * KGRID;
#else
    const int kk = 1;
#endif
    n_t = kk;
    for (int j = 0; j < kk; ++j) {
#if FILTER == FILTER_PCF
        rvec2 o = grid_offset(j);
#else
        rvec2 o = rvec2(0.0);
#endif
#if N_LAYERS == 1
        T[j] = float(line_threshold(lv_v[0] + o.x * lv_dx[0] + o.y * lv_dy[0], lv_s[0], lv_noise));
#else
        float lam_star = 1e38;
        for (int i = 0; i < N_LAYERS; ++i) {
            float fi = float(line_threshold(lv_v[i] + o.x * lv_dx[i] + o.y * lv_dy[i], lv_s[i], lv_noise));
            lam_star = min(lam_star, darkness_of_layer(fi, i));
        }
        T[j] = clamp(exp(-lam_star), 0.0, ONE_BELOW_F);
#endif
    }
#endif
#elif SOURCE == SRC_STIPPLE
    float s_u = dyadic_scale_from_gradient(float(gx.x), float(gy.x), PERIOD);
    float s_v = dyadic_scale_from_gradient(float(gx.y), float(gy.y), PERIOD);
#if !MULTISCALE
    s_u = floor(s_u);
    s_v = floor(s_v);
#endif
#if FILTER == FILTER_PCF
    const int kk = KGRID * KGRID;
    n_t = kk;
    for (int j = 0; j < kk; ++j) {
        rvec2 o = grid_offset(j);
        T[j] = stipple_threshold(uv + o.x * gx + o.y * gy, s_u, s_v);
    }
#else
    T[0] = stipple_threshold(uv, s_u, s_v);
#endif
#endif
}

#if BUMP
// Mikkelsen 2010 surface-gradient bump (refnpr/styles/threshold/bump.py)
rvec3 bump_normal(rvec3 n, rvec2 uv, rvec2 gx, rvec2 gy, ivec2 p) {
    int lv = LV0[BUMP_G];
    rvec2 texels = rvec2(real(LV_COLS[lv]), real(LV_ROWS[lv]));
    rvec2 tx = gx * texels, ty = gy * texels;
    real rho = max(length(tx), length(ty));
    float lod = log2(float(max(rho, 1e-12)));
    real hh = real(BUMP_HEIGHT);
    real dhdx = hh * sample_trilinear(BUMP_G, uv + 0.5 * gx, lod)
                - hh * sample_trilinear(BUMP_G, uv - 0.5 * gx, lod);
    real dhdy = hh * sample_trilinear(BUMP_G, uv + 0.5 * gy, lod)
                - hh * sample_trilinear(BUMP_G, uv - 0.5 * gy, lod);
    rvec3 dpdx = rvec3(texelFetch(g_dposition_dx, p, 0).xyz);
    rvec3 dpdy = rvec3(texelFetch(g_dposition_dy, p, 0).xyz);
    rvec3 r1 = cross(dpdy, n);
    rvec3 r2 = cross(n, dpdx);
    real det = dot(dpdx, r1);
    rvec3 grad = sign(det) * (dhdx * r1 + dhdy * r2);
    rvec3 o = abs(det) * n - grad;
    real len = length(o);
    return len > 0.0 ? o / len : n;
}
#endif

void main() {
    ivec2 p = ivec2(gl_FragCoord.xy);
    int mid = texelFetch(g_mesh_id, p, 0).r;
    if (mid < 0) {
        frag = vec4(0.0);
        return;
    }
    rvec3 nd = rvec3(texelFetch(g_normal, p, 0).xyz);
    rvec2 uv = rvec2(0.0), gx = rvec2(0.0), gy = rvec2(0.0);
#if HAS_UV
    uv = rvec2(texelFetch(g_uv, p, 0).xy) * UVS[mid];
#endif
#if HAS_DUV
    gx = rvec2(texelFetch(g_duv_dx, p, 0).xy) * UVS[mid];
    gy = rvec2(texelFetch(g_duv_dy, p, 0).xy) * UVS[mid];
#endif
#if BUMP
    nd = bump_normal(nd, uv, gx, gy, p);
#endif
    vec3 n = vec3(nd);
    vec3 pos = vec3(0.0);
    vec3 view = vec3(0.0);
#if HAS_POSITION
    pos = texelFetch(g_position, p, 0).xyz;
    rvec3 vd = rvec3(EYE) - rvec3(pos);
    real vl = length(vd);
    view = vl > 0.0 ? vec3(vd / vl) : vec3(0.0);
#endif
    vec3 rgb = MAT_A[mid] * AMBIENT;  // eq. 2: ambient kept
    build_thresholds(mid, uv, gx, gy, p);
    float orient = 1.0;
#if FACING
    orient = 1.0 - FACING_FADE * pow(abs(dot(n, view)), FACING_POWER);
#endif
    real nl_len = length(nd);
    vec3 nu = nl_len > 0.0 ? vec3(nd / nl_len) : vec3(0.0);
#if N_LIGHTS > 0
    for (int li = 0; li < N_LIGHTS; ++li) {
        vec3 L = LIGHT_VEC[li];
        if (LIGHT_KIND[li] == 1) {  // point light: towards its position
            rvec3 d = rvec3(LIGHT_VEC[li]) - rvec3(pos);
            real dl = length(d);
            L = dl > 0.0 ? vec3(d / dl) : vec3(0.0);
        }
        float f_d = min(max(dot(nu, L), 0.0), 1.0);  // eq. 1: f_d
        rgb += MAT_D[mid] * term(f_d, apply_thr(f_d), orient) * LIGHT_COLOR[li];
#if SPECULAR
        float f_s = 0.0;  // eq. 1: f_s, Blinn-Phong, n as given
        if (SHININESS[mid] > 0.0) {
            vec3 h = L + view;
            float hl = length(h);
            h = hl > 0.0 ? h / hl : vec3(0.0);
            float base = max(dot(n, h), 0.0);
            f_s = dot(n, L) > 0.0 ? pow(base, SHININESS[mid]) : 0.0;
        }
        rgb += MAT_S[mid] * term(f_s, apply_thr_s(f_s), orient) * LIGHT_COLOR[li];
#endif
    }
#endif
    frag = vec4(clamp(rgb, 0.0, 1.0), 1.0);
}
