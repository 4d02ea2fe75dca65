#version 450 core
// Freudenberg, Masuch, Strothotte 2002, "Real-Time Halftoning": per-sample shading of the
// refnpr `halftone` style (refnpr/styles/halftone/), one full-screen pass per scene object
// (samples of other objects are discarded, empty samples get alpha 0).
//
// Screens are sampled by hand from their exported mip levels (texelFetch): GL_REPEAT bilinear
// with texel centres at (i + 0.5) / size, trilinear over lod clamped to [0, L - 1], exactly as
// refnpr.texture._kernels does. Hardware filtering (textureLod) would blend with the GPU's
// fixed-point sub-texel weights (8 bits on most GPUs), which moves binary-threshold edges.
//
// The host prepends "#define MAX_LIGHTS n" and optionally "#define REAL_DOUBLE" (float64
// arithmetic for the screen coordinates, filtering, lighting and thresholds, as refnpr) or
// "#define HW_FILTER" (the texture unit's own trilinear filtering, textureLod, instead of the
// exact filtering by hand: what most shaders do; shows what the GPU's filter precision costs).

#ifdef REAL_DOUBLE
#define real double
#define real2 dvec2
#define real3 dvec3
#define real4 dvec4
#else
#define real float
#define real2 vec2
#define real3 vec3
#define real4 vec4
#endif

// G-buffer (array layout, sample grid)
uniform isampler2D g_mesh_id;
uniform sampler2D g_normal;
uniform sampler2D g_uv;
uniform sampler2D g_duv_dx;
uniform sampler2D g_duv_dy;
uniform sampler2D g_position;
uniform sampler2D g_dposition_dx;
uniform sampler2D g_dposition_dy;

// the object's screen and maps
uniform sampler2D t_screen;      // R, all mip levels
uniform int screen_levels;
uniform ivec2 screen_size[16];   // (cols, rows) per level
uniform sampler2D t_normals;     // RGB-encoded stroke normal map, all mip levels
uniform int normals_levels;      // 0: no normal map
uniform ivec2 normals_size[16];
uniform sampler2D t_indication;  // signed indication map (one level)
uniform int has_indication;
uniform sampler2D t_lut;         // tone LUTs: row k = level k
uniform int equalize;

uniform int obj;
uniform int engraving;
uniform vec2 direction;
uniform vec2 uv_scale;
uniform vec2 indication_scale;
uniform int anisotropy;
uniform float lod_offset;
uniform int per_level;
uniform int threshold_binary;
uniform float c_const;
uniform int c_fwidth;
uniform int centred;
uniform float n_axis;
uniform int show;  // 0 color, 1 screen, 2 normals, 3 intensity
uniform vec3 ink;
uniform vec3 paper;
uniform vec3 luma;

// lighting (Veryovka eq. 1)
uniform vec3 m_a;
uniform vec3 m_d;
uniform vec3 m_s;
uniform float shininess;
uniform vec3 l_a;
uniform int use_specular;
uniform vec3 eye;
uniform int light_point[MAX_LIGHTS];
uniform vec3 light_vec[MAX_LIGHTS];  // unit direction towards the light, or the position
uniform vec3 light_color[MAX_LIGHTS];
uniform int n_lights;
uniform int need_position;

out vec4 frag;

int wrap_index(int i, int n) {
    int r = i % n;
    return r < 0 ? r + n : r;
}

// Level sizes come from uniforms: llvmpipe (Mesa 22.3) answers textureSize(t, lod) with one
// lane's level when lod differs within a quad.
ivec2 level_size(int which, int k) { return which == 0 ? screen_size[k] : normals_size[k]; }

