#include "envs/mpm/plb_loss.hpp"

#include <algorithm>
#include <cmath>

#include "common/parallel.hpp"
#include "envs/mpm/kernel.hpp"
#include "envs/mpm/substep.hpp"

namespace dsb::mpm {

namespace {

// sums over the active nodes: sum d m, sum (|m - t| - t), sum m t, sum m, max m
struct NodeSums {
  double dm = 0.0, dev = 0.0, mt = 0.0, m = 0.0, max_m = 0.0;
};

NodeSums add(NodeSums a, const NodeSums& b) {
  a.dm += b.dm;
  a.dev += b.dev;
  a.mt += b.mt;
  a.m += b.m;
  a.max_m = std::max(a.max_m, b.max_m);
  return a;
}

double sign(double v) { return v > 0.0 ? 1.0 : (v < 0.0 ? -1.0 : 0.0); }

struct Closest {
  double d = std::numeric_limits<double>::infinity();
  int p = -1;
};

}  // namespace

PlbLossScratch::PlbLossScratch(const MpmModel& model) {
  mass.assign(model.layout.nodes(), 0.0);
  bins.home.resize(model.particles());
}

void grid_mass(const MpmModel& m, const std::vector<Particle>& particles, ThreadTeam& team, ParticleBins& bins,
               std::vector<double>& mass) {
  const GridLayout& L = m.layout;
  const double inv_dx = 1.0 / m.config.dx;
  mass.resize(L.nodes());
  bin_particles(m, bins, team, particles);
  for (int b : bins.active) for_each_node_of_block(L, b, [&](int, int, int, int n) { mass[n] = 0.0; });
  // m_I = sum_p w_Ip m_p, scattered colour by colour (grid.hpp)
  for_each_particle_by_colour(bins, team, [&](int p) {
    const Stencil s = make_stencil(particles[p].x, inv_dx, L);
    const double mp = m.mass[p];
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) {
        const double wij = s.w[0][i] * s.w[1][j] * mp;
        const int row = L.node(s.base[0] + i, s.base[1] + j, s.base[2]);
        for (int k = 0; k < 3; ++k) mass[row + k] += wij * s.w[2][k];
      }
  });
}

void PlbObjective::grid_mass(const std::vector<Particle>& particles, ThreadTeam& team) const {
  mpm::grid_mass(model_.mpm, particles, team, scratch_.bins, scratch_.mass);
}

std::pair<double, int> PlbObjective::closest(int k, const std::vector<Particle>& particles, const Pose& pose,
                                             ThreadTeam& team) const {
  const PrimitiveSpec& spec = model_.mpm.primitives[k];
  const Closest c = parallel_reduce<Closest>(
      team, static_cast<std::int64_t>(particles.size()), kParticleGrain * 4, Closest{}, Closest{},
      [&](std::int64_t begin, std::int64_t end, Closest acc) {
        for (std::int64_t p = begin; p < end; ++p) {
          const double d = std::max(primitive_distance(spec, pose, particles[p].x), 0.0);
          if (d < acc.d) acc = {d, static_cast<int>(p)};
        }
        return acc;
      },
      [](const Closest& a, const Closest& b) { return b.d < a.d ? b : a; });
  return {c.d, c.p};
}

PlbLossTerms PlbObjective::terms(const std::vector<Particle>& particles, const std::vector<Pose>& poses,
                                 ThreadTeam& team) const {
  grid_mass(particles, team);
  const GridLayout& L = model_.mpm.layout;
  const std::vector<double>& t = model_.target.values;
  const std::vector<double>& d = model_.target_sdf;
  const std::vector<int>& active = scratch_.bins.active;
  const NodeSums s = parallel_reduce<NodeSums>(
      team, static_cast<std::int64_t>(active.size()), kBlockGrain, NodeSums{}, NodeSums{},
      [&](std::int64_t begin, std::int64_t end, NodeSums acc) {
        for (std::int64_t b = begin; b < end; ++b)
          for_each_node_of_block(L, active[b], [&](int, int, int, int n) {
            const double m = scratch_.mass[n];
            acc.dm += d[n] * m;
            acc.dev += std::abs(m - t[n]) - std::abs(t[n]);
            acc.mt += m * t[n];
            acc.m += m;
            acc.max_m = std::max(acc.max_m, m);
          });
        return acc;
      },
      add);
  PlbLossTerms r;
  r.sdf = s.dm;
  // sum over every node of |m - t|: nodes outside the active blocks have m = 0 and add |t| (a
  // target's tiny negatives included: plb_target_file.hpp)
  r.density = s.dev + model_.target_abs_sum;
  for (int k : model_.movable) {
    const double c = closest(k, particles, poses[k], team).first;
    r.contact += c * c;
  }
  // soft IoU (PlasticineLab): S = sum m t / (max m max t), IoU = S / (sum m / max m + sum t / max t - S)
  if (s.max_m > 0.0 && model_.target_max > 0.0) {
    const double S = s.mt / (s.max_m * model_.target_max);
    r.iou = S / (s.m / s.max_m + model_.target_sum / model_.target_max - S);
  }
  return r;
}

double PlbObjective::step_loss(int step, const std::vector<Particle>& particles, const std::vector<Pose>& poses,
                               ThreadTeam& team) const {
  const PlbLossTerms r = terms(particles, poses, team);
  if (step == cfg_.env_steps - 1) scratch_.final_iou = r.iou;
  return cfg_.sdf_weight * r.sdf + cfg_.density_weight * r.density + cfg_.contact_weight * r.contact;
}

void PlbObjective::step_loss_adjoint(int, const std::vector<Particle>& particles, const std::vector<Pose>& poses,
                                     std::vector<ParticleAdjoint>& adj, std::vector<PoseAdjoint>& pose_adj,
                                     ThreadTeam& team) const {
  const MpmModel& m = model_.mpm;
  const GridLayout& L = m.layout;
  const double inv_dx = 1.0 / m.config.dx;
  grid_mass(particles, team);
  const std::vector<double>& t = model_.target.values;
  const std::vector<double>& d = model_.target_sdf;
  // dL/dm_I = w_sdf d_I + w_density sign(m_I - t_I); x_bar_p += m_p sum_I dL/dm_I grad w_Ip
  parallel_for_per_thread(team, m.particles(), [&](std::int64_t begin, std::int64_t end) {
    for (std::int64_t p = begin; p < end; ++p) {
      const Stencil s = make_stencil(particles[p].x, inv_dx, L);
      Vec3 g = Vec3::Zero();
      for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) {
          const int row = L.node(s.base[0] + i, s.base[1] + j, s.base[2]);
          for (int k = 0; k < 3; ++k) {
            const int n = row + k;
            const double mbar = cfg_.sdf_weight * d[n] + cfg_.density_weight * sign(scratch_.mass[n] - t[n]);
            g += mbar * weight_gradient(s, i, j, k);
          }
        }
      adj[p].x += m.mass[p] * g;
    }
  });
  // contact: w (max(sdf(x_p*), 0))^2 through the closest particle and the manipulator's pose
  for (int k : model_.movable) {
    const auto [c, p] = closest(k, particles, poses[k], team);
    if (!(c > 0.0) || p < 0) continue;
    primitive_distance_adjoint(m.primitives[k], poses[k], particles[p].x, 2.0 * cfg_.contact_weight * c, adj[p].x,
                               pose_adj[k]);
  }
}

}  // namespace dsb::mpm
