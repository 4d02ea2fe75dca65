#version 450 core
// X-Toon (Barla, Thollot, Markosian 2006) per-sample shading: tone x detail lookup in a 2D toon
// texture, attribute maps per pixel or per vertex, shape abstraction by normal blending.
// Mirrors refnpr/styles/xtoon/evaluation.py (the kit's case.json "derived" texts say the same).
// Configuration arrives as #defines inserted after the #version line (see styles/xtoon.py):
//   DETAIL       0 depth, 1 focus, 2 orientation, 3 highlight, 4 flow, 5 map, 6 none
//   DIST_EYE     1: z = |P - eye| (Fig. 2a), 0: view-axis distance (Fig. 2b)
//   VERTEX_MODE  1: D (flow: the displacement) per vertex, interpolated with bary
//   SHAPED       1: shape abstraction; BLEND_VERTEX 1: per-vertex blend, 0: per pixel
//   WEIGHT       0 global, 1 detail, 2 texture, 3 map
//   HALF_LAMBERT, LIGHT_POINT, ONE_SIDED, MODULATE, NEED_TRI, PIXEL_DEPTH, PIXEL_POSITION
//   SHOW         0 color, 1 detail, 2 inverse_detail, 3 tone
//DEFINES

layout(location = 0) out vec4 frag;

uniform isampler2D g_mesh_id;
uniform isampler2D g_tri_id;
uniform sampler2D g_bary;
uniform sampler2D g_normal;
uniform sampler2D g_position;
uniform sampler2D g_depth;
uniform sampler2D g_uv;
uniform sampler2D toon_tex;
uniform sampler2D detail_map_tex;
uniform sampler2D weight_tex;

// Scene geometry for the per-vertex quantities (the paper's vertex shader), fetched by tri_id:
// faces: 3 global vertex indices per triangle (tri_id order); verts: 9 floats per vertex
// (position, normal, abstracted normal); diffuse: 3 floats per object (mesh_id order).
layout(std430, binding = 0) readonly buffer Faces { int faces[]; };
layout(std430, binding = 1) readonly buffer Verts { float verts[]; };
layout(std430, binding = 2) readonly buffer Diffuse { float diffuse[]; };

uniform vec3 eye;
uniform vec3 light_dir;     // unit, towards the light (directional)
uniform vec3 light_pos;     // point light position
uniform vec4 view_row2;     // row 2 of the view matrix: view-axis depth = -(row2 . (P, 1))
uniform mat4 vp_now;        // projection @ view (image W x H), current camera
uniform mat4 vp_prev;       // the same for prev_camera (flow)
uniform vec2 image_size;    // W, H in pixels (flow is measured in image pixels)
uniform float z_min;
uniform float r_exp;        // r of the depth/focus maps, or the orientation exponent
uniform float log_r;        // ln r
uniform float z_focus;
uniform float log_near;     // ln((z_c - r z_min) / (z_c - z_min))
uniform float log_far;      // ln((z_c + r z_min) / (z_c + z_min))
uniform float s_exp;
uniform float flow_min;
uniform float flow_max;
uniform float flow_behind;
uniform float tiny;
uniform float weight_value;
uniform vec2 uv_scale;
uniform int n_axis;             // samples per pixel along an axis
uniform int detail_map_per_sample;
uniform int weight_map_per_sample;

float clamp01(float x) { return clamp(x, 0.0, 1.0); }

vec3 unit3(vec3 v) {
    float l = length(v);
    return l > 0.0 ? v / l : vec3(0.0);
}

// x^y for x in [0, 1] as numpy computes it (0^0 = 1, 0^y = 0 for y > 0)
float pow01(float x, float y) {
    if (y == 0.0) return 1.0;
    if (x <= 0.0) return 0.0;
    return pow(x, y);
}

vec3 light_at(vec3 P) {
#if LIGHT_POINT
    return unit3(light_pos - P);
#else
    return light_dir;
#endif
}

vec3 view_vec(vec3 P) {
    vec3 v = eye - P;
    return v / max(length(v), tiny);
}

float z_of(vec3 P) {
#if DIST_EYE
    return length(P - eye);                       // Fig. 2a
#else
    return -(dot(view_row2.xyz, P) + view_row2.w); // Fig. 2b (w_clip)
#endif
}

float detail_z(float z) {
    z = max(z, tiny);
#if DETAIL == 0
    return clamp01(1.0 - log(z / z_min) / log_r);  // sec. 3.1: D = 1 - log_r(z / z_min)
#else
    bool near = z < z_focus;                        // sec. 3.1, depth of field
    float zpm = near ? z_focus - z_min : z_focus + z_min;
    float lr = near ? log_near : log_far;
    return clamp01(1.0 - log(z / zpm) / lr);
#endif
}

vec2 pixel_of(mat4 vp, vec3 P, out bool ok) {
    vec4 c = vp * vec4(P, 1.0);
    ok = c.w > 0.0;
    return vec2((c.x / c.w + 1.0) * 0.5 * image_size.x, (1.0 - c.y / c.w) * 0.5 * image_size.y);
}