// GL_LINEAR / GL_REPEAT sample of level k (refnpr.device.sampling.bilinear)
real4 bilinear(sampler2D t, int which, int k, real2 uv) {
#ifdef HW_FILTER
    return real4(textureLod(t, vec2(uv), float(k)));  // the sampler: LINEAR_MIPMAP_LINEAR, REPEAT
#endif
    ivec2 sz = level_size(which, k);
    int cols = sz.x, rows = sz.y;
    real x = (uv.x - floor(uv.x)) * real(cols) - real(0.5);
    real y = (uv.y - floor(uv.y)) * real(rows) - real(0.5);
    real x0 = floor(x), y0 = floor(y);
    real fx = x - x0, fy = y - y0;
    int i0 = wrap_index(int(x0), cols), i1 = wrap_index(int(x0) + 1, cols);
    int j0 = wrap_index(int(y0), rows), j1 = wrap_index(int(y0) + 1, rows);
    real w00 = (real(1) - fx) * (real(1) - fy);
    real w10 = fx * (real(1) - fy);
    real w01 = (real(1) - fx) * fy;
    real w11 = fx * fy;
    return w00 * real4(texelFetch(t, ivec2(i0, j0), k)) + w10 * real4(texelFetch(t, ivec2(i1, j0), k))
         + w01 * real4(texelFetch(t, ivec2(i0, j1), k)) + w11 * real4(texelFetch(t, ivec2(i1, j1), k));
}

// GL_LINEAR_MIPMAP_LINEAR at an explicit lod (refnpr.texture._kernels.sample_trilinear)
real4 trilinear(sampler2D t, int which, int levels, real2 uv, real lod) {
#ifdef HW_FILTER
    return real4(textureLod(t, vec2(uv), float(lod)));
#endif
    real lam = clamp(lod, real(0), real(levels - 1));
    int k0 = int(floor(lam));
    int k1 = min(k0 + 1, levels - 1);
    real f = lam - real(k0);
    real4 s = (real(1) - f) * bilinear(t, which, k0, uv);
    if (f > real(0)) s += f * bilinear(t, which, k1, uv);
    return s;
}

// anisotropic footprint (refnpr.device.sampling.footprint): probes and axis
int probes;
real2 axis;

real4 sample_screen(sampler2D t, int which, int levels, real2 uv, real lod) {
    if (probes <= 1) return trilinear(t, which, levels, uv, lod);
    real4 s = real4(0);
    for (int j = 0; j < probes; ++j) {
        real off = (real(j) + real(0.5)) / real(probes) - real(0.5);
        s += trilinear(t, which, levels, uv + axis * off, lod);
    }
    return s / real(probes);
}

real sample_level_mean(sampler2D t, int k, real2 uv) {
    if (probes <= 1) return bilinear(t, 0, k, uv).x;
    real s = real(0);
    for (int j = 0; j < probes; ++j) {
        real off = (real(j) + real(0.5)) / real(probes) - real(0.5);
        s += bilinear(t, 0, k, uv + axis * off).x;
    }
    return s / real(probes);
}

// numpy.interp of v on x = linspace(0, 1, bins) against LUT row k
real apply_lut(int k, real v) {
    int bins = textureSize(t_lut, 0).x;
    real p = clamp(v, real(0), real(1)) * real(bins - 1);
    int j = clamp(int(floor(p)), 0, bins - 2);
    real f = p - real(j);
    real a = real(texelFetch(t_lut, ivec2(j, k), 0).x);
    real b = real(texelFetch(t_lut, ivec2(j + 1, k), 0).x);
    return a + f * (b - a);
}

// bilinear clamp-to-edge indication sample (refnpr.formulas.halftone.sample_indication)
real sample_indication(real2 uv) {
    ivec2 sz = textureSize(t_indication, 0);
    int cols = sz.x, rows = sz.y;
    real x = clamp(uv.x * real(cols) - real(0.5), real(0), real(cols - 1));
    real y = clamp(uv.y * real(rows) - real(0.5), real(0), real(rows - 1));
    int x0 = min(int(floor(x)), cols - 1), y0 = min(int(floor(y)), rows - 1);
    int x1 = min(x0 + 1, cols - 1), y1 = min(y0 + 1, rows - 1);
    real fx = x - real(x0), fy = y - real(y0);
    real top = real(texelFetch(t_indication, ivec2(x0, y0), 0).x) * (real(1) - fx)
             + real(texelFetch(t_indication, ivec2(x1, y0), 0).x) * fx;
    real bot = real(texelFetch(t_indication, ivec2(x0, y1), 0).x) * (real(1) - fx)
             + real(texelFetch(t_indication, ivec2(x1, y1), 0).x) * fx;
    return top * (real(1) - fy) + bot * fy;
}

real3 unit(real3 v) {  // zero stays zero (refnpr.formulas._shading_checks.unit_vectors)
    real m = max(max(abs(v.x), abs(v.y)), abs(v.z));
    if (m <= real(0)) return real3(0);
    real3 w = v / m;
    return w / sqrt(dot(w, w));
}

