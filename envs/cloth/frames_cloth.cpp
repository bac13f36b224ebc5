// Scenes of the cloth envs for `harness render` (Env::frames): the env's forward episode on a
// tape (cloth_rollout, the same steps as the loss path and the gradient's forward pass), read at
// the frame steps. Oblique view; the cloth as its grid's rows and columns.
#include <cmath>

#include "common/det_math.hpp"
#include "envs/cloth/flip_env.hpp"
#include "envs/cloth/swing_env.hpp"

namespace dsb::cloth {

namespace {

ScenePoint sp(const Vec3& v) { return {v.x(), v.y(), v.z()}; }

// a cols x rows vertex grid (index row * cols + col) as one polyline per row and per column
void add_grid(Scene& sc, Role role, const std::string& name, std::span<const Vec3> x, int cols, int rows) {
  for (int r = 0; r < rows; ++r) {
    Polyline l{role, name, {}};
    for (int c = 0; c < cols; ++c) l.points.push_back(sp(x[r * cols + c]));
    sc.lines.push_back(std::move(l));
  }
  for (int c = 0; c < cols; ++c) {
    Polyline l{role, name, {}};
    for (int r = 0; r < rows; ++r) l.points.push_back(sp(x[r * cols + c]));
    sc.lines.push_back(std::move(l));
  }
}

}  // namespace

std::vector<Frame> SwingEnv::frames(std::span<const double> x, int n, ThreadTeam&) const {
  const SwingModel& m = model();
  const ClothModel& c = m.cloth;
  std::vector<double> k;
  fill_stiffness(m, x, k);
  ClothState s0;
  fill_initial_state(m, x, s0);
  ClothTape tape;
  cloth_rollout(c, ClothInputs{k, m.anchor_path}, s0, m.steps, tape);
  const int na = c.anchor_count();
  // floor patch: under every position of the episode and the target, 5 cm margin
  const double f = cfg_.floor_height;
  Vec3 lo = m.target[0], hi = m.target[0];
  for (const auto& p : m.target) lo = lo.cwiseMin(p), hi = hi.cwiseMax(p);
  for (int t = 0; t <= m.steps; ++t)
    for (const auto& p : tape.x(t))
      if (p.allFinite()) lo = lo.cwiseMin(p), hi = hi.cwiseMax(p);
  const double x0 = lo.x() - 0.05, x1 = hi.x() + 0.05, z0 = lo.z() - 0.05, z1 = hi.z() + 0.05;
  std::vector<Frame> out;
  for (const int step : frame_steps(m.steps, n)) {
    Frame fr{step, step * c.dt, {}};
    Scene& sc = fr.scene;
    sc.camera = Camera::oblique;
    sc.lines.push_back({Role::fixed, "floor", {{x0, f, z0}, {x1, f, z0}, {x1, f, z1}, {x0, f, z1}}, true});
    const auto xs = tape.x(step);
    // the target of the loss: the centre of mass, the 4 corners or the whole mesh
    if (loss_ == SwingLoss::single) {
      sc.discs.push_back({Role::target, "target", sp(m.target_com), 0.012, false});
      sc.discs.push_back({Role::state, "centre of mass", sp(centre_of_mass(c, xs)), 0.008, true});
    } else if (loss_ == SwingLoss::corner) {
      for (int v : m.corners) {
        sc.discs.push_back({Role::target, "target", sp(m.target[v]), 0.012, false});
        sc.discs.push_back({Role::state, "corner", sp(xs[v]), 0.008, true});
      }
    } else {
      add_grid(sc, Role::target, "target", m.target, cfg_.cols, cfg_.rows);
    }
    add_grid(sc, Role::state, "cloth", xs, cfg_.cols, cfg_.rows);
    // the held corners while they are held
    for (int a = 0; a < na; ++a) {
      const std::size_t row = std::size_t(step) * na + a;
      if (c.anchors[a].held_during(step) && row < m.anchor_path.size())
        sc.discs.push_back({Role::tool, "anchor", sp(m.anchor_path[row]), 0.01, true});
    }
    out.push_back(std::move(fr));
  }
  return out;
}

std::vector<Frame> FlipEnv::frames(std::span<const double> x, int n, ThreadTeam&) const {
  const FlipModel& m = model();
  const auto base = taped_rollout(x);
  const auto& ws = static_cast<const FlipWorkspace&>(*base);
  const PanShape& pan = cfg_.pan;
  const std::array<Vec3, 4> targets = corner_targets(ws.path.back());
  std::vector<Frame> out;
  for (const int step : frame_steps(m.steps, n)) {
    Frame fr{step, step * ws.cloth.dt, {}};
    Scene& sc = fr.scene;
    sc.camera = Camera::oblique;
    const PanPose& pose = ws.path[step];
    // the pan: its rim and the flat bottom's edge (circles in its local x-z plane), and its
    // profile h(r) in the plane z = 0 (48 points each)
    Polyline rim{Role::tool, "pan", {}, true}, bottom{Role::tool, "pan", {}, true}, profile{Role::tool, "pan", {}};
    for (int i = 0; i < 48; ++i) {
      const double a = 2.0 * M_PI * i / 48.0, ca = dm::cos(a), sa = dm::sin(a);
      rim.points.push_back(sp(PanSurface::to_world(pose, Vec3(pan.radius * ca, pan.rim_height, pan.radius * sa))));
      bottom.points.push_back(sp(PanSurface::to_world(pose, Vec3(pan.flat_radius * ca, 0.0, pan.flat_radius * sa))));
      const double r = -pan.radius + 2.0 * pan.radius * i / 47.0;
      double h = 0.0, dh = 0.0, d2h = 0.0;
      pan.profile(std::abs(r), h, dh, d2h);
      profile.points.push_back(sp(PanSurface::to_world(pose, Vec3(r, h, 0.0))));
    }
    sc.lines.push_back(rim);
    sc.lines.push_back(bottom);
    sc.lines.push_back(profile);
    const auto xs = ws.tape.x(step);
    add_grid(sc, Role::state, "pancake", xs, cfg_.cols, cfg_.rows);
    // the corners and their targets (the final pan pose's, in every frame)
    for (int i = 0; i < 4; ++i) {
      sc.discs.push_back({Role::target, "target", sp(targets[i]), 0.012, false});
      sc.discs.push_back({Role::state, "corner", sp(xs[m.corners[i]]), 0.008, true});
    }
    out.push_back(std::move(fr));
  }
  return out;
}

}  // namespace dsb::cloth