vec2 flow_at(vec3 P) {  // sec. 5: screen displacement since prev_camera, image pixels
    bool a, b;
    vec2 now = pixel_of(vp_now, P, a);
    vec2 before = pixel_of(vp_prev, P, b);
    vec2 f = now - before;
    if (!a || !b || any(isnan(f)) || any(isinf(f))) f = vec2(flow_behind, 0.0);
    return f;
}

float detail_flow(vec2 f) {
    float t = (length(f) - flow_min) / (flow_max - flow_min);
    if (isnan(t)) t = 1.0;
    return 1.0 - clamp01(t);
}

// D of the orientation / highlight / flow / depth maps at a point with normal n (per vertex)
float detail_point(vec3 P, vec3 n) {
#if DETAIL == 0 || DETAIL == 1
    return detail_z(z_of(P));
#elif DETAIL == 2
    float c = clamp(dot(n, view_vec(P)), -1.0, 1.0);
    return pow01(min(abs(c), 1.0), r_exp);            // sec. 3.2: |n.v|^r
#elif DETAIL == 3
    vec3 L = light_at(P);
    vec3 refl = 2.0 * dot(n, L) * n - L;
    float x = clamp(dot(view_vec(P), refl), -1.0, 1.0);
#if ONE_SIDED
    float base = max(x, 0.0);
#else
    float base = abs(x);
#endif
    return pow01(min(base, 1.0), s_exp);              // sec. 3.2: |v.r|^s
#elif DETAIL == 4
    return detail_flow(flow_at(P));
#else
    return 1.0;
#endif
}

struct Vtx { vec3 p; vec3 n; vec3 a; };

Vtx vertex(int i) {
    int o = 9 * i;
    return Vtx(vec3(verts[o], verts[o + 1], verts[o + 2]),
               vec3(verts[o + 3], verts[o + 4], verts[o + 5]),
               vec3(verts[o + 6], verts[o + 7], verts[o + 8]));
}

// the per-vertex linear blend (1 - w) n + w n_abs (sec. 4, the paper's vertex shader)
vec3 vertex_blend(Vtx v) {
    vec3 nv = unit3(v.n);
#if SHAPED
#if WEIGHT == 0
    float w = weight_value;
#elif WEIGHT == 1
    float w = 1.0 - detail_point(v.p, nv);  // local weight from the same map, mesh normals
#else
    float w = 0.0;
#endif
    return (1.0 - w) * nv + w * v.a;
#else
    return nv;
#endif
}

float vertex_detail(Vtx v) {
#if SHAPED
    return detail_point(v.p, unit3(vertex_blend(v)));
#else
    return detail_point(v.p, unit3(v.n));
#endif
}

float map_at(sampler2D tex, ivec2 px, int per_sample) {
    ivec2 q = per_sample != 0 ? px : px / n_axis;
    return texelFetch(tex, q, 0).r;
}

// bilinear GL_REPEAT lookup with texel centres (refnpr.texture sample_level, level 0)
float repeat_bilinear(sampler2D tex, vec2 uv) {
    ivec2 size = textureSize(tex, 0);
    float x = (uv.x - floor(uv.x)) * float(size.x) - 0.5;
    float y = (uv.y - floor(uv.y)) * float(size.y) - 0.5;
    float x0 = floor(x);
    float y0 = floor(y);
    float fx = x - x0;
    float fy = y - y0;
    int i0 = int(x0) % size.x; if (i0 < 0) i0 += size.x;
    int j0 = int(y0) % size.y; if (j0 < 0) j0 += size.y;
    int i1 = (i0 + 1) % size.x;
    int j1 = (j0 + 1) % size.y;
    return (1.0 - fx) * (1.0 - fy) * texelFetch(tex, ivec2(i0, j0), 0).r
         + fx * (1.0 - fy) * texelFetch(tex, ivec2(i1, j0), 0).r
         + (1.0 - fx) * fy * texelFetch(tex, ivec2(i0, j1), 0).r
         + fx * fy * texelFetch(tex, ivec2(i1, j1), 0).r;
}

// bilinear clamp-to-edge lookup in the 2D toon texture (refnpr.formulas.xtoon.toon_lookup)
vec4 toon_lookup(float tone, float detail) {
    ivec2 size = textureSize(toon_tex, 0);
    int cols = size.x;
    int rows = size.y;
    float x = clamp(clamp01(tone) * float(cols) - 0.5, 0.0, float(cols - 1));
    float y = clamp(clamp01(detail) * float(rows) - 0.5, 0.0, float(rows - 1));
    int j0 = min(int(floor(x)), max(cols - 2, 0));
    int i0 = min(int(floor(y)), max(rows - 2, 0));
    int j1 = min(j0 + 1, cols - 1);
    int i1 = min(i0 + 1, rows - 1);
    float fx = x - float(j0);
    float fy = y - float(i0);
    vec4 top = texelFetch(toon_tex, ivec2(j0, i0), 0) * (1.0 - fx)
             + texelFetch(toon_tex, ivec2(j1, i0), 0) * fx;
    vec4 bottom = texelFetch(toon_tex, ivec2(j0, i1), 0) * (1.0 - fx)
                + texelFetch(toon_tex, ivec2(j1, i1), 0) * fx;
    return top * (1.0 - fy) + bottom * fy;
}

