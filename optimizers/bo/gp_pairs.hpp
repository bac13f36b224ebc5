#pragma once
// The O(n^2 d) part of a GP likelihood evaluation with the Matern-5/2 ARD kernel (gp.cpp):
// the scaled squared distance of every pair of points, and the lengthscales' gradient summed over
// the pairs. At a 1,000-episode run's n = 1,000 points in cartpole3's 400 dimensions these loops
// were about 85% of a `boleap` run (a perf profile: one distance is a chain of 400 dependent
// additions, computed twice per likelihood evaluation).
//
// Three paths, the same bits: `scalar` is the plain loop, one pair at a time (the reference, kept
// for tests and the benchmark's peer); `sse2` and `avx` put several pairs side by side in SIMD
// lanes (distances) or several dimensions (gradient), and cut the dimensions into chunks that
// stay in cache. Neither changes any pair's or any dimension's order of operations: a distance
// is summed from 0.0 over i = 0, 1, ..., d - 1, a partial sum leaving a register only as a stored
// double, which is exact; each gradient entry adds the pairs' terms in the order b = 0, 1, ...,
// a = b + 1, ... . Every operation is one IEEE 754 + - or *, rounding in a lane exactly as the
// scalar instruction (no FMA: -ffp-contract=off, and the AVX code is compiled for AVX, not FMA).
// test_gp_pairs compares the three paths bit for bit.
#include "common/simd_path.hpp"

namespace dsb::gp_pairs {

// The paths these loops offer: scalar, sse2 and avx (SimdPath::avx2 runs the AVX code). The
// default is the widest at or below the process's ceiling (common/simd_path.hpp): avx where the
// CPU has it, unless DSB_SIMD says narrower. SimdPath::avx must not be asked for on a CPU without
// AVX (cpu_supports).
SimdPath default_path();

// R(a, b) = sum_{i < d} (Xt(a, i) - Xt(b, i))^2 for every a > b, in the order above.
// Xt (n x d, column-major): the points' coordinates divided by the lengthscales, one column per
// dimension. R (n x n, column-major): only the strict lower part is written.
void squared_distances(const double* Xt, int n, int d, double* R, SimdPath path);

// For each dimension i: gl[i] += (C(a, b) t) t, t = Xs(i, a) - Xs(i, b), over the pairs a > b in
// the order b = 0 .. n - 1, a = b + 1 .. n - 1. Xs (d x n, column-major): one scaled point per
// column; C (n x n, column-major): only the strict lower part is read; gl (d).
void ard_gradient(const double* Xs, int n, int d, const double* C, double* gl, SimdPath path);

}  // namespace dsb::gp_pairs
