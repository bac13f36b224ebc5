// The PlasticineLab tasks' targets: each task's scripted reference motion (plb_tasks.cpp) run by
// our engine, its final grid mass (scaled to the mass of kPlbTargetParticles particles, as
// PlasticineLab's targets hold it) written as data/targets/plb-<task>.txt.gz; the check that
// stored targets equal a fresh generation (decoded values, bit for bit); and our stored targets
// beside PlasticineLab's own files.
//   plb_targets --out DIR [--task NAME]      write targets, print their figures vs PlasticineLab's
//   plb_targets --check DIR [--task NAME]    generate and compare with DIR's files (exit 1 on a difference)
//   plb_targets --figures DIR [--task NAME]  DIR's targets against PlasticineLab's figures, as a Markdown
//       table (docs/plasticinelab.md): per PlasticineLab body, centre of mass, bounding box of the
//       cells above 1% of the maximum, faces off in cells, the boxes' IoU, mass (target_shape.hpp)
//   plb_targets --compare ASSETS [--task NAME]
//       our stored targets against PlasticineLab's .npy files in ASSETS (its plb/envs/assets, e.g.
//       Pinch3D-v1.npy), read as `--set plb-NAME.target=FILE` reads them: per task the bounding
//       box of nodes above 1e-4, the centre of mass, the mass, and the overlap (IoU of the sets of
//       nodes above 1e-4); a task whose file is missing is skipped (exit 2 when none is there, 1
//       when a file cannot be read)
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <string>
#include <vector>

#include "common/error.hpp"
#include "common/parallel.hpp"
#include "envs/mpm/episode.hpp"
#include "envs/mpm/plb_env.hpp"
#include "envs/mpm/plb_loss.hpp"
#include "envs/mpm/plb_model.hpp"
#include "envs/mpm/plb_target_file.hpp"
#include "envs/mpm/target_grid.hpp"
#include "envs/mpm/target_shape.hpp"

