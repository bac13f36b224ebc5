#pragma once
// The quadratic B-spline stencil of one particle (MLS-MPM, Hu et al. 2018): per axis
// base = floor(x/dx - 1/2), f = x/dx - base in [0.5, 1.5), weights
//   w0 = (1.5 - f)^2 / 2,  w1 = 3/4 - (f - 1)^2,  w2 = (f - 0.5)^2 / 2,
// their derivatives dw/dx = (-(1.5 - f), -2 (f - 1), f - 0.5) / dx, and node offsets o in {0,1,2}
// with dpos = (o - f) dx = x_node - x_p. The node weight is the product over axes.
#include <algorithm>
#include <array>
#include <cmath>
#include <vector>

#include "envs/mpm/grid.hpp"
#include "envs/mpm/mpm_types.hpp"

namespace dsb::mpm {

struct Stencil {
  std::array<int, 3> base;  // lowest node index per axis
  Vec3 fx;                  // x / dx - base
  double w[3][3];           // w[axis][offset]
  double dw[3][3];          // d w[axis][offset] / d x_axis
};

// base is the node index (position index + layout.pad), clamped into [0, n - 3] (NaN positions
// map to 0) so that a blown-up particle can never index outside the grid; the NaN then spreads
// through the weights and the episode fails.
inline Stencil make_stencil(const Vec3& x, double inv_dx, const GridLayout& layout) {
  Stencil s;
  for (int a = 0; a < 3; ++a) {
    const double scaled = x[a] * inv_dx;
    double b = std::floor(scaled - 0.5);  // in position units
    const double lo = -static_cast<double>(layout.pad), top = static_cast<double>(layout.n[a] - 3 - layout.pad);
    b = !(b >= lo) ? lo : (b > top ? top : b);
    s.base[a] = static_cast<int>(b) + layout.pad;
    const double f = scaled - b;
    s.fx[a] = f;
    const double d0 = 1.5 - f, d1 = f - 1.0, d2 = f - 0.5;
    s.w[a][0] = 0.5 * d0 * d0;
    s.w[a][1] = 0.75 - d1 * d1;
    s.w[a][2] = 0.5 * d2 * d2;
    s.dw[a][0] = -d0 * inv_dx;
    s.dw[a][1] = -2.0 * d1 * inv_dx;
    s.dw[a][2] = d2 * inv_dx;
  }
  return s;
}

// gradient of the node weight w_x[i] w_y[j] w_z[k] with respect to the particle position
inline Vec3 weight_gradient(const Stencil& s, int i, int j, int k) {
  return Vec3(s.dw[0][i] * s.w[1][j] * s.w[2][k], s.w[0][i] * s.dw[1][j] * s.w[2][k],
              s.w[0][i] * s.w[1][j] * s.dw[2][k]);
}

// node (base + (i, j, k)) += w_x[i] w_y[j] w_z[k] (t + i a0 + j a1 + k a2) over the 27 nodes of
// the stencil: an affine field of the node offset scattered with the node weights (P2G's (q, m) as
// Vec4, G2P^T's velocity adjoints as Vec3). The sums in this order are the ones the lanes kernels
// reproduce (transfer_lanes.hpp p2g_scatter, adjoint_lanes.hpp g2p_adjoint_scatter).
template <class V>
inline void scatter_affine(const Stencil& s, const GridLayout& L, const V& t, const V& a0, const V& a1, const V& a2,
                           std::vector<V>& nodes) {
  for (int i = 0; i < 3; ++i) {
    const V ti = t + static_cast<double>(i) * a0;
    for (int j = 0; j < 3; ++j) {
      const V tij = ti + static_cast<double>(j) * a1;
      const double wij = s.w[0][i] * s.w[1][j];
      const int row = L.node(s.base[0] + i, s.base[1] + j, s.base[2]);
      nodes[row] += (wij * s.w[2][0]) * tij;
      nodes[row + 1] += (wij * s.w[2][1]) * (tij + a2);
      nodes[row + 2] += (wij * s.w[2][2]) * (tij + 2.0 * a2);
    }
  }
}

}  // namespace dsb::mpm
