// The tamiss style's per-sample straight-alpha RGBA (refnpr styles/tamiss/compose.py
// composite_ink): ink (coverage) in the ink colour, or a show view's per-sample colour, over the
// paper colour on covered samples (or over nothing: alpha = ink).
struct Frag { uint64_t id; float t; float x; float y; uint meta; };
layout(std430, binding = 0) readonly buffer Counts { uint counts[]; };
layout(std430, binding = 1) readonly buffer Offsets { uint offsets[]; };
layout(std430, binding = 2) readonly buffer Frags { Frag frags[]; };

uniform sampler2D t_ink;      // premultiplied (rgb, coverage) of the strips
uniform isampler2D t_tri_id;
uniform int view;             // 0 color, 1 ids, 2-4 strips coloured per piece
uniform int use_paper;
uniform vec3 paper;
uniform vec3 ink_color;
uniform ivec2 grid;

layout(location = 0) out vec4 outc;

void main() {
    ivec2 p = ivec2(gl_FragCoord.xy);
    double a;
    dvec3 col;
    if (view == 1) {
        uint i = uint(p.y * grid.x + p.x);
        if (counts[i] > 0u) {
            uint64_t sid = frags[offsets[i]].id;
            double h6 = hash01(sid, 11) * 6.0LF;
            dvec3 kk = mod(dvec3(5.0LF, 3.0LF, 1.0LF) + h6, 6.0LF);
            dvec3 ramp = clamp(min(kk, 4.0LF - kk), 0.0LF, 1.0LF);
            col = 0.7LF * (1.0LF - 0.9LF * ramp);
            a = 1.0LF;
        } else {
            col = dvec3(0.0LF);
            a = 0.0LF;
        }
    } else {
        vec4 ink = texelFetch(t_ink, p, 0);
        a = double(ink.a);
        if (view == 0) col = dvec3(ink_color);
        else col = a > 0.0LF ? dvec3(ink.rgb) / a : dvec3(0.0LF);
    }
    a = clamp(a, 0.0LF, 1.0LF);
    double a_b = 0.0LF;
    dvec3 under = dvec3(0.0LF);
    if (use_paper != 0 && texelFetch(t_tri_id, p, 0).r >= 0) { a_b = 1.0LF; under = dvec3(paper); }
    double alpha = a + a_b * (1.0LF - a);
    dvec3 pm = col * a + under * (a_b * (1.0LF - a));
    dvec3 rgb = alpha > 0.0LF ? pm / alpha : dvec3(0.0LF);
    outc = vec4(vec3(clamp(rgb, 0.0LF, 1.0LF)), float(alpha));
}
