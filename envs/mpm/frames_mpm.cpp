// Scenes of the MPM envs for `harness render` (Env::frames): the env's own loss path, rollout(),
// with an EpisodeObserver in its workspace that copies the particle positions and primitive poses
// at the frame steps. Oblique view; manipulators drawn as points on their SDF's zero level set.
#include <algorithm>
#include <cmath>

#include "envs/mpm/fluid_env.hpp"
#include "envs/mpm/plb_env.hpp"

namespace dsb::mpm {

namespace {

ScenePoint sp(const Vec3& v) { return {v.x(), v.y(), v.z()}; }

// the positions and poses of run_episode at the wanted steps
class FrameRecorder : public EpisodeObserver {
 public:
  explicit FrameRecorder(std::vector<int> steps) : steps_(std::move(steps)) {}
  void at_step(int step, const std::vector<Particle>& particles, const std::vector<Pose>& poses) override {
    if (std::find(steps_.begin(), steps_.end(), step) == steps_.end()) return;
    Snapshot s{step, {}, poses};
    s.x.reserve(particles.size());
    for (const auto& p : particles) s.x.push_back(p.x);
    snapshots.push_back(std::move(s));
  }
  struct Snapshot {
    int step = 0;
    std::vector<Vec3> x;      // (particles)
    std::vector<Pose> poses;  // (primitives)
  };
  std::vector<Snapshot> snapshots;  // in step order (a rollout that blew up stops early)