namespace {

using namespace dsb;
using namespace dsb::mpm;

class NoLoss : public EpisodeObjective {
 public:
  double step_loss(int, const std::vector<Particle>&, const std::vector<Pose>&, ThreadTeam&) const override {
    return 0.0;
  }
  void step_loss_adjoint(int, const std::vector<Particle>&, const std::vector<Pose>&, std::vector<ParticleAdjoint>&,
                         std::vector<PoseAdjoint>&, ThreadTeam&) const override {}
};

// the target's grid mass on the scene's nodes: the reference motion's final state, or where the
// task's construction places the initial particles (rope); scaled to the mass of
// kPlbTargetParticles particles as PlasticineLab's targets are (pinch 10000/6000, triplemove
// 10000/9999, the others 1)
NodeGrid generate(const PlbTask& task, ThreadTeam& team) {
  const PlbConfig cfg = plb_config(task.name);
  const MpmModel model = build_plb_mpm_model(cfg);
  MpmWorkspace ws(model);
  if (task.target_placement) {
    ws.reset_state(model);
    for (auto& p : ws.particles) p.x = task.target_placement(p.x);
  } else {
    const auto actions = plb_reference_actions(task, cfg.env_steps);
    const double loss = run_episode(model, ws, team, actions, cfg.env_steps, NoLoss{});
    if (std::isnan(loss)) throw std::runtime_error("the reference motion of " + task.name + " blew up");
  }
  ParticleBins bins;
  bins.home.resize(model.particles());
  std::vector<double> mass;
  grid_mass(model, ws.particles, team, bins, mass);
  NodeGrid g;
  g.n = model.layout.n;
  g.values.assign(model.layout.nodes(), 0.0);
  for (int b : bins.active)
    for_each_node_of_block(model.layout, b, [&](int, int, int, int n) { g.values[n] = mass[n]; });
  if (model.particles() != kPlbTargetParticles) {
    const double scale = static_cast<double>(kPlbTargetParticles) / model.particles();
    for (double& v : g.values) v *= scale;
  }
  return g;
}

// our target's figures (target_shape.hpp) beside PlasticineLab's, body by body (ours matched to
// the nearest of theirs by centre)
void describe(const PlbTask& task, const NodeGrid& g, double dx, int pad) {
  const TargetShape s = describe_target_shape(g, pad, dx);
  std::printf(
      "%-11s mass %.4f, centre (%.3f, %.3f, %.3f), cells above 1%% of the max [%.3f, %.3f, %.3f]..[%.3f, %.3f, "
      "%.3f], %zu bod%s\n",
      task.name.c_str(), s.mass, s.centre.x(), s.centre.y(), s.centre.z(), s.lo.x(), s.lo.y(), s.lo.z(), s.hi.x(),
      s.hi.y(), s.hi.z(), s.bodies.size(), s.bodies.size() == 1 ? "y" : "ies");
  for (const auto& b : s.bodies) {
    const PlbTargetBody* near = nullptr;
    for (const auto& t : task.plb_target)
      if (!near || (t.centre - b.centre).norm() < (near->centre - b.centre).norm()) near = &t;
    const Vec3 c = task.plb_target.size() == 1 ? s.centre : b.centre;  // a single body: the whole centre
    std::printf(
        "%-11s   ours   centre (%.3f, %.3f, %.3f) box [%.3f, %.3f, %.3f]..[%.3f, %.3f, %.3f] (%ld cells, mass "
        "%.4f)\n",
        "", c.x(), c.y(), c.z(), b.lo.x(), b.lo.y(), b.lo.z(), b.hi.x(), b.hi.y(), b.hi.z(), b.cells, b.mass);
    if (!near) continue;
    const Vec3 dlo = (b.lo - near->lo) / dx, dhi = (b.hi - near->hi) / dx;
    std::printf(
        "%-11s   theirs centre (%.3f, %.3f, %.3f) box [%.3f, %.3f, %.3f]..[%.3f, %.3f, %.3f]; centre %.4f apart, "
        "faces off by (%+.1f %+.1f %+.1f)..(%+.1f %+.1f %+.1f) cells, box IoU %.3f\n",
        "", near->centre.x(), near->centre.y(), near->centre.z(), near->lo.x(), near->lo.y(), near->lo.z(),
        near->hi.x(), near->hi.y(), near->hi.z(), (c - near->centre).norm(), dlo.x(), dlo.y(), dlo.z(), dhi.x(),
        dhi.y(), dhi.z(), box_iou(b.lo, b.hi, near->lo, near->hi, dx));
  }
}

// --figures: one Markdown row per body of PlasticineLab's target
void figures(const std::string& dir, const std::string& only) {
  std::printf(
      "| task | centre of mass: ours / PlasticineLab's (apart) | box of the cells above 1%% of the max: ours / "
      "PlasticineLab's | faces off (cells) | box IoU | mass: ours / PlasticineLab's |\n|---|---|---|---|---|---|\n");
  auto v3 = [](const Vec3& v) {
    char b[64];
    std::snprintf(b, sizeof b, "(%.3f, %.3f, %.3f)", v.x(), v.y(), v.z());
    return std::string(b);
  };
  for (const auto& task : plb_tasks()) {
    if (!only.empty() && task.name != only) continue;
    const PlbConfig cfg = plb_config(task.name);
    const double dx = cfg.mpm.dx;
    const TargetShape s = describe_target_shape(read_grid_gz(dir + "/plb-" + task.name + ".txt.gz"), cfg.mpm.pad, dx);
    for (std::size_t t = 0; t < task.plb_target.size(); ++t) {
      const PlbTargetBody& theirs = task.plb_target[t];
      const TargetBody* ours = nullptr;
      for (const auto& b : s.bodies)
        if (!ours || (b.centre - theirs.centre).norm() < (ours->centre - theirs.centre).norm()) ours = &b;
      const Vec3 c = task.plb_target.size() == 1 ? s.centre : ours->centre;
      const Vec3 dlo = (ours->lo - theirs.lo) / dx, dhi = (ours->hi - theirs.hi) / dx;
      const std::string name = task.plb_target.size() == 1 ? task.name : task.name + " block " + std::to_string(t + 1);
      std::printf("| %s | %s / %s (%.4f) | %s..%s / %s..%s | (%+ld %+ld %+ld)..(%+ld %+ld %+ld) | %.2f | %.4f / %s |\n",
                  name.c_str(), v3(c).c_str(), v3(theirs.centre).c_str(), (c - theirs.centre).norm(),
                  v3(ours->lo).c_str(), v3(ours->hi).c_str(), v3(theirs.lo).c_str(), v3(theirs.hi).c_str(),
                  std::lround(dlo.x()), std::lround(dlo.y()), std::lround(dlo.z()), std::lround(dhi.x()),
                  std::lround(dhi.y()), std::lround(dhi.z()), box_iou(ours->lo, ours->hi, theirs.lo, theirs.hi, dx),
                  task.plb_target.size() == 1 ? s.mass : ours->mass, task.plb_target.size() == 1 ? "0.6104" : "0.203");
    }
  }
}

// What --compare prints of a target: nodes above kInside, positions (I - pad) dx.
constexpr double kInside = 1e-4;

struct TargetSummary {
  double lo[3] = {1e9, 1e9, 1e9}, hi[3] = {-1e9, -1e9, -1e9}, centre[3] = {0, 0, 0}, mass = 0.0;
  long inside = 0;
};

TargetSummary summarize(const NodeGrid& g, double dx, int pad) {
  TargetSummary s;
  for (int i = 0; i < g.n[0]; ++i)
    for (int j = 0; j < g.n[1]; ++j)
      for (int k = 0; k < g.n[2]; ++k) {
        const double v = g.at(i, j, k), x[3] = {(i - pad) * dx, (j - pad) * dx, (k - pad) * dx};
        s.mass += v;
        for (int a = 0; a < 3; ++a) s.centre[a] += v * x[a];
        if (!(v > kInside)) continue;
        ++s.inside;
        for (int a = 0; a < 3; ++a) {
          s.lo[a] = std::min(s.lo[a], x[a]);
          s.hi[a] = std::max(s.hi[a], x[a]);
        }
      }
  for (double& c : s.centre) c /= s.mass;
  return s;
}

void print_summary(const char* task, const std::string& source, const TargetSummary& s) {
  std::printf("%-11s %-20s [%.3f, %.3f]  [%.3f, %.3f]  [%.3f, %.3f]  (%.3f, %.3f, %.3f)  %.4f  %6ld\n", task,
              source.c_str(), s.lo[0], s.hi[0], s.lo[1], s.hi[1], s.lo[2], s.hi[2], s.centre[0], s.centre[1],
              s.centre[2], s.mass, s.inside);
}

// our stored targets against PlasticineLab's files in `assets`; the exit status (header above)
int compare(const std::string& assets, const std::string& only) {
  std::printf("our targets (data/targets) against PlasticineLab's in %s; nodes with mass > %g\n", assets.c_str(),
              kInside);
  std::printf("%-11s %-20s %-14s  %-14s  %-14s  %-21s  %-6s  %6s\n", "task", "target", "x range", "y range", "z range",
              "centre of mass", "mass", "nodes");
  int found = 0, unreadable = 0;
  for (const auto& task : plb_tasks()) {
    if (!only.empty() && task.name != only) continue;
    const PlbConfig cfg = plb_config(task.name);
    const std::string file = assets + "/" + task.plb_asset;
    if (!std::filesystem::exists(file)) {
      std::printf("%-11s %s: not in %s, skipped\n", task.name.c_str(), task.plb_asset.c_str(), assets.c_str());
      continue;
    }
    ++found;
    NodeGrid theirs;
    try {
      theirs = read_plb_target(file, cfg.mpm).grid;
    } catch (const UsageError& e) {
      std::printf("%-11s %s\n", task.name.c_str(), e.what());
      ++unreadable;
      continue;
    }
    const NodeGrid ours = read_grid_gz(plb_target_path(task.name));
    const double dx = cfg.mpm.dx;
    const int pad = cfg.mpm.pad;
    const TargetSummary a = summarize(ours, dx, pad), b = summarize(theirs, dx, pad);
    print_summary(task.name.c_str(), "ours", a);
    print_summary("", task.plb_asset, b);
    long both = 0, either = 0;
    for (std::size_t n = 0; n < ours.values.size(); ++n) {
      const bool in_a = ours.values[n] > kInside, in_b = theirs.values[n] > kInside;
      both += in_a && in_b;
      either += in_a || in_b;
    }
    const double d = std::hypot(a.centre[0] - b.centre[0], a.centre[1] - b.centre[1], a.centre[2] - b.centre[2]);
    std::printf(
        "%-11s centre of mass %.3f apart; overlap (IoU of nodes > %g) %.3f (%ld of %ld); mass ratio "
        "theirs/ours %.3f\n",
        "", d, kInside, either > 0 ? static_cast<double>(both) / static_cast<double>(either) : 0.0, both, either,
        b.mass / a.mass);
  }
  if (found == 0) {
    std::fprintf(stderr, "plb_targets: no PlasticineLab target file (e.g. Pinch3D-v1.npy) in %s\n", assets.c_str());
    return 2;
  }
  return unreadable == 0 ? 0 : 1;
}

}  // namespace

