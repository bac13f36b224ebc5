// Sobol sequence: van der Corput first dimension, the known primitive polynomials, 1-D
// stratification of aligned blocks of 2^k points, the unit box, determinism, 400- and
// 1111-dimensional sequences, and a lower discrepancy than i.i.d. uniforms.
#include "optimizers/bo/sobol.hpp"

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdint>
#include <stdexcept>
#include <vector>

#include <gtest/gtest.h>

namespace {

using dsb::Rng;
using dsb::SobolSequence;

bool in_unit_box(const Eigen::MatrixXd& P) { return (P.array() >= 0.0).all() && (P.array() < 1.0).all(); }

// counts of the points of rows [first, first + count) of P in the 2^k intervals of column j
std::vector<int> strata(const Eigen::MatrixXd& P, int j, int first, int count, int k) {
  std::vector<int> c(std::size_t{1} << k, 0);
  for (int i = first; i < first + count; ++i) ++c[static_cast<std::size_t>(std::ldexp(P(i, j), k))];
  return c;
}

// max over the boxes [0, a) x [0, b), a, b in {1/64, ..., 1}, of |fraction inside - a b|
double star_discrepancy_proxy(const Eigen::MatrixXd& P) {
  double worst = 0.0;
  for (int ia = 1; ia <= 64; ++ia)
    for (int ib = 1; ib <= 64; ++ib) {
      const double a = ia / 64.0, b = ib / 64.0;
      int inside = 0;
      for (Eigen::Index i = 0; i < P.rows(); ++i) inside += (P(i, 0) < a && P(i, 1) < b) ? 1 : 0;
      worst = std::max(worst, std::abs(static_cast<double>(inside) / P.rows() - a * b));
    }
  return worst;
}

// ---------------------------------------------------------------------------------------------
// construction

TEST(Sobol, FirstDimensionIsVanDerCorputInGrayCodeOrder) {
  // Gray-code order with the origin skipped: x_k has the bits of k ^ (k >> 1) reversed
  const double expected[] = {0.5, 0.75, 0.25, 0.375, 0.875, 0.625, 0.125, 0.1875, 0.6875, 0.9375, 0.4375};
  SobolSequence one(1);
  SobolSequence many(9);
  for (double e : expected) {
    EXPECT_EQ(one.next()[0], e);
    EXPECT_EQ(many.next()[0], e);
  }
}

TEST(Sobol, SecondDimensionIsTheStandardOne) {
  // polynomial x + 1 forces m_1 = 1 and v_i = v_(i-1) ^ (v_(i-1) >> 1): 0.5, 0.75, 0.625, ...
  const double expected[] = {0.5, 0.25, 0.75, 0.375, 0.875, 0.125, 0.625, 0.3125};
  SobolSequence s(2);
  for (double e : expected) EXPECT_EQ(s.next()[1], e);
}

TEST(Sobol, PrimitivePolynomialsOfDegreeOneToFiveAreTheKnownOnes) {
  // x+1; x^2+x+1; x^3+x+1, x^3+x^2+1; x^4+x+1, x^4+x^3+1; the six of degree 5
  const std::vector<std::uint32_t> known = {0b11,     0b111,    0b1011,   0b1101,   0b10011,  0b11001,
                                            0b100101, 0b101001, 0b101111, 0b110111, 0b111011, 0b111101};
  EXPECT_EQ(dsb::primitive_polynomials(12), known);
  // counts per degree 1..13 are phi(2^k - 1) / k; all 1110 reach exactly degree 13
  const auto all = dsb::primitive_polynomials(1110);
  std::vector<int> per_degree(14, 0);
  for (std::uint32_t p : all) ++per_degree[std::bit_width(p) - 1];
  EXPECT_EQ(per_degree, (std::vector<int>{0, 1, 1, 2, 2, 6, 6, 18, 16, 48, 60, 176, 144, 630}));
  EXPECT_TRUE(std::is_sorted(all.begin(), all.end()));
  EXPECT_THROW(dsb::primitive_polynomials(1111), std::invalid_argument);
}

TEST(Sobol, RejectsBadDimension) {
  EXPECT_THROW(SobolSequence(0), std::invalid_argument);
  EXPECT_THROW(SobolSequence(1112), std::invalid_argument);
}

// ---------------------------------------------------------------------------------------------
// point-set properties

TEST(Sobol, PointsLieInTheUnitBox) {
  for (int dim = 1; dim <= 8; ++dim) {
    Rng rng(100 + dim);
    EXPECT_TRUE(in_unit_box(SobolSequence(dim).draw(5000))) << dim;
    EXPECT_TRUE(in_unit_box(SobolSequence(dim, &rng).draw(5000))) << dim;
  }
}

// Every 1-D projection is a (0,1)-sequence: the Gray-code indices [m 2^k, (m+1) 2^k) hit each of
// the 2^k intervals once. Because the origin (index 0) is skipped, the first 2^k points emitted
// are NOT such a block (they end with index 2^k); so the first 2^k - 1 points hit distinct
// intervals, and the next 2^k points (indices 2^k .. 2^(k+1) - 1) hit every interval exactly once.
// A digital shift permutes the intervals, so both hold scrambled too.
TEST(Sobol, OneDimensionalProjectionsAreStratified) {
  for (int scrambled = 0; scrambled < 2; ++scrambled) {
    Rng rng(7);
    SobolSequence seq(8, scrambled ? &rng : nullptr);
    const Eigen::MatrixXd P = seq.draw(2047);
    for (int k = 1; k <= 10; ++k) {
      const int m = 1 << k;
      for (int j = 0; j < 8; ++j) {
        const auto head = strata(P, j, 0, m - 1, k);
        EXPECT_EQ(*std::max_element(head.begin(), head.end()), 1) << "k " << k << " dim " << j;
        const auto block = strata(P, j, m - 1, m, k);
        EXPECT_TRUE(std::all_of(block.begin(), block.end(), [](int c) { return c == 1; }))
            << "k " << k << " dim " << j << " scrambled " << scrambled;
      }
    }
  }
}

// (0,m,2)-net of the first two dimensions: every elementary box of area 2^-6 holds exactly one
// of the 64 points with Gray indices 64..127
TEST(Sobol, FirstTwoDimensionsFormANet) {
  const Eigen::MatrixXd P = SobolSequence(2).draw(127);
  for (int a = 0; a <= 6; ++a) {
    std::vector<int> c(64, 0);
    for (int i = 63; i < 127; ++i) {
      const int u = static_cast<int>(std::ldexp(P(i, 0), a)), v = static_cast<int>(std::ldexp(P(i, 1), 6 - a));
      ++c[(u << (6 - a)) + v];
    }
    EXPECT_TRUE(std::all_of(c.begin(), c.end(), [](int x) { return x == 1; })) << "a " << a;
  }
}

TEST(Sobol, SameSeedSameSequenceDifferentSeedDifferent) {
  Rng r1(42), r2(42), r3(43);
  const Eigen::MatrixXd a = SobolSequence(5, &r1).draw(300);
  const Eigen::MatrixXd b = SobolSequence(5, &r2).draw(300);
  const Eigen::MatrixXd c = SobolSequence(5, &r3).draw(300);
  EXPECT_TRUE((a.array() == b.array()).all());
  EXPECT_GT((a - c).cwiseAbs().maxCoeff(), 0.1);
  // unscrambled sequences do not depend on any caller state
  EXPECT_TRUE((SobolSequence(5).draw(300).array() == SobolSequence(5).draw(300).array()).all());
  // draw(n) equals n calls of next()
  Rng r4(42);
  SobolSequence s(5, &r4);
  for (int i = 0; i < 300; ++i) EXPECT_TRUE((s.next().transpose().array() == a.row(i).array()).all());
}

TEST(Sobol, HighDimensionalSequences) {
  for (int dim : {400, 1111}) {
    Rng rng(dim);
    const Eigen::MatrixXd P = SobolSequence(dim).draw(256);
    const Eigen::MatrixXd Q = SobolSequence(dim, &rng).draw(256);
    EXPECT_EQ(P.cols(), dim);
    EXPECT_TRUE(in_unit_box(P));
    EXPECT_TRUE(in_unit_box(Q));
    // every coordinate is a valid (0,1)-sequence: Gray indices 128..255 fill the 128 intervals
    int bad = 0;
    for (int j = 0; j < dim; ++j) {
      const auto block = strata(P, j, 127, 128, 7);
      bad += std::all_of(block.begin(), block.end(), [](int c) { return c == 1; }) ? 0 : 1;
    }
    EXPECT_EQ(bad, 0) << dim;
  }
  // a lower dimension is a prefix of a higher one
  const Eigen::MatrixXd low = SobolSequence(400).draw(64);
  const Eigen::MatrixXd high = SobolSequence(1111).draw(64);
  EXPECT_TRUE((low.array() == high.leftCols(400).array()).all());
}

TEST(Sobol, LowerDiscrepancyThanUniformRandom) {
  Rng rng(11), shift(12);
  const Eigen::MatrixXd sobol = SobolSequence(2).draw(1024);
  const Eigen::MatrixXd shifted = SobolSequence(2, &shift).draw(1024);
  Eigen::MatrixXd random(1024, 2);
  for (Eigen::Index i = 0; i < random.rows(); ++i)
    for (int j = 0; j < 2; ++j) random(i, j) = rng.uniform();
  const double ds = star_discrepancy_proxy(sobol), dh = star_discrepancy_proxy(shifted),
               dr = star_discrepancy_proxy(random);
  RecordProperty("discrepancy_sobol", std::to_string(ds));
  RecordProperty("discrepancy_shifted", std::to_string(dh));
  RecordProperty("discrepancy_random", std::to_string(dr));
  EXPECT_LT(ds, 0.005);
  EXPECT_LT(dh, 0.005);
  EXPECT_GT(dr, 2.0 * std::max(ds, dh));
}

}  // namespace
