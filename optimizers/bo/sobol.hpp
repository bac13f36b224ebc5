#pragma once
// Own Sobol low-discrepancy sequence (no copied direction-number tables): primitive polynomials
// over GF(2) are enumerated by degree with a primitivity test, and the free initial direction
// numbers m_k (odd, < 2^k) are drawn from a fixed-seed dsb::Rng, so the sequence is the same on
// every machine. Scrambled by a random digital shift (XOR) from the caller's RNG, as a randomized
// QMC sequence. Dimension 1 is the van der Corput sequence.
#include <cstdint>
#include <vector>

#include <Eigen/Dense>

#include "common/rng.hpp"

namespace dsb {

class SobolSequence {
 public:
  // dim in 1..1111; with `scramble`, a digital shift drawn from rng
  SobolSequence(int dim, Rng* scramble = nullptr);
  int dim() const { return dim_; }
  // next point in [0, 1)^dim (Gray-code order, skipping the all-zero first point)
  Eigen::VectorXd next();
  // n points as rows (n x dim)
  Eigen::MatrixXd draw(int n);
  // the digital shift (dim; zeros unscrambled)
  const std::vector<std::uint32_t>& shift() const { return shift_; }

 private:
  int dim_;
  std::vector<std::uint32_t> direction_;  // dim x 32 direction numbers, row-major
  std::vector<std::uint32_t> state_, shift_;
  std::uint32_t index_ = 0;
};

// The first `count` primitive polynomials over GF(2) (0 <= count <= 1110) in the order the
// sequence uses them (degree, then value), as bit masks: bit k is the coefficient of x^k, e.g.
// x^3 + x + 1 = 0b1011.
std::vector<std::uint32_t> primitive_polynomials(int count);

}  // namespace dsb
