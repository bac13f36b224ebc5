// The PlasticineLab tasks' targets: each task's scripted reference motion (plb_tasks.cpp) run by
// our engine, its final grid mass written as data/targets/plb-<task>.txt.gz; and the check that
// stored targets equal a fresh generation (decoded values, bit for bit).
//   plb_targets --out DIR [--task NAME]      write targets, print bounding boxes vs PlasticineLab's
//   plb_targets --check DIR [--task NAME]    generate and compare with DIR's files (exit 1 on a difference)
#include <cmath>
#include <cstdio>
#include <cstring>
#include <string>
#include <vector>

#include "common/error.hpp"
#include "common/parallel.hpp"
#include "envs/mpm/episode.hpp"
#include "envs/mpm/plb_env.hpp"
#include "envs/mpm/plb_loss.hpp"
#include "envs/mpm/plb_scene.hpp"
#include "envs/mpm/target_grid.hpp"

namespace {

using namespace dsb;
using namespace dsb::mpm;

class NoLoss : public EpisodeObjective {
 public:
  double step_loss(int, const std::vector<Particle>&, const std::vector<Pose>&, ThreadTeam&) const override { return 0.0; }
  void step_loss_adjoint(int, const std::vector<Particle>&, const std::vector<Pose>&, std::vector<ParticleAdjoint>&,
                         std::vector<PoseAdjoint>&, ThreadTeam&) const override {}
};

// the reference motion's final grid mass on the scene's nodes
NodeGrid generate(const PlbTask& task, ThreadTeam& team) {
  const PlbConfig cfg = plb_config(task.name);
  const MpmModel model = build_plb_scene(cfg);
  MpmWorkspace ws(model);
  const auto actions = plb_reference_actions(task, cfg.env_steps);
  const double loss = run_episode(model, ws, team, actions, cfg.env_steps, NoLoss{});
  if (std::isnan(loss)) throw std::runtime_error("the reference motion of " + task.name + " blew up");
  ParticleBins bins;
  bins.home.resize(model.particles());
  std::vector<double> mass;
  grid_mass(model, ws.particles, team, bins, mass);
  NodeGrid g;
  g.n = model.layout.n;
  g.values.assign(model.layout.nodes(), 0.0);
  for (int b : bins.active) for_each_node_of_block(model.layout, b, [&](int, int, int, int n) { g.values[n] = mass[n]; });
  return g;
}

// bounding box of nodes above 1e-4 (positions) and centre of mass
void describe(const PlbTask& task, const NodeGrid& g, double dx, int pad) {
  double lo[3] = {1e9, 1e9, 1e9}, hi[3] = {-1e9, -1e9, -1e9}, c[3] = {0, 0, 0}, total = 0.0;
  for (int i = 0; i < g.n[0]; ++i)
    for (int j = 0; j < g.n[1]; ++j)
      for (int k = 0; k < g.n[2]; ++k) {
        const double v = g.values[(static_cast<std::size_t>(i) * g.n[1] + j) * g.n[2] + k];
        const double x[3] = {(i - pad) * dx, (j - pad) * dx, (k - pad) * dx};
        total += v;
        for (int a = 0; a < 3; ++a) c[a] += v * x[a];
        if (v > 1e-4)
          for (int a = 0; a < 3; ++a) {
            lo[a] = std::min(lo[a], x[a]);
            hi[a] = std::max(hi[a], x[a]);
          }
      }
  std::printf("%-11s ours: x [%.3f, %.3f] y [%.3f, %.3f] z [%.3f, %.3f] centre (%.3f, %.3f, %.3f) mass %.4f\n",
              task.name.c_str(), lo[0], hi[0], lo[1], hi[1], lo[2], hi[2], c[0] / total, c[1] / total, c[2] / total, total);
  const auto& b = task.plb_bbox;
  std::printf("%-11s PlasticineLab: x [%.2f, %.2f] y [%.2f, %.2f] z [%.2f, %.2f] centre (%.3f, %.3f, %.3f)\n", "", b[0],
              b[1], b[2], b[3], b[4], b[5], task.plb_centre.x(), task.plb_centre.y(), task.plb_centre.z());
}

}  // namespace

int main(int argc, char** argv) {
  std::string out, check, only;
  for (int i = 1; i + 1 < argc; i += 2) {
    if (!std::strcmp(argv[i], "--out")) out = argv[i + 1];
    else if (!std::strcmp(argv[i], "--check")) check = argv[i + 1];
    else if (!std::strcmp(argv[i], "--task")) only = argv[i + 1];
  }
  if (out.empty() == check.empty()) {
    std::fprintf(stderr, "usage: plb_targets --out DIR | --check DIR [--task NAME]\n");
    return 2;
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
        std::printf("%-11s %s\n", "", same ? "stored target equals a fresh generation" : "DIFFERS from a fresh generation");
        differing += same ? 0 : 1;
      }
    }
  } catch (const std::exception& e) {
    std::fprintf(stderr, "plb_targets: %s\n", e.what());
    return 2;
  }
  return differing == 0 ? 0 : 1;
}
