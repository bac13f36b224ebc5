#pragma once
// The order in which Eigen 3.4 sums the entries of the engine's small products, for the lanes
// code (lanes.hpp) that must repeat the scalar code's bits. Templates on the number type: double
// or a Pack. In an anonymous namespace for the reason lanes.hpp gives.
#include "envs/mpm/lanes.hpp"

namespace dsb::mpm {
namespace {

// The entry (row, .) of a 3x3 product as Eigen 3.4 evaluates it in the portable (SSE2) build,
// t_k = lhs(row, k) rhs(k, .). Where the product initialises a matrix (construction, return
// value) or is part of a larger expression: rows 0 and 1 are one SSE2 packet accumulated left to
// right, (t0 + t1) + t2, and row 2 a scalar reduction, which Eigen's unroller splits in halves,
// t0 + (t1 + t2) (eigen_product_sum). Where it is assigned to an existing matrix (operator=,
// which assumes aliasing and goes through a temporary), every row is a scalar reduction,
// t0 + (t1 + t2) (eigen_assigned_product_sum). Eigen folds a scalar factor of a product into its
// left operand: s * (X * Y) is computed as (s X) * Y. (Measured against Eigen on random
// matrices; the tests compare every use with the scalar code.)
template <class T>
DSB_LANE_INLINE T eigen_product_sum(int row, const T& t0, const T& t1, const T& t2) {
  return row < 2 ? (t0 + t1) + t2 : t0 + (t1 + t2);
}
template <class T>
DSB_LANE_INLINE T eigen_assigned_product_sum(const T& t0, const T& t1, const T& t2) {
  return t0 + (t1 + t2);
}

}  // namespace
}  // namespace dsb::mpm
