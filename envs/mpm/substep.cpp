#include "envs/mpm/substep.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>

#include "common/parallel.hpp"
#include "envs/mpm/kernel.hpp"
#include "envs/mpm/substep_lanes.hpp"

namespace dsb::mpm {

namespace {

// 1. stress phase: A_p and the new F (or J) of every particle. Solids go through
// solid_update_batch in chunks (SVDs, logarithms and exponentials batched: the same bits as one
// particle at a time, several times faster).
void stress_phase(const MpmModel& model, MpmWorkspace& ws, ThreadTeam& team, SubstepTape* tape) {
  const MpmConfig& cfg = model.config;
  const double k_stress = 4.0 * cfg.dt / (cfg.dx * cfg.dx);
  parallel_for_per_thread(team, model.particles(), [&](std::int64_t begin, std::int64_t end) {
    std::array<SolidTape, kSolidBatch> tapes;
    std::array<Mat3, kSolidBatch> F, tau;
    std::array<Svd3, kSolidBatch> svd;
    std::array<const Material*, kSolidBatch> mats;
    std::array<int, kSolidBatch> index;
    int n = 0;
    // finish the solids gathered so far
    auto flush = [&] {
      svd3_batch(F.data(), svd.data(), n);
      for (int i = 0; i < n; ++i) tapes[i].svd = svd[i];
      if (tape)
        for (int i = 0; i < n; ++i) tape->svd[index[i]] = record_svd(svd[i]);
      solid_update_batch(mats.data(), F.data(), tapes.data(), tau.data(), n);
      for (int i = 0; i < n; ++i) {
        const int p = index[i];
        Particle& P = ws.particles[p];
        P.F = F[i];
        // A = -(4 dt V / dx^2) tau + m C
        ws.affine[p] = -(k_stress * model.volume[p]) * tau[i] + model.mass[p] * P.C;
      }
      n = 0;
    };
    for (std::int64_t p = begin; p < end; ++p) {
      Particle& P = ws.particles[p];
      const Material& mat = model.materials[model.material_of[p]];
      if (mat.kind == MaterialKind::fluid) {
        const Mat3 t = fluid_update(mat, P.C, cfg.dt, P.J);
        ws.affine[p] = -(k_stress * model.volume[p]) * t + model.mass[p] * P.C;
        continue;
      }
      // F_tmp = (I + dt C) F
      F[n] = trial_deformation(P.C, cfg.dt, P.F);
      mats[n] = &mat;
      index[n] = static_cast<int>(p);
      if (++n == kSolidBatch) flush();
    }
    flush();
  });
}

}  // namespace

void bin_particles(const MpmModel& model, ParticleBins& bins, ThreadTeam& team, const std::vector<Particle>& parts) {
  const double inv_dx = 1.0 / model.config.dx;
  const GridLayout& L = model.layout;
  parallel_for_per_thread(team, model.particles(), [&](std::int64_t begin, std::int64_t end) {
    for (std::int64_t p = begin; p < end; ++p) {
      const Stencil s = make_stencil(parts[p].x, inv_dx, L);
      bins.home[p] = L.unit(s.base[0] >> kUnitLog2, s.base[1] >> kUnitLog2, s.base[2] >> kUnitLog2);
    }
  });
  bins.rebuild(L);
}

namespace {

// 3. P2G, colour by colour
void p2g(const MpmModel& model, MpmWorkspace& ws, const ParticleBins& bins, ThreadTeam& team) {
  const MpmConfig& cfg = model.config;
  const double dx = cfg.dx, inv_dx = 1.0 / dx;
  const GridLayout& L = model.layout;
  GridFields& g = ws.grid;
  for_each_particle_by_colour(bins, team, [&](int p) {
    const Particle& P = ws.particles[p];
    const Stencil s = make_stencil(P.x, inv_dx, L);
    const double mp = model.mass[p];
    const Mat3& A = ws.affine[p];
    // (q_i, m_i) += w (m v + A dpos, m), dpos = (o - fx) dx: a base term and one column of
    // dx A per axis
    Vec4 base_term;
    base_term << mp * P.v - dx * (A * s.fx), mp;
    Vec4 a0, a1, a2;
    a0 << dx * A.col(0), 0.0;
    a1 << dx * A.col(1), 0.0;
    a2 << dx * A.col(2), 0.0;
    scatter_affine(s, L, base_term, a0, a1, a2, g.mq);
  });
}

// 5. grid update on the active blocks
void grid_update(const MpmModel& model, MpmWorkspace& ws, const ParticleBins& bins, ThreadTeam& team) {
  const MpmConfig& cfg = model.config;
  const GridLayout& L = model.layout;
  GridFields& g = ws.grid;
  const std::vector<int>& active = bins.active;
  const Vec3 dv_gravity = cfg.dt * cfg.gravity;
  const int np = static_cast<int>(model.primitives.size());
  parallel_for_per_thread(team, static_cast<std::int64_t>(active.size()), [&](std::int64_t begin, std::int64_t end) {
    for (std::int64_t bb = begin; bb < end; ++bb)
      for_each_node_of_block(L, active[bb], [&](int i, int j, int k, int n) {
        const double m = g.mq[n].w();
        if (!(m > cfg.grid_mass_epsilon)) {
          g.v[n].setZero();
          return;
        }
        // v = q / m + dt g
        Vec3 v = g.mq[n].head<3>() / m + dv_gravity;
        const Vec3 x((i - L.pad) * cfg.dx, (j - L.pad) * cfg.dx, (k - L.pad) * cfg.dx);
        for (int pr = 0; pr < np; ++pr) v = collide(model.primitives[pr], ws.frames[pr], x, v);
        const int I[3] = {i - L.pad, j - L.pad, k - L.pad};  // position indices
        apply_boundary(cfg, I, v);
        g.v[n] = v;
      });
  });
}

// 6. G2P and advection
void g2p(const MpmModel& model, MpmWorkspace& ws, ThreadTeam& team) {
  const MpmConfig& cfg = model.config;
  const double dx = cfg.dx, inv_dx = 1.0 / dx;
  const GridLayout& L = model.layout;
  const GridFields& g = ws.grid;
  const double lo = cfg.clamp_low();
  const Vec3 hi(cfg.clamp_high(0), cfg.clamp_high(1), cfg.clamp_high(2));
  parallel_for_per_thread(team, model.particles(), [&](std::int64_t begin, std::int64_t end) {
    for (std::int64_t p = begin; p < end; ++p) {
      Particle& P = ws.particles[p];
      const Stencil s = make_stencil(P.x, inv_dx, L);
      // v = sum w v_i and B = sum w v_i o^T (integer offsets o), by axis: the z sums first
      Vec3 v = Vec3::Zero();
      Mat3 B = Mat3::Zero();
      for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) {
          const int row = L.node(s.base[0] + i, s.base[1] + j, s.base[2]);
          const Vec3 vz = s.w[2][0] * g.v[row] + s.w[2][1] * g.v[row + 1] + s.w[2][2] * g.v[row + 2];
          const Vec3 vzk = s.w[2][1] * g.v[row + 1] + (2.0 * s.w[2][2]) * g.v[row + 2];
          const double wij = s.w[0][i] * s.w[1][j];
          v += wij * vz;
          B.col(0) += (wij * i) * vz;
          B.col(1) += (wij * j) * vz;
          B.col(2) += wij * vzk;
        }
      // C = (4 / dx^2) sum w v_i (x_i - x_p)^T = (4 / dx) (B - v fx^T)
      P.C = (4.0 * inv_dx) * (B - v * s.fx.transpose());
      P.v = v;
      // x += dt v, clamped to the domain
      const Vec3 x = P.x + cfg.dt * v;
      for (int a = 0; a < 3; ++a) P.x[a] = std::min(std::max(x[a], lo), hi[a]);
    }
  });
}

}  // namespace

