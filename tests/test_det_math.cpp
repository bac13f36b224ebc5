// Deterministic elementary functions (common/det_math): accuracy against libm at seeded points,
// exact special values, and the recorded digest of their bits.
#include <gtest/gtest.h>

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <limits>
#include <numbers>
#include <string>
#include <vector>

#include "common/det_math.hpp"
#include "common/rng.hpp"

namespace {

namespace dm = dsb::dm;
constexpr double kInf = std::numeric_limits<double>::infinity();
constexpr int kPoints = 20000;
// the long double reference is itself up to ~2^-11 ulp of double from the exact value
constexpr double kRefSlack = 1e-3;

// |got - ref| in units in the last place of double at ref (ref: the long double libm value,
// about 2^-11 ulp of double from the exact value, so a faithful stand-in for it)
double ulp_error(double got, long double ref) {
  const double r = static_cast<double>(ref);
  if (std::isnan(r)) return std::isnan(got) ? 0.0 : kInf;
  if (std::isinf(r) || r == 0.0) return got == r ? 0.0 : kInf;
  int e = 0;
  (void)std::frexp(r, &e);  // |r| in [2^(e-1), 2^e)
  const long double ulp = std::ldexp(1.0L, std::max(e - 53, -1074));
  return static_cast<double>(std::fabs(static_cast<long double>(got) - ref) / ulp);
}

// how many doubles lie between a and b (0: the same double; 1: neighbours)
std::uint64_t ulp_distance(double a, double b) {
  auto ordered = [](double v) {
    const auto u = std::bit_cast<std::int64_t>(v);
    return u < 0 ? std::numeric_limits<std::int64_t>::min() - u : u;
  };
  const std::int64_t ia = ordered(a), ib = ordered(b);
  return ia > ib ? static_cast<std::uint64_t>(ia - ib) : static_cast<std::uint64_t>(ib - ia);
}

// a point of [lo, hi]: uniform, or log-uniform when both are > 0 and `log_scale` (drawn with
// dm:: so that the points, too, are the same on every CPU)
double draw(dsb::Rng& rng, double lo, double hi, bool log_scale) {
  if (!log_scale) return rng.uniform(lo, hi);
  return dm::exp(rng.uniform(dm::log(lo), dm::log(hi)));
}

struct Unary {
  const char* name;
  double (*det)(double);
  long double (*ref)(long double);
  double (*libm)(double);
  double lo, hi;
  bool log_scale;
  double max_ulp;           // SLEEF's bound against the exact value
  std::uint64_t max_apart;  // against glibc's double function (its own error included)
};

// glibc's own double functions are within 1 ulp of exact for exp, log, pow, sin, cos and
// friends, up to 2-4 for tanh, cbrt, erfc, lgamma (its libm-test-ulps tables; cbrt measured 3 ulp
// off here); the distance to them is therefore bounded by 1 ulp or by 1 + glibc's error.
const std::vector<Unary>& unary_cases() {
  static const std::vector<Unary> cases = {
      {"exp", dm::exp, expl, ::exp, -700.0, 700.0, false, 1.0, 1},
      {"exp (near 0)", dm::exp, expl, ::exp, -5.0, 5.0, false, 1.0, 1},
      {"expm1", dm::expm1, expm1l, ::expm1, -30.0, 30.0, false, 1.0, 1},
      {"expm1 (near 0)", dm::expm1, expm1l, ::expm1, -1e-3, 1e-3, false, 1.0, 1},
      {"exp2", dm::exp2, exp2l, ::exp2, -1000.0, 1000.0, false, 1.0, 1},
      {"log", dm::log, logl, ::log, 1e-300, 1e300, true, 1.0, 1},
      {"log (near 1)", dm::log, logl, ::log, 0.5, 2.0, false, 1.0, 1},
      {"log1p", dm::log1p, log1pl, ::log1p, -0.9, 1e6, false, 1.0, 1},
      {"log1p (near 0)", dm::log1p, log1pl, ::log1p, 1e-12, 1e-3, true, 1.0, 1},
      {"log2", dm::log2, log2l, ::log2, 1e-300, 1e300, true, 1.0, 1},
      {"log10", dm::log10, log10l, ::log10, 1e-300, 1e300, true, 1.0, 2},
      {"cbrt", dm::cbrt, cbrtl, ::cbrt, -1e6, 1e6, false, 1.0, 4},
      {"sin", dm::sin, sinl, ::sin, -10.0, 10.0, false, 1.0, 1},
      {"sin (large)", dm::sin, sinl, ::sin, -1e5, 1e5, false, 1.0, 1},
      {"cos", dm::cos, cosl, ::cos, -10.0, 10.0, false, 1.0, 1},
      {"cos (large)", dm::cos, cosl, ::cos, -1e5, 1e5, false, 1.0, 1},
      {"tan", dm::tan, tanl, ::tan, -10.0, 10.0, false, 1.0, 1},
      {"asin", dm::asin, asinl, ::asin, -1.0, 1.0, false, 1.0, 1},
      {"acos", dm::acos, acosl, ::acos, -1.0, 1.0, false, 1.0, 1},
      {"atan", dm::atan, atanl, ::atan, -1e3, 1e3, false, 1.0, 1},
      {"sinh", dm::sinh, sinhl, ::sinh, -20.0, 20.0, false, 1.0, 2},
      {"cosh", dm::cosh, coshl, ::cosh, -20.0, 20.0, false, 1.0, 2},
      {"tanh", dm::tanh, tanhl, ::tanh, -20.0, 20.0, false, 1.0, 2},
      {"erf", dm::erf, erfl, ::erf, -6.0, 6.0, false, 1.0, 1},
      {"erfc", dm::erfc, erfcl, ::erfc, -6.0, 26.0, false, 1.5, 3},
      {"lgamma", dm::lgamma, lgammal, ::lgamma, 1e-3, 1e3, true, 1.0, 3},
  };
  return cases;
}

// Every function at kPoints seeded points: within its ulp bound of the exact value and within
// max_apart doubles of glibc's result. Prints the worst errors seen.
TEST(DetMath, UnaryFunctionsMatchLibm) {
  for (const Unary& c : unary_cases()) {
    SCOPED_TRACE(c.name);
    dsb::Rng rng(dsb::fnv1a64(c.name));
    double worst = 0.0;
    std::uint64_t worst_apart = 0;
    for (int k = 0; k < kPoints; ++k) {
      const double x = draw(rng, c.lo, c.hi, c.log_scale);
      const double got = c.det(x);
      const double err = ulp_error(got, c.ref(x));
      const std::uint64_t apart = ulp_distance(got, c.libm(x));
      worst = std::max(worst, err);
      worst_apart = std::max(worst_apart, apart);
      if (err > c.max_ulp + kRefSlack || apart > c.max_apart) {
        ADD_FAILURE() << c.name << "(" << std::hexfloat << x << ") = " << got << ", error " << std::defaultfloat << err
                      << " ulp, " << apart << " doubles from libm";
        break;
      }
    }
    std::printf("[ info     ] %-15s worst %.3f ulp, at most %llu doubles from glibc\n", c.name, worst,
                static_cast<unsigned long long>(worst_apart));
  }
}

TEST(DetMath, BinaryFunctionsMatchLibm) {
  struct Binary {
    const char* name;
    double (*det)(double, double);
    long double (*ref)(long double, long double);
    double (*libm)(double, double);
    double max_ulp;
  };
  for (const Binary& c : {Binary{"pow", dm::pow, powl, ::pow, 1.0}, Binary{"atan2", dm::atan2, atan2l, ::atan2, 1.0},
                          Binary{"hypot", dm::hypot, hypotl, ::hypot, 0.5}}) {
    SCOPED_TRACE(c.name);
    dsb::Rng rng(dsb::fnv1a64(c.name));
    double worst = 0.0;
    for (int k = 0; k < kPoints; ++k) {
      double x, y;
      if (std::string(c.name) == "pow") {
        // positive bases over many magnitudes; every 4th point a negative base with an integer
        // exponent (the only real-valued case)
        x = draw(rng, 1e-3, 1e3, true);
        y = rng.uniform(-40.0, 40.0);
        if (k % 4 == 0) {
          x = -x;
          y = std::round(y);
        }
      } else {
        x = rng.uniform(-10.0, 10.0);
        y = rng.uniform(-10.0, 10.0);
      }
      const double got = c.det(x, y);
      const double err = ulp_error(got, c.ref(x, y));
      worst = std::max(worst, err);
      if (err > c.max_ulp + kRefSlack || ulp_distance(got, c.libm(x, y)) > 1) {
        ADD_FAILURE() << c.name << "(" << std::hexfloat << x << ", " << y << ") = " << got << std::defaultfloat
                      << ", error " << err << " ulp";
        break;
      }
    }
    std::printf("[ info     ] %-15s worst %.3f ulp\n", c.name, worst);
  }
}

// sincos: both values within 1 ulp (they need not be the bits of sin and cos: they differ by one
// ulp at some points).
TEST(DetMath, SincosWithinOneUlp) {
  dsb::Rng rng(7);
  double worst = 0.0;
  for (int k = 0; k < kPoints; ++k) {
    const double x = rng.uniform(-100.0, 100.0);
    double s = 0.0, c = 0.0;
    dm::sincos(x, &s, &c);
    worst = std::max({worst, ulp_error(s, sinl(x)), ulp_error(c, cosl(x))});
    ASSERT_LE(worst, 1.0 + kRefSlack) << "at x = " << std::hexfloat << x;
  }
  std::printf("[ info     ] %-15s worst %.3f ulp\n", "sincos", worst);
}

TEST(DetMath, ExactSpecialValues) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  EXPECT_EQ(dm::exp(0.0), 1.0);
  EXPECT_EQ(dm::exp(-kInf), 0.0);
  EXPECT_EQ(dm::exp(kInf), kInf);
  EXPECT_EQ(dm::exp(710.0), kInf);  // overflows
  EXPECT_EQ(dm::exp(-746.0), 0.0);  // underflows
  EXPECT_EQ(dm::expm1(0.0), 0.0);
  EXPECT_EQ(dm::expm1(-kInf), -1.0);
  EXPECT_EQ(dm::exp2(10.0), 1024.0);
  EXPECT_EQ(dm::log(1.0), 0.0);
  EXPECT_EQ(dm::log(0.0), -kInf);
  EXPECT_EQ(dm::log(kInf), kInf);
  EXPECT_TRUE(std::isnan(dm::log(-1.0)));
  EXPECT_EQ(dm::log1p(0.0), 0.0);
  EXPECT_EQ(dm::log1p(-1.0), -kInf);
  EXPECT_EQ(dm::log2(1024.0), 10.0);
  EXPECT_EQ(dm::log10(1000.0), 3.0);
  EXPECT_EQ(dm::pow(2.0, 10.0), 1024.0);
  EXPECT_EQ(dm::pow(10.0, 3.0), 1000.0);
  EXPECT_EQ(dm::pow(-2.0, 3.0), -8.0);
  EXPECT_EQ(dm::pow(0.3, 0.0), 1.0);
  EXPECT_EQ(dm::pow(nan, 0.0), 1.0);
  EXPECT_EQ(dm::pow(0.0, -1.0), kInf);
  EXPECT_TRUE(std::isnan(dm::pow(-8.0, 1.0 / 3.0)));
  EXPECT_EQ(dm::cbrt(-27.0), -3.0);
  EXPECT_EQ(dm::hypot(3.0, 4.0), 5.0);
  EXPECT_EQ(dm::hypot(kInf, nan), kInf);
  EXPECT_EQ(dm::sin(0.0), 0.0);
  EXPECT_TRUE(std::signbit(dm::sin(-0.0)));
  EXPECT_EQ(dm::cos(0.0), 1.0);
  EXPECT_TRUE(std::isnan(dm::sin(kInf)));
  EXPECT_TRUE(std::isnan(dm::cos(nan)));
  EXPECT_EQ(dm::tan(0.0), 0.0);
  EXPECT_EQ(dm::atan2(0.0, -1.0), std::numbers::pi);
  EXPECT_EQ(dm::atan2(1.0, 0.0), std::numbers::pi / 2.0);
  EXPECT_EQ(dm::atan2(0.0, 1.0), 0.0);
  EXPECT_EQ(dm::asin(1.0), std::numbers::pi / 2.0);
  EXPECT_EQ(dm::acos(-1.0), std::numbers::pi);
  EXPECT_EQ(dm::atan(kInf), std::numbers::pi / 2.0);
  EXPECT_EQ(dm::tanh(0.0), 0.0);
  EXPECT_EQ(dm::tanh(kInf), 1.0);
  EXPECT_EQ(dm::tanh(-kInf), -1.0);
  EXPECT_EQ(dm::sinh(0.0), 0.0);
  EXPECT_EQ(dm::cosh(0.0), 1.0);
  EXPECT_EQ(dm::erf(0.0), 0.0);
  EXPECT_EQ(dm::erf(kInf), 1.0);
  EXPECT_EQ(dm::erfc(0.0), 1.0);
  EXPECT_EQ(dm::lgamma(1.0), 0.0);
  EXPECT_EQ(dm::lgamma(2.0), 0.0);
}