 private:
  std::vector<int> steps_;
};

// points on the surface of a primitive at a pose: the nodes of a 28^3 lattice over its bounding
// cube whose signed distance is within 0.6 lattice spacings of zero
PointCloud primitive_outline(const PrimitiveSpec& spec, const Pose& pose) {
  constexpr int kN = 28;
  const double r = bounding_radius(spec.shape);
  const double h = 2.0 * r / (kN - 1);
  PointCloud c{Role::tool, spec.name, {}, false};
  for (int i = 0; i < kN; ++i)
    for (int j = 0; j < kN; ++j)
      for (int k = 0; k < kN; ++k) {
        const Vec3 local(-r + i * h, -r + j * h, -r + k * h);
        const Vec3 world = pose.p + pose.q * local;
        if (std::abs(primitive_distance(spec, pose, world)) <= 0.6 * h) c.points.push_back(sp(world));
      }
  return c;
}

// the 12 edges of an axis-aligned box as three polylines (bottom, top, verticals)
void add_box(Scene& sc, Role role, const std::string& name, const Vec3& lo, const Vec3& hi) {
  const double x0 = lo.x(), y0 = lo.y(), z0 = lo.z(), x1 = hi.x(), y1 = hi.y(), z1 = hi.z();
  sc.lines.push_back({role, name, {{x0, y0, z0}, {x1, y0, z0}, {x1, y0, z1}, {x0, y0, z1}}, true});
  sc.lines.push_back({role, name, {{x0, y1, z0}, {x1, y1, z0}, {x1, y1, z1}, {x0, y1, z1}}, true});
  for (const auto& [x, z] : {std::pair{x0, z0}, {x1, z0}, {x1, z1}, {x0, z1}})
    sc.lines.push_back({role, name, {{x, y0, z}, {x, y1, z}}});
}

// a body's particles as a cloud
PointCloud body_cloud(const Body& b, const std::vector<Vec3>& x, Role role) {
  PointCloud c{role, b.name, {}, false};
  for (int p = b.begin; p < b.end; ++p) c.points.push_back(sp(x[p]));
  return c;
}

}  // namespace

std::vector<dsb::Frame> FluidEnv::frames(std::span<const double> x, int n, ThreadTeam& team) const {
  const MpmModel& m = model();
  FrameRecorder rec(frame_steps(cfg_.env_steps, n));
  auto ws = make_workspace();
  static_cast<FluidWorkspace&>(*ws).mpm.observer = &rec;
  (void)rollout(x, *ws, team);
  // tank: inner walls and floor at `bound` cells, rim at y_w above the floor
  const double dx = m.config.dx, lo = m.config.bound * dx, floor = cfg_.floor_y();
  const double hi_x = (m.config.grid[0] - m.config.bound) * dx, hi_z = (m.config.grid[2] - m.config.bound) * dx;
  const double rim = floor + cfg_.rim_height;
  std::vector<dsb::Frame> out;
  for (const auto& s : rec.snapshots) {
    dsb::Frame f{s.step, s.step * m.config.substeps * m.config.dt, {}};
    Scene& sc = f.scene;
    sc.camera = Camera::oblique;
    add_box(sc, Role::fixed, "tank", Vec3(lo, floor, lo), Vec3(hi_x, rim, hi_z));
    // the target: above the rim (y_w) over the tank's axis
    sc.lines.push_back(
        {Role::target, "y_w", {{lo, rim, lo}, {hi_x, rim, lo}, {hi_x, rim, hi_z}, {lo, rim, hi_z}}, true});
    const double ax = cfg_.tank_axis_xz[0], az = cfg_.tank_axis_xz[1];
    sc.lines.push_back({Role::target, "axis", {{ax, floor, az}, {ax, rim + 0.1, az}}});
    sc.clouds.push_back(body_cloud(m.bodies[1], s.x, Role::medium));  // syrup
    sc.clouds.push_back(body_cloud(m.bodies[0], s.x, Role::state));   // cube
    for (std::size_t i = 0; i < m.primitives.size(); ++i)
      sc.clouds.push_back(primitive_outline(m.primitives[i], s.poses[i]));
    out.push_back(std::move(f));
  }
  return out;
}

std::vector<dsb::Frame> PlbEnv::frames(std::span<const double> x, int n, ThreadTeam& team) const {
  const PlbModel& pm = model();
  const MpmModel& m = pm.mpm;
  FrameRecorder rec(frame_steps(cfg_.env_steps, n));
  auto ws = make_workspace();
  static_cast<PlbWorkspace&>(*ws).mpm.observer = &rec;
  (void)rollout(x, *ws, team);
  // the target's shell, drawn over the plasticine: nodes whose target mass exceeds the SDF
  // threshold with a face neighbour that does not (node i at (i - pad) dx)
  const double dx = m.config.dx;
  const int pad = m.layout.pad;
  PointCloud target{Role::target, "target", {}, false};
  const NodeGrid& g = pm.target;
  auto inside = [&](int i, int j, int k) {
    return i >= 0 && j >= 0 && k >= 0 && i < g.n[0] && j < g.n[1] && k < g.n[2] &&
        g.at(i, j, k) > cfg_.target_threshold;
  };
  for (int i = 0; i < g.n[0]; ++i)
    for (int j = 0; j < g.n[1]; ++j)
      for (int k = 0; k < g.n[2]; ++k)
        if (inside(i, j, k) &&
            !(inside(i - 1, j, k) && inside(i + 1, j, k) && inside(i, j - 1, k) && inside(i, j + 1, k) &&
              inside(i, j, k - 1) && inside(i, j, k + 1)))
          target.points.push_back({(i - pad) * dx, (j - pad) * dx, (k - pad) * dx});
  const double lo = m.config.bound * dx;
  const Vec3 hi((m.config.grid[0] - m.config.bound) * dx, (m.config.grid[1] - m.config.bound) * dx,
                (m.config.grid[2] - m.config.bound) * dx);
  std::vector<dsb::Frame> out;
  for (const auto& s : rec.snapshots) {
    dsb::Frame f{s.step, s.step * m.config.substeps * m.config.dt, {}};
    Scene& sc = f.scene;
    sc.camera = Camera::oblique;
    // the floor of the domain (inside the walls)
    sc.lines.push_back(
        {Role::fixed, "floor", {{lo, lo, lo}, {hi.x(), lo, lo}, {hi.x(), lo, hi.z()}, {lo, lo, hi.z()}}, true});
    for (const Body& b : m.bodies) sc.clouds.push_back(body_cloud(b, s.x, Role::state));
    sc.clouds.push_back(target);
    for (std::size_t i = 0; i < m.primitives.size(); ++i)
      sc.clouds.push_back(primitive_outline(m.primitives[i], s.poses[i]));
    out.push_back(std::move(f));
  }
  return out;
}

std::vector<dsb::Frame> PlbEnv::target_frames() const {
  const PlbModel& pm = model();
  const MpmModel& m = pm.mpm;
  const NodeGrid& g = pm.target;
  const double dx = m.config.dx;
  const int pad = m.layout.pad;
  // the cells target_shape.hpp measures: above 1% of the grid's maximum
  const double threshold = 0.01 * g.max();
  auto inside = [&](int i, int j, int k) {
    return i >= 0 && j >= 0 && k >= 0 && i < g.n[0] && j < g.n[1] && k < g.n[2] && g.at(i, j, k) > threshold;
  };
  // each column's highest cell (n0 x n2; -1: none)
  std::vector<int> height(static_cast<std::size_t>(g.n[0]) * g.n[2], -1);
  for (int i = 0; i < g.n[0]; ++i)
    for (int j = 0; j < g.n[1]; ++j)
      for (int k = 0; k < g.n[2]; ++k)
        if (inside(i, j, k)) height[static_cast<std::size_t>(i) * g.n[2] + k] = j;
  // a top face lies in a dent when a column within 3 cells stands 2 cells higher or more
  auto in_dent = [&](int i, int j, int k) {
    for (int a = std::max(0, i - 3); a <= std::min(g.n[0] - 1, i + 3); ++a)
      for (int c = std::max(0, k - 3); c <= std::min(g.n[2] - 1, k + 3); ++c)
        if (height[static_cast<std::size_t>(a) * g.n[2] + c] >= j + 2) return true;
    return false;
  };
  // its shell (cells with a face neighbour outside) as discs of a cell's size: the top faces
  // orange, those in dents and the other faces light orange (so that imprints show), far ones
  // first (the oblique camera looks from -x, -z and above: render/camera.cpp) so the nearer cover them
  struct Cell {
    double far;
    Disc disc;
  };
  std::vector<Cell> cells;
  Vec3 lo = Vec3::Constant(INFINITY), hi = Vec3::Constant(-INFINITY);
  for (int i = 0; i < g.n[0]; ++i)
    for (int j = 0; j < g.n[1]; ++j)
      for (int k = 0; k < g.n[2]; ++k) {
        if (!inside(i, j, k)) continue;
        const Vec3 x((i - pad) * dx, (j - pad) * dx, (k - pad) * dx);
        lo = lo.cwiseMin(x);
        hi = hi.cwiseMax(x);
        const bool top = !inside(i, j + 1, k);
        if (!top && inside(i - 1, j, k) && inside(i + 1, j, k) && inside(i, j - 1, k) && inside(i, j, k - 1) &&
            inside(i, j, k + 1))
          continue;
        const double far = 0.9063 * (0.5 * x.x() + 0.866 * x.z()) - 0.4226 * x.y();
        const bool lit = top && !in_dent(i, j, k);
        cells.push_back({far, Disc{lit ? Role::state : Role::trace, "target", sp(x), 0.6 * dx, true}});
      }
  std::stable_sort(cells.begin(), cells.end(), [](const Cell& a, const Cell& b) { return a.far > b.far; });
  const int steps = cfg_.env_steps;
  dsb::Frame f{steps, steps * m.config.substeps * m.config.dt, {}};
  Scene& sc = f.scene;
  sc.camera = Camera::oblique;
  // a floor under the target, 0.05 around its cells
  const double y0 = m.config.bound * dx, e = 0.05;
  sc.lines.push_back({Role::fixed,
                      "floor",
                      {{lo.x() - e, y0, lo.z() - e},
                       {hi.x() + e, y0, lo.z() - e},
                       {hi.x() + e, y0, hi.z() + e},
                       {lo.x() - e, y0, hi.z() + e}},
                      true});
  for (auto& c : cells) sc.discs.push_back(std::move(c.disc));
  // PlasticineLab's target: each body's bounding box
  for (const auto& b : find_plb_task(cfg_.task)->plb_target) add_box(sc, Role::target, "plasticinelab box", b.lo, b.hi);
  return {std::move(f)};
}

}  // namespace dsb::mpm