int main(int argc, char** argv) {
  std::string out, check, assets, figures_dir, only;
  for (int i = 1; i + 1 < argc; i += 2) {
    if (!std::strcmp(argv[i], "--out"))
      out = argv[i + 1];
    else if (!std::strcmp(argv[i], "--figures"))
      figures_dir = argv[i + 1];
    else if (!std::strcmp(argv[i], "--check"))
      check = argv[i + 1];
    else if (!std::strcmp(argv[i], "--compare"))
      assets = argv[i + 1];
    else if (!std::strcmp(argv[i], "--task"))
      only = argv[i + 1];
  }
  const int modes = int{!out.empty()} + int{!check.empty()} + int{!assets.empty()} + int{!figures_dir.empty()};
  if (modes != 1) {
    std::fprintf(stderr,
                 "usage: plb_targets --out DIR | --check DIR | --figures DIR | --compare ASSETS_DIR [--task NAME]\n");
    return 2;
  }
  if (!figures_dir.empty()) {
    try {
      figures(figures_dir, only);
      return 0;
    } catch (const std::exception& e) {
      std::fprintf(stderr, "plb_targets: %s\n", e.what());
      return 2;
    }
  }
  if (!assets.empty()) {
    try {
      return compare(assets, only);
    } catch (const std::exception& e) {
      std::fprintf(stderr, "plb_targets: %s\n", e.what());
      return 2;
    }
  }
  ThreadTeam team(2);
  int differing = 0;
  try {
    for (const auto& task : plb_tasks()) {
      if (!only.empty() && task.name != only) continue;
      const NodeGrid g = generate(task, team);
      const PlbConfig cfg = plb_config(task.name);
      describe(task, g, cfg.mpm.dx, cfg.mpm.pad);
      const std::string name = "/plb-" + task.name + ".txt.gz";
      if (!out.empty()) {
        write_grid_gz(out + name, g);
      } else {
        const NodeGrid stored = read_grid_gz(check + name);
        const bool same = stored.n == g.n && stored.values.size() == g.values.size() &&
            std::memcmp(stored.values.data(), g.values.data(), g.values.size() * sizeof(double)) == 0;
        std::printf("%-11s %s\n", "",
                    same ? "stored target equals a fresh generation" : "DIFFERS from a fresh generation");
        differing += same ? 0 : 1;
      }
    }
  } catch (const std::exception& e) {
    std::fprintf(stderr, "plb_targets: %s\n", e.what());
    return 2;
  }
  return differing == 0 ? 0 : 1;
}
