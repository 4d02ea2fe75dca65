// threshold style: the arithmetic of the shader's "real" parts (before the generated constants).
// Precision: "real" (rvec2, rvec3) is float (REAL_DOUBLE 0, the default: what a GPU shader does)
// or double (REAL_DOUBLE 1: refnpr's float64) for the line coordinates, their analytic box
// filter, the noise and stipple lattices and the texture filtering weights; log, exp, atan and
// lighting are float either way (GLSL has no double exp/log/atan). The splitmix64 hashes are
// 64-bit integer arithmetic in both modes and read the float64 bits of exact lattice values.
#if REAL_DOUBLE
#define real double
#define rvec2 dvec2
#define rvec3 dvec3
#else
#define real float
#define rvec2 vec2
#define rvec3 vec3
#endif
