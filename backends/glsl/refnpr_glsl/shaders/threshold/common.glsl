// threshold style (Veryovka 2002): shared helpers. refnpr: refnpr/formulas/_shading_checks.py,
// refnpr/formulas/threshold/lines.py.
// (real, rvec2, rvec3: see precision.glsl)

// texture levels and tables (offsets in the generated constants)
layout(std430, binding = 0) readonly buffer ThresholdData { float DATA[]; };

const float ONE_BELOW_F = uintBitsToFloat(0x3f7fffffu);     // largest float32 below 1
#if REAL_DOUBLE
const real ONE_BELOW_R = uint64BitsToDouble(0x3FEFFFFFFFFFFFFFul);  // largest float64 below 1
const real TINY_A = 1e-100lf;  // line_coverage: footprints below this are point samples
const real TINY_B = 1e-200lf;
#else
const real ONE_BELOW_R = uintBitsToFloat(0x3f7fffffu);
const real TINY_A = 0.0;  // (1e-100 and 1e-200 underflow in float: only exact zeros)
const real TINY_B = 0.0;
#endif
const float FLT_TINY = 1.17549435e-38;

float frac_f(float x) { return min(x - floor(x), ONE_BELOW_F); }
real frac_r(real x) { return min(x - floor(x), ONE_BELOW_R); }

// floor(s) clipped to [-1100, 1100] (refnpr K_MAX)
int floor_int(float s) { return int(clamp(floor(s), -1100.0, 1100.0)); }

// 2^k exactly (0 or +inf beyond the type's range, as ldexp under/overflows)
real pow2_r(int k) {
#if REAL_DOUBLE
    if (k > 1023) return uint64BitsToDouble(0x7FF0000000000000ul);
    if (k < -1022) return 0.0;
    return uint64BitsToDouble(uint64_t(k + 1023) << 52);
#else
    if (k > 127) return uintBitsToFloat(0x7f800000u);
    if (k < -126) return 0.0;
    return uintBitsToFloat(uint(k + 127) << 23);
#endif
}

// Frac(v 2^k) (eq. 6); a non-finite product is an integer: 0
real scaled_frac_r(real v, int k) {
    real p = v * pow2_r(k);
    if (isinf(p) || isnan(p)) p = 0.0;
    return frac_r(p);
}

// T_n(x, t) of eq. 4, bounded by ceil(x n) / n (eq. 3 for n = 1)
float step_n(float x, float t) {
#if N_STEPS == 1
    return x >= t ? 1.0 : 0.0;
#else
    float xn = x * float(N_STEPS);
    float whole = floor(xn);
    float levels = whole + ((xn - whole >= t) ? 1.0 : 0.0);
    return min(levels, ceil(xn)) / float(N_STEPS);
#endif
}

// eqs. 7-8 with base f(v) = v, v in [0, 1), t in [0, 1]; result in [0, 1)
real multiscale_kernel(real v, real t) {
    real v1 = v < 0.5 ? 2.0 * v : 2.0 * v - 1.0;
    real f;
#if UNIFORM
    real a = (1.0 - t) / (2.0 * (1.0 + t));
    real b = 1.0 - a;
    f = v < a ? v : (v < 0.5 ? 2.0 * v - a : (v < b ? 2.0 * v - b : v));
#else
    f = (1.0 - t) * v + t * v1;
#endif
    return clamp(f, 0.0, ONE_BELOW_R);
}

// eq. 5 with d = 1 / |grad v|: s = -log2(w |(dv/dx, dv/dy)|)
float dyadic_scale_from_gradient(float dx, float dy, float w) {
    float g = max(length(vec2(dx, dy)), FLT_TINY);
    return -(log2(g) + log2(w));
}

// ---- splitmix64 (refnpr/styles/threshold/noise.py, refnpr/formulas/threshold/stipple.py)
const uint64_t M1 = 0x9E3779B97F4A7C15ul;
const uint64_t M2 = 0xBF58476D1CE4E5B9ul;
const uint64_t M3 = 0x94D049BB133111EBul;

uint64_t mix64(uint64_t h) {
    h ^= h >> 30;
    h *= M2;
    h ^= h >> 27;
    h *= M3;
    h ^= h >> 31;
    return h;
}

// (h >> 11) / 2^53 in [0, 1)
real unit64(uint64_t h) { return real(double(h >> 11) / 9007199254740992.0lf); }

// float64 bits with -0.0 folded onto 0.0
uint64_t bits_d(double x) { return x == 0.0lf ? 0ul : doubleBitsToUint64(x); }