namespace {

// The lower wall of axis a on velocity w (PlasticineLab's boundary): walls zero the outward
// component; the floor (a = y) applies Coulomb friction, |v_t| = sqrt(v_x^2 + v_z^2 + 1e-8),
// v = max(1 + mu v_y / |v_t|, 0) (v_x, 0, v_z), or sticks when mu >= 10. Sets `hit`.
Vec3 lower_wall(const MpmConfig& cfg, int a, const int I[3], const Vec3& w, bool& hit) {
  hit = I[a] < cfg.bound && w[a] < 0.0;
  if (!hit) return w;
  Vec3 v = w;
  if (a != 1 || cfg.floor_friction == 0.0) {
    v[a] = 0.0;
  } else if (cfg.floor_friction >= 10.0) {
    v.setZero();  // sticky floor
  } else {
    const double tn = std::sqrt(w.x() * w.x() + w.z() * w.z() + 1e-8);
    const double f = std::max(1.0 + cfg.floor_friction * w.y() / tn, 0.0);
    v = Vec3(f * w.x(), 0.0, f * w.z());
  }
  return v;
}

// the upper wall of axis a (PlasticineLab: index > n - bound) zeroes an outward component
bool upper_wall_hit(const MpmConfig& cfg, int a, const int I[3], const Vec3& v) {
  return I[a] > cfg.grid[a] - cfg.bound && v[a] > 0.0;
}

}  // namespace