TEST(DetMath, BatchesGiveTheScalarBits) {
  // the dispatched path (below: each path forced): odd lengths exercise the tails, special values
  // and wide ranges the vector lanes
  dsb::Rng rng(77);
  std::vector<double> x = {0.0,    -0.0,   1.0,    -1.0, kInf, -kInf, std::numeric_limits<double>::quiet_NaN(),
                           1e-310, 709.78, -745.2, 1e300};
  for (int i = 0; i < 100001; ++i) x.push_back(rng.uniform(-50.0, 50.0) * (i % 3 == 0 ? 1e-6 : 1.0));
  std::vector<double> positive(x.size());
  for (std::size_t i = 0; i < x.size(); ++i) positive[i] = std::abs(x[i]) * (1.0 + i % 7);
  std::vector<double> out(x.size());
  dm::exp_batch(x.data(), out.data(), x.size());
  for (std::size_t i = 0; i < x.size(); ++i)
    ASSERT_EQ(std::bit_cast<std::uint64_t>(out[i]), std::bit_cast<std::uint64_t>(dm::exp(x[i]))) << "exp " << x[i];
  dm::log_batch(positive.data(), out.data(), positive.size());
  for (std::size_t i = 0; i < x.size(); ++i)
    ASSERT_EQ(std::bit_cast<std::uint64_t>(out[i]), std::bit_cast<std::uint64_t>(dm::log(positive[i])))
        << "log " << positive[i];
}