float srgb_to_linear(float x) {
    return x <= 0.04045 ? x / 12.92 : pow((x + 0.055) / 1.055, 2.4);
}

void main() {
    ivec2 px = ivec2(gl_FragCoord.xy);
    int mid = texelFetch(g_mesh_id, px, 0).r;
    if (mid < 0) {
        frag = vec4(0.0);
        return;
    }
#if PIXEL_POSITION
    vec3 P = texelFetch(g_position, px, 0).xyz;
#else
    vec3 P = vec3(0.0);
#endif
    vec3 L = light_at(P);
#if NEED_TRI
    int tri = texelFetch(g_tri_id, px, 0).r;
    vec3 b = texelFetch(g_bary, px, 0).xyz;
    Vtx v0 = vertex(faces[3 * tri]);
    Vtx v1 = vertex(faces[3 * tri + 1]);
    Vtx v2 = vertex(faces[3 * tri + 2]);
#endif

    // shading normal
#if !SHAPED
    vec3 n = unit3(texelFetch(g_normal, px, 0).xyz);
#elif BLEND_VERTEX
    vec3 n = unit3(b.x * vertex_blend(v0) + b.y * vertex_blend(v1) + b.z * vertex_blend(v2));
#else
    vec3 n0 = unit3(texelFetch(g_normal, px, 0).xyz);
    vec3 na = b.x * v0.a + b.y * v1.a + b.z * v2.a;
#if WEIGHT == 0
    float w = weight_value;
#elif WEIGHT == 1
#if DETAIL == 0 || DETAIL == 1
#if PIXEL_DEPTH
    float w = 1.0 - detail_z(texelFetch(g_depth, px, 0).r);
#else
    float w = 1.0 - detail_z(z_of(P));
#endif
#elif DETAIL == 5
    float w = 1.0 - map_at(detail_map_tex, px, detail_map_per_sample);
#else
    float w = 1.0 - detail_point(P, n0);
#endif
#elif WEIGHT == 2
    float w = clamp01(repeat_bilinear(weight_tex, texelFetch(g_uv, px, 0).xy * uv_scale));
#else
    float w = map_at(weight_tex, px, weight_map_per_sample);
#endif
    bool ok = length(na) > 0.0;
    if (!ok) na = n0;
    if (length(n0) == 0.0) {
        n0 = ok ? na : vec3(0.0, 0.0, 1.0);
        if (!ok) na = vec3(0.0, 0.0, 1.0);
    }
    vec3 a = unit3(n0);
    vec3 c = unit3(na);
    vec3 m = (1.0 - w) * a + w * c;                 // sec. 4: blend, renormalized per pixel
    float mn = length(m);
    vec3 n = mn > 1.17549435e-38 ? m / mn : (w < 0.5 ? a : c);
#endif

    float n_dot_l = dot(n, L);
#if HALF_LAMBERT
    float tone = 0.5 * (n_dot_l + 1.0);
#else
    float tone = clamp01(n_dot_l);                   // sec. 3: tone from n.l
#endif

#if VERTEX_MODE && DETAIL == 4
    float D = detail_flow(b.x * flow_at(v0.p) + b.y * flow_at(v1.p) + b.z * flow_at(v2.p));
#elif VERTEX_MODE && DETAIL < 4
    float D = clamp01(b.x * vertex_detail(v0) + b.y * vertex_detail(v1) + b.z * vertex_detail(v2));
#elif DETAIL == 0 || DETAIL == 1
#if PIXEL_DEPTH
    float D = detail_z(texelFetch(g_depth, px, 0).r);
#else
    float D = detail_z(z_of(P));
#endif
#elif DETAIL == 5
    float D = map_at(detail_map_tex, px, detail_map_per_sample);
#else
    float D = detail_point(P, n);
#endif

#if SHOW == 0
    vec4 t = toon_lookup(tone, D);                   // sec. 3: the 2D toon texture
    vec3 col = t.rgb;
#if MODULATE
    col *= vec3(diffuse[3 * mid], diffuse[3 * mid + 1], diffuse[3 * mid + 2]);
#endif
    frag = vec4(clamp(col, 0.0, 1.0), clamp01(t.a));
#else
#if SHOW == 1
    float value = D;
#elif SHOW == 2
    float value = 1.0 - D;
#else
    float value = tone;
#endif
    frag = vec4(vec3(srgb_to_linear(clamp01(value))), 1.0);
#endif
}
