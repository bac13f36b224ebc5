#include "envs/cloth/cloth_model.hpp"

#include <algorithm>
#include <cmath>
#include <string>

#include "common/error.hpp"

namespace dsb::cloth {

PlaneSurface::PlaneSurface(const Vec3& point, const Vec3& normal) : point_(point) {
  const double len = normal.norm();
  if (!(len > 0.0 && std::isfinite(len))) throw ConfigError("plane surface", "normal", "must be nonzero and finite");
  normal_ = normal / len;
}

std::shared_ptr<const PlaneSurface> PlaneSurface::floor(double height) {
  return std::make_shared<const PlaneSurface>(Vec3(0.0, height, 0.0), Vec3::UnitY());
}

SurfaceSample PlaneSurface::sample(int, const Vec3& x) const {
  // distance n . (x - p); constant normal, static surface
  SurfaceSample s;
  s.distance = normal_.dot(x - point_);
  s.normal = normal_;
  return s;
}

std::vector<double> ClothModel::default_stiffness() const {
  std::vector<double> k(springs.size());
  for (std::size_t s = 0; s < springs.size(); ++s) k[s] = springs[s].stiffness;
  return k;
}

std::vector<int> ClothModel::anchor_of_vertex() const {
  std::vector<int> of(rest_position.size(), -1);
  for (std::size_t a = 0; a < anchors.size(); ++a) of[anchors[a].vertex] = static_cast<int>(a);
  return of;
}

void ClothModel::validate() const {
  auto fail = [](const std::string& field, const std::string& why) { throw ConfigError("cloth model", field, why); };
  const int n = vertices();
  if (n < 1) fail("rest_position", "must hold at least one vertex");
  if (mass.size() != rest_position.size())
    fail("mass", "must have one entry per vertex (" + std::to_string(n) + "), got " + std::to_string(mass.size()));
  for (int i = 0; i < n; ++i) {
    if (!(std::isfinite(mass[i]) && mass[i] > 0.0)) fail("mass[" + std::to_string(i) + "]", "must be finite and > 0");
    if (!rest_position[i].allFinite()) fail("rest_position[" + std::to_string(i) + "]", "must be finite");
  }
  for (std::size_t s = 0; s < springs.size(); ++s) {
    const Spring& sp = springs[s];
    const std::string f = "springs[" + std::to_string(s) + "]";
    if (sp.i < 0 || sp.i >= n || sp.j < 0 || sp.j >= n || sp.i == sp.j)
      fail(f + ".i/j", "must be two distinct vertices in [0, " + std::to_string(n) + ")");
    if (!(std::isfinite(sp.rest_length) && sp.rest_length > 0.0)) fail(f + ".rest_length", "must be finite and > 0");
    if (!(std::isfinite(sp.stiffness) && sp.stiffness >= 0.0)) fail(f + ".stiffness", "must be finite and >= 0");
    if (!(std::isfinite(sp.damping) && sp.damping >= 0.0)) fail(f + ".damping", "must be finite and >= 0");
  }
  std::vector<char> taken(n, 0);
  for (std::size_t a = 0; a < anchors.size(); ++a) {
    const int v = anchors[a].vertex;
    const std::string f = "anchors[" + std::to_string(a) + "]";
    if (v < 0 || v >= n) fail(f + ".vertex", "must be in [0, " + std::to_string(n) + ")");
    if (taken[v]) fail(f + ".vertex", "holds a vertex that another anchor holds");
    taken[v] = 1;
    if (anchors[a].release_step < 0) fail(f + ".release_step", "must be >= 0");
  }
  for (std::size_t k = 0; k < surfaces.size(); ++k)
    if (!surfaces[k]) fail("surfaces[" + std::to_string(k) + "]", "must not be null");
  if (!gravity.allFinite()) fail("gravity", "must be finite");
  if (!(std::isfinite(dt) && dt > 0.0)) fail("dt", "must be finite and > 0");
  if (!(std::isfinite(damping) && damping >= 0.0)) fail("damping", "must be finite and >= 0");
  if (!(tangential_keep >= 0.0 && tangential_keep <= 1.0)) fail("tangential_keep", "must be in [0, 1]");
}

ClothState rest_state(const ClothModel& m) {
  ClothState s;
  s.x = m.rest_position;
  s.v.assign(m.rest_position.size(), Vec3::Zero());
  return s;
}

Vec3 centre_of_mass(const ClothModel& m, std::span<const Vec3> x) {
  double total = 0.0;
  Vec3 sum = Vec3::Zero();
  for (int i = 0; i < m.vertices(); ++i) {
    sum += m.mass[i] * x[i];
    total += m.mass[i];
  }
  return sum / total;
}

ClothModel build_grid(const GridSpec& g) {
  auto fail = [](const std::string& field, const std::string& why) { throw ConfigError("cloth grid", field, why); };
  if (g.cols < 2 || g.rows < 2) fail("cols/rows", "must be >= 2");
  if (!(g.width > 0.0 && g.height > 0.0)) fail("width/height", "must be > 0");
  if (!(g.total_mass > 0.0)) fail("total_mass", "must be > 0");
  if (std::abs(g.axis_u.norm() - 1.0) > 1e-12 || std::abs(g.axis_v.norm() - 1.0) > 1e-12 ||
      std::abs(g.axis_u.dot(g.axis_v)) > 1e-12)
    fail("axis_u/axis_v", "must be orthogonal unit vectors");
  ClothModel m;
  const int W = g.cols, H = g.rows;
  const double du = g.width / (W - 1), dv = g.height / (H - 1);
  // vertex (col, row) at origin + col du axis_u + row dv axis_v
  for (int r = 0; r < H; ++r)
    for (int c = 0; c < W; ++c) m.rest_position.push_back(g.origin + (c * du) * g.axis_u + (r * dv) * g.axis_v);
  m.mass.assign(std::size_t(W) * H, g.total_mass / (W * H));
  auto id = [W](int c, int r) { return r * W + c; };
  auto add = [&](int a, int b, double k, double damp, SpringKind kind) {
    m.springs.push_back({a, b, (m.rest_position[b] - m.rest_position[a]).norm(), k, damp, kind});
  };
  const double ks = g.structural_stiffness, cs = g.structural_damping;
  const double kh = g.shear_stiffness, ch = g.shear_damping;
  const double kb = g.bending_stiffness, cb = g.bending_damping;
  // structural: horizontal neighbours row by row, then vertical neighbours
  for (int r = 0; r < H; ++r)
    for (int c = 0; c + 1 < W; ++c) add(id(c, r), id(c + 1, r), ks, cs, SpringKind::structural);
  for (int r = 0; r + 1 < H; ++r)
    for (int c = 0; c < W; ++c) add(id(c, r), id(c, r + 1), ks, cs, SpringKind::structural);
  // shear: both diagonals of each cell
  for (int r = 0; r + 1 < H; ++r)
    for (int c = 0; c + 1 < W; ++c) {
      add(id(c, r), id(c + 1, r + 1), kh, ch, SpringKind::shear);
      add(id(c + 1, r), id(c, r + 1), kh, ch, SpringKind::shear);
    }
  // bending: two apart, horizontal then vertical
  for (int r = 0; r < H; ++r)
    for (int c = 0; c + 2 < W; ++c) add(id(c, r), id(c + 2, r), kb, cb, SpringKind::bending);
  for (int r = 0; r + 2 < H; ++r)
    for (int c = 0; c < W; ++c) add(id(c, r), id(c, r + 2), kb, cb, SpringKind::bending);
  return m;
}

double frequency_bound(const ClothModel& m, std::span<const double> stiffness) {
  // omega_max^2 <= max_i 2 sum_{s at i} k_s / m_i (block Gershgorin on M^-1 K, |e e^T| = 1)
  std::vector<double> ksum(m.rest_position.size(), 0.0);
  for (std::size_t s = 0; s < m.springs.size(); ++s) {
    ksum[m.springs[s].i] += stiffness[s];
    ksum[m.springs[s].j] += stiffness[s];
  }
  double w2 = 0.0;
  for (std::size_t i = 0; i < ksum.size(); ++i) w2 = std::max(w2, 2.0 * ksum[i] / m.mass[i]);
  return std::sqrt(w2);
}

std::array<int, 9> grid_subsample_3x3(int cols, int rows) {
  const int cs[3] = {0, (cols - 1) / 2, cols - 1}, rs[3] = {0, (rows - 1) / 2, rows - 1};
  std::array<int, 9> v{};
  for (int a = 0; a < 3; ++a)
    for (int b = 0; b < 3; ++b) v[a * 3 + b] = rs[a] * cols + cs[b];
  return v;
}

void append_vertex_states(std::vector<double>& observation, const ClothState& s, std::span<const int> vertices) {
  for (int v : vertices)
    for (int k = 0; k < 3; ++k) observation.push_back(s.x[v](k));
  for (int v : vertices)
    for (int k = 0; k < 3; ++k) observation.push_back(s.v[v](k));
}

}  // namespace dsb::cloth
