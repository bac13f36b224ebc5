#include "common/det_math.hpp"

#include <immintrin.h>
#include <sleef.h>

// Every function is SLEEF's "cinz" (consistent, no FMA) pure-C scalar variant at 1.0-ulp accuracy
// (u10), except erfc (SLEEF has it only at 1.5 ulp). These are plain C with no CPU dispatch, so a
// given libsleef gives the same bits on every x86-64 CPU.
// exp_batch / log_batch use the cinz SSE2 and AVX variants, which give the same bits (det_math.hpp).
namespace dsb::detmath {

double exp(double x) { return Sleef_cinz_expd1_u10purec(x); }
double expm1(double x) { return Sleef_cinz_expm1d1_u10purec(x); }
double exp2(double x) { return Sleef_cinz_exp2d1_u10purec(x); }
double log(double x) { return Sleef_cinz_logd1_u10purec(x); }
double log1p(double x) { return Sleef_cinz_log1pd1_u10purec(x); }
double log2(double x) { return Sleef_cinz_log2d1_u10purec(x); }
double log10(double x) { return Sleef_cinz_log10d1_u10purec(x); }
double pow(double x, double y) { return Sleef_cinz_powd1_u10purec(x, y); }
double cbrt(double x) { return Sleef_cinz_cbrtd1_u10purec(x); }
double hypot(double x, double y) { return Sleef_cinz_hypotd1_u05purec(x, y); }

double sin(double x) { return Sleef_cinz_sind1_u10purec(x); }
double cos(double x) { return Sleef_cinz_cosd1_u10purec(x); }
void sincos(double x, double* s, double* c) {
  const Sleef_double_2 r = Sleef_cinz_sincosd1_u10purec(x);
  *s = r.x;
  *c = r.y;
}
double tan(double x) { return Sleef_cinz_tand1_u10purec(x); }
double asin(double x) { return Sleef_cinz_asind1_u10purec(x); }
double acos(double x) { return Sleef_cinz_acosd1_u10purec(x); }
double atan(double x) { return Sleef_cinz_atand1_u10purec(x); }
double atan2(double y, double x) { return Sleef_cinz_atan2d1_u10purec(y, x); }

double sinh(double x) { return Sleef_cinz_sinhd1_u10purec(x); }
double cosh(double x) { return Sleef_cinz_coshd1_u10purec(x); }
double tanh(double x) { return Sleef_cinz_tanhd1_u10purec(x); }

double erf(double x) { return Sleef_cinz_erfd1_u10purec(x); }
double erfc(double x) { return Sleef_cinz_erfcd1_u15purec(x); }
double lgamma(double x) { return Sleef_cinz_lgammad1_u10purec(x); }

namespace {

// sleef.h declares its __m256d functions only where the whole file is compiled with -mavx
extern "C" __m256d Sleef_cinz_expd4_u10avx(__m256d);
extern "C" __m256d Sleef_cinz_logd4_u10avx(__m256d);

// Batches: pairs through SLEEF's cinz SSE2 variant, an odd last element through the scalar one;
// on the AVX path quads first through the cinz AVX variant. The AVX calls (arguments in ymm
// registers) sit in functions compiled with target("avx"), which does not enable FMA.
template <class Pair, class Single>
void batch_sse2(const double* x, double* out, std::size_t n, Pair pair, Single single) {
  std::size_t i = 0;
  for (; i + 2 <= n; i += 2) _mm_storeu_pd(out + i, pair(_mm_loadu_pd(x + i)));
  for (; i < n; ++i) out[i] = single(x[i]);
}

void exp_sse2(const double* x, double* out, std::size_t n) {
  batch_sse2(x, out, n, Sleef_cinz_expd2_u10sse2, Sleef_cinz_expd1_u10purec);
}
void log_sse2(const double* x, double* out, std::size_t n) {
  batch_sse2(x, out, n, Sleef_cinz_logd2_u10sse2, Sleef_cinz_logd1_u10purec);
}

[[gnu::target("avx")]] void exp_avx(const double* x, double* out, std::size_t n) {
  std::size_t i = 0;
  for (; i + 4 <= n; i += 4) _mm256_storeu_pd(out + i, Sleef_cinz_expd4_u10avx(_mm256_loadu_pd(x + i)));
  exp_sse2(x + i, out + i, n - i);
}
[[gnu::target("avx")]] void log_avx(const double* x, double* out, std::size_t n) {
  std::size_t i = 0;
  for (; i + 4 <= n; i += 4) _mm256_storeu_pd(out + i, Sleef_cinz_logd4_u10avx(_mm256_loadu_pd(x + i)));
  log_sse2(x + i, out + i, n - i);
}

}  // namespace

void exp_batch(const double* x, double* out, std::size_t n, SimdPath path) {
  (path == SimdPath::avx ? exp_avx : exp_sse2)(x, out, n);
}
void log_batch(const double* x, double* out, std::size_t n, SimdPath path) {
  (path == SimdPath::avx ? log_avx : log_sse2)(x, out, n);
}

// the batches offer SSE2 and AVX (common/simd_path.hpp)
void exp_batch(const double* x, double* out, std::size_t n) {
  exp_batch(x, out, n, simd_path({SimdPath::sse2, SimdPath::avx}));
}
void log_batch(const double* x, double* out, std::size_t n) {
  log_batch(x, out, n, simd_path({SimdPath::sse2, SimdPath::avx}));
}

}  // namespace dsb::detmath