void apply_boundary(const MpmConfig& cfg, const int I[3], Vec3& v) {
  for (int a = 0; a < 3; ++a) {
    bool hit;
    v = lower_wall(cfg, a, I, v, hit);
    if (upper_wall_hit(cfg, a, I, v)) v[a] = 0.0;
  }
}

Vec3 apply_boundary_adjoint(const MpmConfig& cfg, const int I[3], const Vec3& v_in, const Vec3& v_out_bar) {
  // forward again, keeping the velocity before each axis and after its lower wall
  Vec3 before[3], mid[3];
  bool lower[3];
  Vec3 v = v_in;
  for (int a = 0; a < 3; ++a) {
    before[a] = v;
    mid[a] = lower_wall(cfg, a, I, v, lower[a]);
    v = mid[a];
    if (upper_wall_hit(cfg, a, I, v)) v[a] = 0.0;
  }
  Vec3 bar = v_out_bar;
  for (int a = 2; a >= 0; --a) {
    if (upper_wall_hit(cfg, a, I, mid[a])) bar[a] = 0.0;
    if (!lower[a]) continue;
    const Vec3& w = before[a];
    if (a != 1 || cfg.floor_friction == 0.0) {
      bar[a] = 0.0;
    } else if (cfg.floor_friction >= 10.0) {
      bar.setZero();
    } else {
      const double mu = cfg.floor_friction;
      const double tn = std::sqrt(w.x() * w.x() + w.z() * w.z() + 1e-8);
      const double f = 1.0 + mu * w.y() / tn;
      if (f <= 0.0) {
        bar.setZero();
      } else {
        // v_h = f w_h (h = x, z): df/dw_y = mu / tn, df/dw_h = -mu w_y w_h / tn^3
        const double s = bar.x() * w.x() + bar.z() * w.z();
        const double t3 = tn * tn * tn;
        bar = Vec3(f * bar.x() - s * mu * w.y() * w.x() / t3, s * mu / tn, f * bar.z() - s * mu * w.y() * w.z() / t3);
      }
    }
  }
  return bar;
}

PhaseClock::PhaseClock(PhaseTimes* times) : times_(times) {
  if (times_) last_ = std::chrono::steady_clock::now();
}

void PhaseClock::lap(double PhaseTimes::*phase) {
  if (!times_) return;
  const auto now = std::chrono::steady_clock::now();
  times_->*phase += std::chrono::duration<double>(now - last_).count();
  last_ = now;
}

void substep(const MpmModel& model, MpmWorkspace& ws, ThreadTeam& team, const double* actions, SubstepTape* tape) {
  const MpmConfig& cfg = model.config;
  PhaseClock clock(ws.phase_times);
  ParticleBins& bins = tape ? tape->bins : ws.bins;
  if (tape) {
    copy_in_parts(team, ws.particles, tape->before);
    tape->poses = ws.poses;
    clock.lap(&PhaseTimes::other);
  }
  bin_particles(model, bins, team, ws.particles);
  clock.lap(&PhaseTimes::bin);
  const LaneKernels* lanes = lane_kernels(ws.lanes);
  if (lanes)
    stress_phase_lanes(model, ws, team, tape, *lanes);
  else
    stress_phase(model, ws, team, tape);
  clock.lap(&PhaseTimes::stress);
  clear_blocks(model.layout, bins.active, ws.grid, team);
  clock.lap(&PhaseTimes::bin);
  if (lanes)
    p2g_lanes(model, ws, bins, team, *lanes);
  else
    p2g(model, ws, bins, team);
  clock.lap(&PhaseTimes::p2g);
  // 4. kinematics pose f -> f + 1 and the contact frames
  const int np = static_cast<int>(model.primitives.size());
  for (int pr = 0; pr < np; ++pr) {
    const PrimitiveSpec& spec = model.primitives[pr];
    ws.next_poses[pr] = advance_pose(spec, ws.poses[pr], actions + model.action_offset(pr), cfg.substeps);
    ws.frames[pr] = contact_frame(spec, ws.poses[pr], ws.next_poses[pr], cfg.dt);
  }
  grid_update(model, ws, bins, team);
  clock.lap(&PhaseTimes::grid);
  if (tape) {
    tape->grid.save(model.layout, bins.active, ws.grid, team);
    clock.lap(&PhaseTimes::other);
  }
  if (lanes)
    g2p_lanes(model, ws, team, *lanes);
  else
    g2p(model, ws, team);
  for (int pr = 0; pr < np; ++pr) ws.poses[pr] = ws.next_poses[pr];
  clock.lap(&PhaseTimes::g2p);
}

}  // namespace dsb::mpm
