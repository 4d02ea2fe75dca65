// TAMISS common code: 64-bit stroke ids and hashes, double-precision helpers.
// (#version and #extension lines are added by refnpr_glsl/styles/tamiss.py)

const uint64_t M1 = 0x9E3779B97F4A7C15UL;
const uint64_t M2 = 0xBF58476D1CE4E5B9UL;
const uint64_t M3 = 0x94D049BB133111EBUL;
const int KX[7] = int[7](0, 6, 5, 1, 3, 4, 2);
const double INV53 = 1.0LF / 9007199254740992.0LF;
const double LN2 = 0.69314718055994530942LF;
const double PI_D = 3.14159265358979323846LF;

uint64_t splitmix(uint64_t z) {
    z = z + M1;
    z = (z ^ (z >> 30)) * M2;
    z = (z ^ (z >> 27)) * M3;
    return z ^ (z >> 31);
}

// salt * 0x9E3779B97F4A7C15 mod 2^64
uint64_t salt_offset(int salt) { return uint64_t(salt) * M1; }

// refnpr field.hash01: top 53 bits of splitmix64(id + salt * M1), as a double in [0, 1)
double hash01(uint64_t sid, int salt) {
    return double(splitmix(sid + salt_offset(salt)) >> 11) * INV53;
}

// refnpr field.pack_id
uint64_t pack_id(int chart, int layer, int level, int gx, int gy, int r) {
    int64_t v = int64_t(chart) * 4 + int64_t(layer);
    v = v * 16 + int64_t(level);
    v = (v << 22) + int64_t(gx + (1 << 21));
    v = (v << 22) + int64_t(gy + (1 << 21));
    return uint64_t(v * 8 + int64_t(r));
}

int id_level(uint64_t sid) { return int((sid >> 47) & 15UL); }

// refnpr field.key32: top half of splitmix64(id), 0xFFFFFFFF folded to 0xFFFFFFFE
uint key32(uint64_t sid) {
    uint k = uint(splitmix(sid) >> 32);
    return k == 0xFFFFFFFFu ? 0xFFFFFFFEu : k;
}

// Wellons' lowbias32 (refnpr formulas/tamiss/hashing.py)
uint lowbias32(uint x) {
    x ^= x >> 16;
    x *= 0x7FEB352Du;
    x ^= x >> 15;
    x *= 0x846CA68Bu;
    x ^= x >> 16;
    return x;
}

// log2 in double (GLSL has none): frexp, then 2 atanh((m - 1) / (m + 1)) / ln 2
double dlog2(double x) {
    int e;
    double m = frexp(x, e);  // x = m 2^e, m in [0.5, 1)
    if (m < 0.70710678118654752LF) { m *= 2.0LF; e -= 1; }
    double z = (m - 1.0LF) / (m + 1.0LF);
    double z2 = z * z;
    double term = z;
    double acc = 0.0LF;
    for (int k = 0; k < 40; k++) {
        acc += term / double(2 * k + 1);
        term *= z2;
    }
    return double(e) + 2.0LF * acc / LN2;
}

// 2^x in double: ldexp of the integer part, Taylor series of exp(f ln 2)
double dexp2(double x) {
    double fl = floor(x);
    double y = (x - fl) * LN2;
    double term = 1.0LF;
    double acc = 1.0LF;
    for (int k = 1; k < 30; k++) {
        term *= y / double(k);
        acc += term;
    }
    return ldexp(acc, int(fl));
}

// sin in double: reduce to [-pi, pi], Taylor series
double dsin(double x) {
    double tp = 2.0LF * PI_D;
    double r = x - tp * floor(x / tp + 0.5LF);
    double r2 = r * r;
    double term = r;
    double acc = r;
    for (int k = 1; k < 30; k++) {
        term *= -r2 / double((2 * k) * (2 * k + 1));
        acc += term;
    }
    return acc;
}

double dhypot(double a, double b) { return sqrt(a * a + b * b); }

// IEEE float32 division and square root (GLSL allows 2.5 ulp, and drivers multiply by a
// reciprocal): through double, then rounded once to float, as numpy's float32 arithmetic.
float fdiv(float a, float b) { return float(double(a) / double(b)); }
float fsqrt(float a) { return float(sqrt(double(a))); }