// Arguments for the batch paths: every special value (zeros, infinities, NaNs of both signs,
// denormals, the extremes, the overflow and underflow edges of exp), then seeded draws: exp's and
// log's working ranges, tiny and huge magnitudes, denormals, and arbitrary bit patterns (every
// exponent, NaN payloads included).
std::vector<double> batch_arguments(std::size_t count) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const double dmin = std::numeric_limits<double>::denorm_min();
  const double nmin = std::numeric_limits<double>::min();
  const double dmax = std::numeric_limits<double>::max();
  const double eps = std::numeric_limits<double>::epsilon();
  std::vector<double> x = {0.0,       -0.0,      1.0,         -1.0,     kInf,     -kInf,   nan,       -nan,   dmin,
                           -dmin,     nmin,      nmin - dmin, dmax,     -dmax,    1e-310,  1e300,     0.5,    2.0,
                           1.0 - eps, 1.0 + eps, 709.78,      709.7827, 709.7828, -708.39, -745.1332, -745.2, -746.0};
  dsb::Rng rng(20240612);
  while (x.size() < count) {
    double v = 0.0;
    switch (x.size() % 8) {
      case 0: v = rng.uniform(-750.0, 750.0); break;
      case 1: v = rng.uniform(-1.0, 1.0); break;
      case 2: v = rng.uniform(0.0, 50.0); break;
      case 3: v = rng.uniform(0.5, 2.0); break;
      case 4:  // any magnitude from denormal to huge
        v = std::ldexp(rng.uniform(0.5, 1.0), static_cast<int>(rng.below(2100)) - 1074);
        break;
      case 5: v = std::bit_cast<double>(rng.next_u64() >> 12); break;  // a denormal (or zero)
      default: v = std::bit_cast<double>(rng.next_u64()); break;       // any double, NaNs too
    }
    x.push_back(rng.below(4) == 0 ? -v : v);
  }
  return x;
}

