// The GP's pairwise kernels (optimizers/bo/gp_pairs): closed-form values, and the SSE2 and AVX
// lanes paths against the scalar reference loops, bit for bit, at sizes that leave every kind of
// remainder (tiles, single registers, single points, partial dimension chunks).
#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <cstdint>
#include <cstring>
#include <vector>

#include "common/rng.hpp"
#include "common/simd_path.hpp"
#include "optimizers/bo/gp_pairs.hpp"

namespace {

namespace gpp = dsb::gp_pairs;

// points in the box [0, 1]^d divided by lengthscales spread over [0.05, 20]: values whose
// differences and squares round in every way
std::vector<double> scaled_points(int count, int d, std::uint64_t seed) {
  dsb::Rng rng(seed);
  std::vector<double> lengthscales(d);
  for (double& l : lengthscales) l = 0.05 * std::pow(400.0, rng.uniform());
  std::vector<double> x(static_cast<std::size_t>(count) * d);
  for (int p = 0; p < count; ++p)
    for (int i = 0; i < d; ++i) x[static_cast<std::size_t>(p) * d + i] = rng.uniform() / lengthscales[i];
  return x;  // point p's coordinate i at p d + i: Xs (d x count), column-major
}

std::vector<double> transposed(const std::vector<double>& xs, int n, int d) {
  std::vector<double> xt(xs.size());
  for (int a = 0; a < n; ++a)
    for (int i = 0; i < d; ++i) xt[static_cast<std::size_t>(i) * n + a] = xs[static_cast<std::size_t>(a) * d + i];
  return xt;  // Xt (n x d), column-major
}

std::vector<dsb::SimdPath> lane_paths() {
  std::vector<dsb::SimdPath> paths{dsb::SimdPath::sse2};
  if (dsb::cpu_supports(dsb::SimdPath::avx)) paths.push_back(dsb::SimdPath::avx);
  return paths;
}

const char* name(dsb::SimdPath p) { return dsb::simd_path_name(p); }

TEST(GpPairs, SquaredDistancesAndGradientOfTwoPointsHaveTheirClosedForms) {
  // points (0, 0, 1) and (3, 4, 1): r^2 = 25; with C = 2: gl = (2 * 9, 2 * 16, 0) added to (1, 1, 1)
  const std::vector<double> xs{0, 0, 1, 3, 4, 1};
  const std::vector<double> xt = transposed(xs, 2, 3);
  const std::vector<double> C{0, 2, 0, 0};
  for (dsb::SimdPath p : {dsb::SimdPath::scalar, dsb::SimdPath::sse2}) {
    std::vector<double> R(4, -1.0);
    gpp::squared_distances(xt.data(), 2, 3, R.data(), p);
    EXPECT_EQ(R[1], 25.0) << name(p);
    EXPECT_EQ(R[0], -1.0) << name(p) << ": the diagonal is not written";
    EXPECT_EQ(R[2], -1.0) << name(p) << ": the upper part is not written";
    std::vector<double> gl{1, 1, 1};
    gpp::ard_gradient(xs.data(), 2, 3, C.data(), gl.data(), p);
    EXPECT_EQ(gl, (std::vector<double>{19, 33, 1})) << name(p);
  }
}

// every lanes path against the scalar loops on seeded points and pair weights, bit for bit
void expect_lanes_match_scalar(int n, int d, std::uint64_t seed) {
  const std::vector<double> xs = scaled_points(n, d, seed);
  const std::vector<double> xt = transposed(xs, n, d);
  dsb::Rng rng(seed + 1);
  std::vector<double> C(static_cast<std::size_t>(n) * n);
  for (double& c : C) c = 2.0 * rng.uniform() - 1.0;
  std::vector<double> R_ref(C.size(), 0.0), gl_ref(d, 0.5);
  gpp::squared_distances(xt.data(), n, d, R_ref.data(), dsb::SimdPath::scalar);
  gpp::ard_gradient(xs.data(), n, d, C.data(), gl_ref.data(), dsb::SimdPath::scalar);
  for (dsb::SimdPath p : lane_paths()) {
    std::vector<double> R(C.size(), 0.0), gl(d, 0.5);
    gpp::squared_distances(xt.data(), n, d, R.data(), p);
    gpp::ard_gradient(xs.data(), n, d, C.data(), gl.data(), p);
    EXPECT_EQ(std::memcmp(R.data(), R_ref.data(), R.size() * sizeof(double)), 0)
        << name(p) << " distances, n = " << n << ", d = " << d;
    EXPECT_EQ(std::memcmp(gl.data(), gl_ref.data(), gl.size() * sizeof(double)), 0)
        << name(p) << " gradient, n = " << n << ", d = " << d;
  }
}

TEST(GpPairs, LanesGiveTheScalarBitsAtEverySize) {
  // n: below a register, across tiles with every remainder; d: below, at and across a 32-chunk
  for (int n : {1, 2, 3, 5, 8, 17, 35, 70})
    for (int d : {1, 2, 3, 31, 32, 33, 70}) expect_lanes_match_scalar(n, d, 1000u * n + d);
}

TEST(GpPairs, LanesGiveTheScalarBitsAtARunsSize) {
  // a 400-D GP after a few leaps: every tile full, and a remainder of dimensions (410 = 25 x 16 + 10)
  expect_lanes_match_scalar(150, 410, 99);
}

TEST(GpPairs, ScalarDistancesSumTheDimensionsInOrder) {
  // the order pinned: the squares 1e16, 1, 1 summed from the left give 1e16 (the spacing of doubles
  // at 1e16 is 2, so each 1 is lost to rounding); the ones first would give 1e16 + 2
  const int d = 3;
  const std::vector<double> xs{0, 0, 0, 1e8, 1, 1};
  const std::vector<double> xt = transposed(xs, 2, d);
  for (dsb::SimdPath p : {dsb::SimdPath::scalar, dsb::SimdPath::sse2}) {
    std::vector<double> R(4, 0.0);
    gpp::squared_distances(xt.data(), 2, d, R.data(), p);
    EXPECT_EQ(R[1], 1e16) << name(p);
  }
}

TEST(GpPairs, DefaultPathIsTheWidestItOffersUnderTheCeiling) {
  // the one dispatch of common/simd_path.hpp: AVX exactly where the CPU has it (the widest these
  // loops offer), unless DSB_SIMD asked for a narrower path; the batched exp/log take the same
  EXPECT_EQ(gpp::default_path(), dsb::simd_path({dsb::SimdPath::scalar, dsb::SimdPath::sse2, dsb::SimdPath::avx}));
  const char* forced = std::getenv("DSB_SIMD");
  if (!forced || !*forced) {
    EXPECT_EQ(gpp::default_path(), dsb::cpu_supports(dsb::SimdPath::avx) ? dsb::SimdPath::avx : dsb::SimdPath::sse2);
  } else {
    EXPECT_LE(gpp::default_path(), dsb::simd_ceiling());
  }
}

}  // namespace