real threshold_fn(real scr, real intensity, real c_auto) {
    if (threshold_binary == 1) return (scr + (intensity - real(0.5))) > real(0.5) ? real(1) : real(0);
    if (c_fwidth == 1) return clamp(real(0.5) - c_auto * (real(1) - scr - intensity), real(0), real(1));
    real top = centred == 1 ? real(0.5) : real(1);
    return clamp(top - (real(1) - scr - intensity) * real(c_const), real(0), real(1));
}

real srgb_to_linear(real x) {  // refnpr.image.srgb_to_linear
    x = clamp(x, real(0), real(1));
    if (x <= real(0.04045)) return x / real(12.92);
    real y = (x + real(0.055)) / real(1.055);
    real lin = real(pow(float(y), 2.4));
#ifdef REAL_DOUBLE
    // GLSL has no double pow: refine L = y^(12/5) by Newton on L^5 = y^12 (two steps from the
    // float32 estimate reach double precision), so that raw values on an 8-bit rounding tie
    // (x = 0.5 -> 127.5) round as refnpr's float64 does
    real y2 = y * y;
    real y12 = y2 * y2 * y2;
    y12 *= y12;
    for (int i = 0; i < 2; ++i) {
        real l4 = (lin * lin) * (lin * lin);
        lin -= (l4 * lin - y12) / (real(5) * l4);
    }
#endif
    return lin;
}

