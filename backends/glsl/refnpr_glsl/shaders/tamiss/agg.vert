// Aggregation by blending (TAMISS sec. 3.1 "summation", sec. 4): one point per fragment, drawn
// into the texel of its stroke's slot. mode 0 / 1: (t, x, y) into a MIN / MAX blended target;
// mode 2: the 15 regressors of refnpr's fragment_regressors (s^0..s^6, s^0..s^3 (x - o_x),
// s^0..s^3 (y - o_y)) in float32 into four additively blended RGBA32F targets. Points blend in
// fragment order (sample order), the order in which refnpr sums.
struct Frag { uint64_t id; float t; float x; float y; uint meta; };

layout(std430, binding = 2) readonly buffer Frags { Frag frags[]; };
layout(std430, binding = 14) readonly buffer State { ivec2 state[]; };

uniform int mode;
uniform int tw;
uniform ivec2 tsize;
uniform sampler2D t_mn;
uniform sampler2D t_mx;

flat out vec4 o0;
flat out vec4 o1;
flat out vec4 o2;
flat out vec4 o3;

void main() {
    int s = state[gl_VertexID].x;
    o0 = o1 = o2 = o3 = vec4(0.0);
    if (s < 0) {
        gl_Position = vec4(4.0, 4.0, 0.0, 1.0);  // outside: lost fragments add nothing
        return;
    }
    Frag f = frags[gl_VertexID];
    ivec2 tp = ivec2(s % tw, s / tw);
    gl_Position = vec4((vec2(tp) + 0.5) / vec2(tsize) * 2.0 - 1.0, 0.0, 1.0);
    if (mode < 2) {
        o0 = vec4(f.t, f.x, f.y, 0.0);
        return;
    }
    precise vec4 mn = texelFetch(t_mn, tp, 0);
    precise vec4 mx = texelFetch(t_mx, tp, 0);
    precise float lo = mn.x;
    precise float hi = mx.x;
    precise float ox = (mn.y + mx.y) * 0.5;
    precise float oy = (mn.z + mx.z) * 0.5;
    precise float half_ = (hi - lo) * 0.5;
    precise float centre = lo + half_;
    precise float s_ = half_ > 0.0 ? fdiv(f.t - centre, half_) : 0.0;
    precise float p0 = 1.0;
    precise float p1 = p0 * s_;
    precise float p2 = p1 * s_;
    precise float p3 = p2 * s_;
    precise float p4 = p3 * s_;
    precise float p5 = p4 * s_;
    precise float p6 = p5 * s_;
    precise float xr = f.x - ox;
    precise float yr = f.y - oy;
    o0 = vec4(p0, p1, p2, p3);
    o1 = vec4(p4, p5, p6, 0.0);
    o2 = vec4(p0 * xr, p1 * xr, p2 * xr, p3 * xr);
    o3 = vec4(p0 * yr, p1 * yr, p2 * yr, p3 * yr);
}