// f_batch through `path` against the scalar f, bit for bit: on `count` arguments at once, then
// every length 1..17 at four starting offsets (every tail and lane position of the chunks)
using BatchFn = void (*)(const double*, double*, std::size_t, dsb::SimdPath);
void expect_scalar_bits(const char* name, BatchFn batch, double (*scalar)(double), dsb::SimdPath path,
                        std::size_t count) {
  SCOPED_TRACE(name);
  const std::vector<double> x = batch_arguments(count);
  std::vector<double> want(x.size()), got(x.size());
  for (std::size_t i = 0; i < x.size(); ++i) want[i] = scalar(x[i]);
  batch(x.data(), got.data(), x.size(), path);
  for (std::size_t i = 0; i < x.size(); ++i)
    ASSERT_EQ(std::bit_cast<std::uint64_t>(got[i]), std::bit_cast<std::uint64_t>(want[i]))
        << name << "(" << std::hexfloat << x[i] << ") at " << std::dec << i;
  for (std::size_t offset = 0; offset < 4; ++offset)
    for (std::size_t len = 1; len <= 17; ++len) {
      std::vector<double> part(len);
      batch(x.data() + offset, part.data(), len, path);
      EXPECT_EQ(0, std::memcmp(part.data(), want.data() + offset, len * sizeof(double)))
          << name << ": length " << len << " at offset " << offset;
    }
}