void main() {
    ivec2 p = ivec2(gl_FragCoord.xy);
    int mid = texelFetch(g_mesh_id, p, 0).x;
    if (mid < 0) { frag = vec4(0.0); return; }
    if (mid != obj) discard;

    real3 n = real3(texelFetch(g_normal, p, 0).xyz);
    real2 uv = real2(texelFetch(g_uv, p, 0).xy);
    real2 dx = real2(texelFetch(g_duv_dx, p, 0).xy);
    real2 dy = real2(texelFetch(g_duv_dy, p, 0).xy);

    // screen coordinates (screens.screen_coords): engraving t = s . direction, (t, 0.5)
    real2 sc = real2(uv_scale);
    real2 coords = uv * sc, cdx = dx * sc, cdy = dy * sc;
    if (engraving == 1) {
        real2 d = real2(direction);
        coords = real2(dot(coords, d), real(0.5));
        cdx = real2(dot(cdx, d), real(0));
        cdy = real2(dot(cdy, d), real(0));
    }

    // LOD and footprint (refnpr.device.sampling.footprint)
    ivec2 size0 = screen_size[0];
    real2 tex = real2(real(size0.x), real(size0.y));
    real px = length(cdx * tex), py = length(cdy * tex);
    real lod;
    probes = 1;
    axis = real2(0);
    if (anisotropy == 1) {
        lod = real(log2(float(max(max(px, py), real(exp2(-64.0))))));
    } else {
        real p_max = max(px, py), p_min = min(px, py);
        real ratio = p_max / max(p_min, real(exp2(-64.0)));
        probes = int(clamp(ceil(ratio - real(1e-9)), real(1), real(anisotropy)));
        lod = real(log2(float(max(p_max / real(probes), real(exp2(-64.0))))));
        axis = px >= py ? cdx : cdy;
    }
    lod += real(lod_offset);

    // target intensity (refnpr/styles/halftone/_kernels.py lit_row), with DOT3 stroke lighting (sec. 5.2)
    bool bump = normals_levels > 0;
    real3 nmap = real3(0.5, 0.5, 1.0);
    real3 T = real3(0), B = real3(0);
    bool valid = false;
    if (bump) {
        nmap = sample_screen(t_normals, 1, normals_levels, coords, lod).xyz;
        // shading.tangent_frame with the unscaled uv derivatives
        real3 dpx = real3(texelFetch(g_dposition_dx, p, 0).xyz);
        real3 dpy = real3(texelFetch(g_dposition_dy, p, 0).xyz);
        real ux = dx.x, vx = dx.y, uy = dy.x, vy = dy.y;
        real det = ux * vy - uy * vx;
        bool ok = abs(det) > real(1e-20);
        real inv = ok ? real(1) / det : real(0);
        real3 p_u = (dpx * vy - dpy * vx) * inv;
        real3 p_v = (dpy * ux - dpx * uy) * inv;
        real3 t = p_u - dot(p_u, n) * n;
        real t_len = length(t);
        t = t_len > real(1e-30) ? t / t_len : real3(0);
        real3 b = p_v - dot(p_v, n) * n - dot(p_v, t) * t;
        real b_len = length(b);
        b = b_len > real(1e-30) ? b / b_len : real3(0);
        valid = ok && t_len > real(1e-30) && b_len > real(1e-30);
        T = t;
        B = b;
    }
    real3 pos = real3(0), v = real3(0);
    if (need_position == 1) pos = real3(texelFetch(g_position, p, 0).xyz);
    if (use_specular == 1) v = unit(real3(eye) - pos);
    real3 nu = unit(n);
    real3 rgb = real3(m_a) * real3(l_a);
    for (int i = 0; i < n_lights; ++i) {
        real3 ld = light_point[i] == 1 ? unit(real3(light_vec[i]) - pos) : real3(light_vec[i]);
        real3 lu = unit(ld);
        real f_d = min(max(dot(nu, lu), real(0)), real(1));
        if (bump && valid) {
            real3 l_t = real3(dot(ld, T), dot(ld, B), dot(ld, n));
            real3 nm = unit(real(2) * nmap - real(1));
            f_d = clamp(dot(nm, unit(l_t)), real(0), real(1));
        }
        rgb += real3(m_d) * f_d * real3(light_color[i]);
        if (use_specular == 1) {
            real n_dot_l = dot(nu, lu);
            real base = clamp(dot(nu, unit(lu + v)), real(0), real(1));
            real f_s = n_dot_l > real(0) ? real(pow(float(base), shininess)) : real(0);
            rgb += real3(m_s) * f_s * real3(light_color[i]);
        }
    }
    real intensity = clamp(dot(rgb, real3(luma)), real(0), real(1));
    if (has_indication == 1) {  // sec. 5.1
        real ind = sample_indication(uv * real2(indication_scale));
        intensity = clamp(intensity + ind, real(0), real(1));
    }

    real c_auto = real(0);
    if (c_fwidth == 1 && threshold_binary == 0 && show == 0) {
        real step_ = real(1) / real(n_axis);
        real fw = real(0);
        for (int a = 0; a < 2; ++a) {
            real2 d = (a == 0 ? cdx : cdy) * step_;
            real plus = sample_screen(t_screen, 0, screen_levels, coords + d, lod).x;
            real minus = sample_screen(t_screen, 0, screen_levels, coords - d, lod).x;
            fw += abs(plus - minus) / real(2);
        }
        c_auto = real(1) / max(fw, real(1e-6));
    }

    if (show == 3) {
        float g = float(srgb_to_linear(intensity));
        frag = vec4(g, g, g, 1.0);
        return;
    }
    if (show == 2) {
        frag = vec4(float(srgb_to_linear(nmap.x)), float(srgb_to_linear(nmap.y)),
                    float(srgb_to_linear(nmap.z)), 1.0);
        return;
    }
    if (show == 1) {
        float g = float(srgb_to_linear(sample_screen(t_screen, 0, screen_levels, coords, lod).x));
        frag = vec4(g, g, g, 1.0);
        return;
    }
    real out_v;
    if (per_level == 0) {
        real value = sample_screen(t_screen, 0, screen_levels, coords, lod).x;  // sec. 3: (uv, LOD)
        out_v = threshold_fn(value, intensity, c_auto);
    } else {  // per-level thresholds blended by the trilinear weight (tone_correct: LUTs first)
        real lam = clamp(lod, real(0), real(screen_levels - 1));
        int k0 = int(floor(lam));
        int k1 = min(k0 + 1, screen_levels - 1);
        real w1 = lam - real(k0);
        real s0 = sample_level_mean(t_screen, k0, coords);
        real s1 = sample_level_mean(t_screen, k1, coords);
        if (equalize == 1) {
            s0 = apply_lut(k0, s0);
            s1 = apply_lut(k1, s1);
        }
        out_v = (real(1) - w1) * threshold_fn(s0, intensity, c_auto)
              + w1 * threshold_fn(s1, intensity, c_auto);
    }
    real3 col = out_v * real3(paper) + (real(1) - out_v) * real3(ink);
    frag = vec4(vec3(clamp(col, real3(0), real3(1))), 1.0);
}
