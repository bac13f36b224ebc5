// Own Sobol sequence. Construction (Bratley and Fox 1988; Joe and Kuo 2003 for
// the recurrence in 32-bit fixed point), with our own direction numbers:
// - dimension 1: v_i = 2^-i (van der Corput);
// - dimension j >= 2: the (j-1)-th primitive polynomial over GF(2), in order of degree then value,
//   x^s + a_1 x^(s-1) + ... + a_(s-1) x + 1; initial m_1..m_s odd with m_i < 2^i, drawn from
//   dsb::Rng(kDirectionSeed) in dimension order (so a sequence of dimension D is the first D
//   coordinates of any longer one); then
//   m_i = 2 a_1 m_(i-1) ^ 4 a_2 m_(i-2) ^ ... ^ 2^(s-1) a_(s-1) m_(i-s+1) ^ 2^s m_(i-s) ^ m_(i-s),
//   v_i = m_i / 2^i kept as 32-bit fixed point;
// - points in Gray-code order (Antonov and Saleev 1979): x_k = x_(k-1) ^ v_(c), c = 1 + the number
//   of trailing zero bits of k; the all-zero point x_0 is skipped;
// - scrambling: a random digital shift, one 32-bit XOR mask per dimension.
// 1110 primitive polynomials exist up to degree 13 (1, 1, 2, 2, 6, 6, 18, 16, 48, 60, 176, 144,
// 630 of degrees 1..13), hence the maximum dimension 1 + 1110 = 1111.
#include "optimizers/bo/sobol.hpp"

#include <algorithm>
#include <bit>
#include <cmath>
#include <stdexcept>
#include <string>
#include <utility>

namespace dsb {

namespace {

constexpr int kBits = 32;
constexpr int kMaxDim = 1111;
constexpr int kMaxDegree = 13;
// seed of the initial direction numbers (fixed forever: changing it changes every Sobol point)
constexpr std::uint64_t kDirectionSeed = 0x50B0150B01D1ECULL;

// product of a and b modulo the polynomial `mod` of degree `deg` (all over GF(2), as bit masks)
std::uint64_t gf2_mulmod(std::uint64_t a, std::uint64_t b, std::uint64_t mod, int deg) {
  std::uint64_t r = 0;
  while (b) {
    if (b & 1) r ^= a;
    b >>= 1;
    a <<= 1;
    if ((a >> deg) & 1) a ^= mod;
  }
  return r;
}

// x^e modulo `mod`
std::uint64_t gf2_xpow(std::uint64_t e, std::uint64_t mod, int deg) {
  std::uint64_t result = 1, base = deg == 1 ? (2 ^ mod) : 2;  // x reduced (x = 1 mod x + 1)
  while (e) {
    if (e & 1) result = gf2_mulmod(result, base, mod, deg);
    base = gf2_mulmod(base, base, mod, deg);
    e >>= 1;
  }
  return result;
}

// primitive iff x has multiplicative order exactly 2^deg - 1 modulo poly: x^(2^deg - 1) = 1 and
// x^((2^deg - 1) / p) != 1 for every prime p dividing 2^deg - 1 (a reducible poly fails too: its
// unit group has fewer than 2^deg - 1 elements)
bool gf2_primitive(std::uint32_t poly, int deg) {
  if ((poly & 1) == 0) return false;  // divisible by x
  const std::uint64_t order = (std::uint64_t{1} << deg) - 1;
  if (gf2_xpow(order, poly, deg) != 1) return false;
  std::uint64_t rest = order;
  for (std::uint64_t p = 2; p <= rest; ++p) {
    if (rest % p) continue;
    if (gf2_xpow(order / p, poly, deg) == 1) return false;
    while (rest % p == 0) rest /= p;
  }
  return true;
}

// the first 1110 primitive polynomials, computed once
const std::vector<std::uint32_t>& all_primitive_polynomials() {
  static const std::vector<std::uint32_t> table = [] {
    std::vector<std::uint32_t> t;
    for (int deg = 1; deg <= kMaxDegree && static_cast<int>(t.size()) < kMaxDim - 1; ++deg)
      for (std::uint32_t p = (1u << deg) | 1u; p < (2u << deg); p += 2)
        if (gf2_primitive(p, deg)) t.push_back(p);
    return t;
  }();
  return table;
}

}  // namespace

std::vector<std::uint32_t> primitive_polynomials(int count) {
  const auto& all = all_primitive_polynomials();
  if (count < 0 || count > static_cast<int>(all.size()))
    throw std::invalid_argument("sobol: primitive_polynomials count must be in 0.." + std::to_string(all.size()));
  return {all.begin(), all.begin() + count};
}

SobolSequence::SobolSequence(int dim, Rng* scramble) : dim_(dim) {
  if (dim < 1 || dim > kMaxDim)
    throw std::invalid_argument("sobol: dimension must be in 1.." + std::to_string(kMaxDim) + " (got " +
                                std::to_string(dim) + ")");
  direction_.assign(static_cast<std::size_t>(dim) * kBits, 0);
  for (int i = 0; i < kBits; ++i) direction_[i] = 1u << (kBits - 1 - i);  // van der Corput
  const auto& polys = all_primitive_polynomials();
  Rng draws(kDirectionSeed);
  for (int j = 1; j < dim; ++j) {
    std::uint32_t* v = &direction_[static_cast<std::size_t>(j) * kBits];
    const std::uint32_t poly = polys[j - 1];
    const int s = std::bit_width(poly) - 1;  // degree
    // m_i odd in [1, 2^i), as v_i = m_i 2^(32 - i)
    for (int i = 1; i <= s && i <= kBits; ++i) {
      const std::uint32_t m = 2u * static_cast<std::uint32_t>(draws.below(std::uint64_t{1} << (i - 1))) + 1u;
      v[i - 1] = m << (kBits - i);
    }
    for (int i = s + 1; i <= kBits; ++i) {
      std::uint32_t vi = v[i - s - 1] ^ (v[i - s - 1] >> s);
      for (int k = 1; k < s; ++k)
        if ((poly >> (s - k)) & 1u) vi ^= v[i - k - 1];
      v[i - 1] = vi;
    }
  }
  state_.assign(dim, 0);
  shift_.assign(dim, 0);
  if (scramble)
    for (auto& sh : shift_) sh = static_cast<std::uint32_t>(scramble->next_u64() >> 32);
}

Eigen::VectorXd SobolSequence::next() {
  if (index_ == ~std::uint32_t{0}) throw std::length_error("sobol: more than 2^32 - 1 points requested");
  ++index_;
  const int c = std::countr_zero(index_);
  Eigen::VectorXd x(dim_);
  for (int j = 0; j < dim_; ++j) {
    state_[j] ^= direction_[static_cast<std::size_t>(j) * kBits + c];
    x[j] = static_cast<double>(state_[j] ^ shift_[j]) * 0x1.0p-32;
  }
  return x;
}

Eigen::MatrixXd SobolSequence::draw(int n) {
  if (n < 0) throw std::invalid_argument("sobol: draw needs n >= 0");
  Eigen::MatrixXd P(n, dim_);
  for (int i = 0; i < n; ++i) P.row(i) = next().transpose();
  return P;
}

}  // namespace dsb
