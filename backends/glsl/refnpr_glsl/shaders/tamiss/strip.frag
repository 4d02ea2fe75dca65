// Anti-aliased coverage of one stroke piece at one sample (refnpr _kernels.raster_strips): the
// fraction of aa x aa sub-samples inside ANY of the strip's 2 (K - 1) triangles (union), times
// opacity and the brush (bilinear at the barycentric (t, across) of the triangle the sample
// centre is most inside). Output premultiplied (colour a, a), blended with "over" (ONE,
// ONE_MINUS_SRC_ALPHA) in piece order.
struct Piece { uint64_t id; int valid; int level; ivec4 bbox; vec4 color; };
layout(std430, binding = 18) readonly buffer Pieces { Piece pieces[]; };
layout(std430, binding = 19) readonly buffer Verts { double verts[]; };

uniform int K;
uniform int aa;
uniform int wrap_t;
uniform float opacity;
uniform sampler2D t_brush;

flat in int piece;
layout(location = 0) out vec4 outc;

double edge(dvec2 a, dvec2 b, dvec2 p) { return (b.x - a.x) * (p.y - a.y) - (b.y - a.y) * (p.x - a.x); }

dvec2 L(int k) { uint o = (uint(piece) * uint(K) + uint(k)) * 5u; return dvec2(verts[o], verts[o + 1u]); }
dvec2 R(int k) { uint o = (uint(piece) * uint(K) + uint(k)) * 5u; return dvec2(verts[o + 2u], verts[o + 3u]); }
double T(int k) { uint o = (uint(piece) * uint(K) + uint(k)) * 5u; return verts[o + 4u]; }

void main() {
    ivec2 px = ivec2(gl_FragCoord.xy);
    Piece pe = pieces[piece];
    double x = double(px.x), y = double(px.y);
    double inv = 1.0LF / double(aa);
    uint64_t mask = 0UL;
    double best = -1e300LF;
    double bu = 0.0LF, bv = 0.0LF;
    for (int seg = 0; seg < K - 1; seg++) {
        for (int tri = 0; tri < 2; tri++) {
            dvec2 a, b, c;
            double ta, tb, tc, va, vb, vc;
            if (tri == 0) {
                a = L(seg); b = R(seg); c = L(seg + 1);
                ta = T(seg); tb = T(seg); tc = T(seg + 1);
                va = 0.0LF; vb = 1.0LF; vc = 0.0LF;
            } else {
                a = R(seg); b = R(seg + 1); c = L(seg + 1);
                ta = T(seg); tb = T(seg + 1); tc = T(seg + 1);
                va = 1.0LF; vb = 1.0LF; vc = 0.0LF;
            }
            double area = edge(a, b, c);
            if (abs(area) < 1e-12LF) continue;
            double sgn = area > 0.0LF ? 1.0LF : -1.0LF;
            if (x < floor(min(a.x, min(b.x, c.x))) || x > floor(max(a.x, max(b.x, c.x)))) continue;
            if (y < floor(min(a.y, min(b.y, c.y))) || y > floor(max(a.y, max(b.y, c.y)))) continue;
            for (int sj = 0; sj < aa; sj++) {
                double py = y + (double(sj) + 0.5LF) * inv;
                for (int si = 0; si < aa; si++) {
                    double pxs = x + (double(si) + 0.5LF) * inv;
                    dvec2 p = dvec2(pxs, py);
                    double e0 = edge(b, c, p) * sgn;
                    double e1 = edge(c, a, p) * sgn;
                    double e2 = edge(a, b, p) * sgn;
                    if (e0 >= 0.0LF && e1 >= 0.0LF && e2 >= 0.0LF)
                        mask |= 1UL << uint(sj * aa + si);
                }
            }
            dvec2 pc = dvec2(x + 0.5LF, y + 0.5LF);
            double w0 = edge(b, c, pc) / area;
            double w1 = edge(c, a, pc) / area;
            double w2 = 1.0LF - w0 - w1;
            double m = min(w0, min(w1, w2));
            if (m > best) {
                best = m;
                double w0c = max(w0, 0.0LF), w1c = max(w1, 0.0LF), w2c = max(w2, 0.0LF);
                double ws = w0c + w1c + w2c;
                bu = (w0c * ta + w1c * tb + w2c * tc) / ws;
                bv = (w0c * va + w1c * vb + w2c * vc) / ws;
            }
        }
    }
    if (mask == 0UL) discard;
    double cov = double(bitCount(unpackUint2x32(mask).x) + bitCount(unpackUint2x32(mask).y))
                 / double(aa * aa);
    ivec2 bs = textureSize(t_brush, 0);
    int wb = bs.x, hb = bs.y;
    double fu = bu * double(wb) - 0.5LF;
    double fv = min(max(bv, 0.0LF), 1.0LF) * double(hb) - 0.5LF;
    int iu = int(floor(fu)), iv = int(floor(fv));
    double au = fu - double(iu), av = fv - double(iv);
    double val = 0.0LF;
    for (int dv = 0; dv < 2; dv++) {
        int rr = clamp(iv + dv, 0, hb - 1);
        double wv = dv == 1 ? av : 1.0LF - av;
        for (int du = 0; du < 2; du++) {
            int cc = iu + du;
            if (wrap_t != 0) { cc = cc % wb; if (cc < 0) cc += wb; }
            else cc = clamp(cc, 0, wb - 1);
            double wu = du == 1 ? au : 1.0LF - au;
            val += wu * wv * double(texelFetch(t_brush, ivec2(cc, rr), 0).r);
        }
    }
    double a_ = cov * double(opacity) * val;
    float af = float(a_);
    outc = vec4(pe.color.rgb * af, af);
}