constexpr std::size_t kBatchArguments = std::size_t{1} << 21;

TEST(DetMath, Sse2BatchesGiveTheScalarBits) {
  expect_scalar_bits("exp", dm::exp_batch, dm::exp, dsb::SimdPath::sse2, kBatchArguments);
  expect_scalar_bits("log", dm::log_batch, dm::log, dsb::SimdPath::sse2, kBatchArguments);
}

TEST(DetMath, AvxBatchesGiveTheScalarBits) {
  if (!dsb::cpu_supports(dsb::SimdPath::avx)) GTEST_SKIP() << "this CPU has no AVX: only the SSE2 path runs here";
  expect_scalar_bits("exp", dm::exp_batch, dm::exp, dsb::SimdPath::avx, kBatchArguments);
  expect_scalar_bits("log", dm::log_batch, dm::log, dsb::SimdPath::avx, kBatchArguments);
}

// FNV-1a over the bits of every function at seeded points. The digest below was recorded with
// Debian 12's libsleef 3.5.1; it is the same on every x86-64 CPU. If it changes, the SLEEF
// library gives other bits (another version or build), and results recorded with the old one
// (data/baselines) will not reproduce with this build.
TEST(DetMath, BitsMatchTheRecordedDigest) {
  std::uint64_t h = 0xcbf29ce484222325ULL;
  auto mix = [&h](double v) {
    std::uint64_t u = std::bit_cast<std::uint64_t>(v);
    for (int b = 0; b < 8; ++b, u >>= 8) {
      h ^= u & 0xff;
      h *= 0x100000001b3ULL;
    }
  };
  for (const Unary& c : unary_cases()) {
    dsb::Rng rng(dsb::fnv1a64(c.name) + 1);
    for (int k = 0; k < 1000; ++k) mix(c.det(draw(rng, c.lo, c.hi, c.log_scale)));
  }
  dsb::Rng rng(99);
  for (int k = 0; k < 1000; ++k) {
    const double x = rng.uniform(0.01, 10.0), y = rng.uniform(-10.0, 10.0);
    mix(dm::pow(x, y));
    mix(dm::atan2(y, x - 5.0));
    mix(dm::hypot(x, y));
  }
  char hex[17];
  std::snprintf(hex, sizeof hex, "%016llx", static_cast<unsigned long long>(h));
  std::printf("[ info     ] det_math digest %s\n", hex);
  EXPECT_EQ(std::string(hex), "c461891640d86931");
}

}  // namespace
