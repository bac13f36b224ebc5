#pragma once
// Deterministic elementary functions: the same bits on every x86-64 CPU.
//
// glibc's libm picks its exp/log/pow/sin/cos/tan/atan variants by CPU feature (FMA, AVX2,
// AVX-512) at load time, so the same binary gives results that differ in the last bit between
// machines, and an optimizer run then diverges. Every elementary function that a stored result
// depends on (envs, optimizers, the RNG) goes through these instead: SLEEF's "cinz" pure-C scalar
// functions (Debian's libsleef-dev), which use no FMA and no CPU dispatch (the batches below pick
// a vector width by CPU, among variants that give the scalar bits). Accuracy: 1.0 ulp
// (SLEEF's u10 bound; tests/test_det_math.cpp checks it against libm). Cost per call against
// glibc's: exp about 2x, sin/cos 2-2.5x, log 4x, pow 5-6x (tests/perf/bench_det_math.cpp).
// sqrt, fabs, floor, round, fmin/fmax and + - * / are exact in IEEE 754 and need nothing here.
// Not covered: NLopt's own libm calls (see optimizers/nlopt_adapters.hpp) and reference/.
//
// Use: `dm::exp(x)` (dm is an alias of dsb::detmath, declared below).
#include <cstddef>

#include "common/simd_path.hpp"

namespace dsb {
namespace detmath {

double exp(double x);
double expm1(double x);  // exp(x) - 1, accurate near 0
double exp2(double x);
double log(double x);
double log1p(double x);  // log(1 + x), accurate near 0
double log2(double x);
double log10(double x);
double pow(double x, double y);
double cbrt(double x);
double hypot(double x, double y);

double sin(double x);
double cos(double x);
// both at the cost of about one; may differ from sin(x), cos(x) in the last bit
void sincos(double x, double* s, double* c);
double tan(double x);
double asin(double x);
double acos(double x);
double atan(double x);
double atan2(double y, double x);

double sinh(double x);
double cosh(double x);
double tanh(double x);

double erf(double x);
double erfc(double x);
double lgamma(double x);  // log |Gamma(x)|; 1 ulp for x > 0

// Batches: out[i] = f(x[i]) for i < n, bit for bit what the scalar function gives. Dispatched
// once per process (common/simd_path.hpp): where the CPU has AVX, four at a time through SLEEF's
// cinz AVX variant (Sleef_cinz_expd4_u10avx, ..._logd4_u10avx), then a pair through the cinz SSE2
// variant and a last odd one through the scalar function; without AVX, pairs and the scalar one.
// The bits cannot differ between the paths: SLEEF's cinz ("consistent") variants are built to
// give the same results in every vector width, computing the same operations in the same order
// without FMA, from IEEE 754 correctly rounded + - * / (a lane of a packed instruction rounds
// exactly like the scalar one), integer and bit operations and selects; the AVX caller is
// compiled without FMA too. tests/test_det_math.cpp checks both paths against the scalar
// functions on 2 million arguments (special values, denormals, NaN payloads included). Per value, one 2.6 GHz Sapphire Rapids core,
// n = 192: exp 9.4 ns scalar, 2.9 ns SSE2, 1.6 ns AVX (1.8x SSE2); log 13.8, 7.1 and 3.8 ns (1.9x).
void exp_batch(const double* x, double* out, std::size_t n);
void log_batch(const double* x, double* out, std::size_t n);
// The same through the given path, for tests and benchmarks: SimdPath::avx (which requires
// cpu_supports(SimdPath::avx)), any other SSE2.
void exp_batch(const double* x, double* out, std::size_t n, SimdPath path);
void log_batch(const double* x, double* out, std::size_t n, SimdPath path);

}  // namespace detmath

namespace dm = detmath;

}  // namespace dsb
