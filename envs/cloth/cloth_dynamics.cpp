#include "envs/cloth/cloth_dynamics.hpp"

#include <algorithm>
#include <array>
#include <stdexcept>
#include <string>

#include "common/det_math.hpp"

namespace dsb::cloth {

namespace {

// contact chain per vertex kept on the stack in the reverse pass; one bit each in the tape's flags
constexpr int kMaxSurfaces = 8;

void check_inputs(const ClothModel& m, const ClothInputs& in) {
  if (in.stiffness.size() != m.springs.size())
    throw std::invalid_argument("cloth: stiffness has " + std::to_string(in.stiffness.size()) + " entries, the model " +
                                std::to_string(m.springs.size()) + " springs");
  if (!m.anchors.empty() && in.anchor_path.size() % m.anchors.size() != 0)
    throw std::invalid_argument("cloth: anchor_path size is not a multiple of the anchor count");
  if (m.surfaces.size() > std::size_t(kMaxSurfaces))
    throw std::invalid_argument("cloth: at most " + std::to_string(kMaxSurfaces) + " contact surfaces");
}

// rows of the anchor path an episode of `steps` steps reads
int path_rows_needed(const ClothModel& m, int steps) {
  int rows = 0;
  for (const Anchor& a : m.anchors) rows = std::max(rows, std::min(a.release_step, steps) + 1);
  return rows;
}

const Vec3& path_at(const ClothModel& m, const ClothInputs& in, int t, int a) {
  return in.anchor_path[std::size_t(t) * m.anchors.size() + a];
}

// pin: x_a = p_a(t) for every anchor held during step t
void pin_anchors(const ClothModel& m, const ClothInputs& in, int t, ClothState& s) {
  for (int a = 0; a < m.anchor_count(); ++a)
    if (m.anchors[a].held_during(t)) s.x[m.anchors[a].vertex] = path_at(m, in, t, a);
}

}  // namespace

std::vector<Vec3> anchor_path_from(const ClothModel& m, int steps,
                                   const std::function<Vec3(int anchor, double t)>& position) {
  std::vector<Vec3> path(std::size_t(steps + 1) * m.anchors.size());
  for (int t = 0; t <= steps; ++t)
    for (int a = 0; a < m.anchor_count(); ++a) path[std::size_t(t) * m.anchors.size() + a] = position(a, t * m.dt);
  return path;
}

void cloth_forces(const ClothModel& m, std::span<const double> stiffness, const ClothState& s, std::span<Vec3> f,
                  std::span<SpringLength> lengths) {
  const int n = m.vertices();
  // gravity: f_i = m_i g
  for (int i = 0; i < n; ++i) f[i] = m.mass[i] * m.gravity;
  // springs in model order: F = k (l - L0) + c (v_j - v_i) . e along e = (x_j - x_i) / l
  for (std::size_t k = 0; k < m.springs.size(); ++k) {
    const Spring& sp = m.springs[k];
    const Vec3 d = s.x[sp.j] - s.x[sp.i];
    const double l = d.norm();
    const double inv_l = 1.0 / l;  // one division per spring, not three
    if (!lengths.empty()) lengths[k] = {l, inv_l};
    const Vec3 e = d * inv_l;
    const double vr = (s.v[sp.j] - s.v[sp.i]).dot(e);
    const double F = stiffness[k] * (l - sp.rest_length) + sp.damping * vr;
    f[sp.i] += F * e;
    f[sp.j] -= F * e;
  }
}

void cloth_step(const ClothModel& m, const ClothInputs& in, int t, ClothState& s, std::span<Vec3> force,
                const StepRecord& record) {
  const int n = m.vertices();
  const double dt = m.dt;
  pin_anchors(m, in, t, s);
  cloth_forces(m, in.stiffness, s, force, record.spring_length);
  // symplectic Euler velocity with global damping: v' = exp(-damping dt) (v + dt f / m)
  const double drag = dm::exp(-m.damping * dt);
  for (int i = 0; i < n; ++i) s.v[i] = drag * (s.v[i] + (dt / m.mass[i]) * force[i]);
  if (!record.pre_contact_v.empty())
    for (int i = 0; i < n; ++i) record.pre_contact_v[i] = s.v[i];
  // contact at the step's start position: remove the inward normal part of the relative velocity
  const double keep = m.tangential_keep;
  const int ns = static_cast<int>(m.surfaces.size());
  for (int i = 0; i < n; ++i) {
    std::uint8_t acted = 0;
    for (int k = 0; k < ns; ++k) {
      const SurfaceSample q = m.surfaces[k]->sample(t, s.x[i]);
      if (!(q.distance <= 0.0)) continue;
      const Vec3 w = s.v[i] - q.velocity;
      const double wn = w.dot(q.normal);
      if (wn < 0.0) {
        s.v[i] = q.velocity + keep * (w - wn * q.normal);
        acted |= std::uint8_t(1u << k);
      }
    }
    if (!record.contact.empty()) record.contact[i] = acted;
  }
  // positions with the new velocities: x' = x + dt v'
  for (int i = 0; i < n; ++i) s.x[i] += dt * s.v[i];
  // held anchors end at p(t+1) with the path's velocity (p(t+1) - p(t)) / dt
  for (int a = 0; a < m.anchor_count(); ++a) {
    if (!m.anchors[a].held_during(t)) continue;
    const int v = m.anchors[a].vertex;
    s.x[v] = path_at(m, in, t + 1, a);
    s.v[v] = (path_at(m, in, t + 1, a) - path_at(m, in, t, a)) / dt;
  }
}

void ClothAdjoint::reset(int n) {
  x.assign(n, Vec3::Zero());
  v.assign(n, Vec3::Zero());
}

void cloth_step_adjoint(const ClothModel& m, const ClothInputs& in, ClothTape& tape, int t, ClothAdjoint& adj,
                        ClothGradient& grad) {
  const std::span<const Vec3> x_t = tape.x(t), v_t = tape.v(t), pre_contact_v = tape.pre_contact_v(t);
  const std::span<const std::uint8_t> contact = tape.contact(t);
  const std::span<const SpringLength> lengths = tape.spring_length(t);
  const std::span<Vec3> f_bar = tape.scratch();
  const int n = m.vertices();
  const double dt = m.dt;
  const std::size_t na = m.anchors.size();
  // reverse of the held anchors' end state: x' = p(t+1), v' = (p(t+1) - p(t)) / dt
  for (int a = 0; a < m.anchor_count(); ++a) {
    if (!m.anchors[a].held_during(t)) continue;
    const int v = m.anchors[a].vertex;
    grad.anchor_path[std::size_t(t + 1) * na + a] += adj.x[v] + adj.v[v] / dt;
    grad.anchor_path[std::size_t(t) * na + a] -= adj.v[v] / dt;
    adj.x[v].setZero();
    adj.v[v].setZero();
  }
  const double drag = dm::exp(-m.damping * dt);
  const double keep = m.tangential_keep;
  const int ns = static_cast<int>(m.surfaces.size());
  for (int i = 0; i < n; ++i) {
    // reverse of x' = x + dt v': dL/dv' (total) = v'_bar + dt x'_bar; x_bar = x'_bar
    Vec3 ob = adj.v[i] + dt * adj.x[i];
    // contact chain replayed from the pre-contact velocity through the surfaces that acted (the
    // others are the identity): vin[k] enters surface k
    const unsigned acted = contact[i];
    std::array<Vec3, kMaxSurfaces> vin;
    Vec3 vi = pre_contact_v[i];
    for (int k = 0; acted != 0 && k < ns; ++k) {
      if (!(acted & (1u << k))) continue;
      vin[k] = vi;
      const SurfaceSample q = m.surfaces[k]->sample(t, x_t[i]);
      const Vec3 w = vi - q.velocity;
      vi = q.velocity + keep * (w - w.dot(q.normal) * q.normal);
    }
    // reverse of v = u + c (w - (w . n) n), w = vin - u, surfaces in reverse order
    for (int k = ns - 1; acted != 0 && k >= 0; --k) {
      if (!(acted & (1u << k))) continue;
      const SurfaceSample q = m.surfaces[k]->sample(t, x_t[i]);
      const Vec3& nrm = q.normal;
      const Vec3 w = vin[k] - q.velocity;
      const double wn = w.dot(nrm);
      const double obn = ob.dot(nrm);
      const Vec3 vin_bar = keep * (ob - obn * nrm);    // c (I - n n^T) ob
      const Vec3 u_bar = ob - vin_bar;                 // (I - c (I - n n^T)) ob
      const Vec3 n_bar = -keep * (obn * w + wn * ob);  // -c (w n^T + w_n I) ob
      adj.x[i] += q.dnormal_dx.transpose() * n_bar + q.dvelocity_dx.transpose() * u_bar;
      if (m.surfaces[k]->param_count() > 0)
        m.surfaces[k]->sample_adjoint(t, x_t[i], n_bar, u_bar, grad.surface_params[k]);
      ob = vin_bar;
    }
    // reverse of v' = drag (v + dt f / m): v_bar = drag vp_bar, f_bar = drag dt / m vp_bar
    adj.v[i] = drag * ob;
    f_bar[i] = (drag * dt / m.mass[i]) * ob;
  }
  // reverse of the spring forces f_i += F e, f_j -= F e, F = k (l - L0) + c vr, vr = (v_j - v_i) . e,
  // e = d / l, l = |d|, d = x_j - x_i:
  //   F_bar = e . g with g = f_bar_i - f_bar_j;  k_bar = F_bar (l - L0);  c_bar = F_bar vr;
  //   v_bar_j = -v_bar_i = c F_bar e;
  //   d_bar = (I - e e^T) e_bar / l + k F_bar e with e_bar = F g + c F_bar dv, whose part along e
  //   is F F_bar + c F_bar vr: d_bar = (F g + c F_bar dv) / l + (k F_bar - (F F_bar + c F_bar vr) / l) e
  for (std::size_t s = 0; s < m.springs.size(); ++s) {
    const Spring& sp = m.springs[s];
    const Vec3 d = x_t[sp.j] - x_t[sp.i];
    const double l = lengths[s].length, inv_l = lengths[s].inverse;  // cloth_forces' bits
    const Vec3 e = d * inv_l;
    const Vec3 dv = v_t[sp.j] - v_t[sp.i];
    const double vr = dv.dot(e);
    const double k = in.stiffness[s];
    const double stretch = l - sp.rest_length;
    const double F = k * stretch + sp.damping * vr;
    const Vec3 g = f_bar[sp.i] - f_bar[sp.j];
    const double F_bar = e.dot(g);
    grad.stiffness[s] += F_bar * stretch;
    grad.damping[s] += F_bar * vr;
    const double vr_bar = F_bar * sp.damping;
    const double along = F_bar * k - (F * F_bar + vr_bar * vr) * inv_l;
    const Vec3 d_bar = (F * inv_l) * g + (vr_bar * inv_l) * dv + along * e;
    const Vec3 ve = vr_bar * e;
    adj.v[sp.j] += ve;
    adj.v[sp.i] -= ve;
    adj.x[sp.j] += d_bar;
    adj.x[sp.i] -= d_bar;
  }
  // reverse of the pin x_a = p_a(t)
  for (int a = 0; a < m.anchor_count(); ++a) {
    if (!m.anchors[a].held_during(t)) continue;
    const int v = m.anchors[a].vertex;
    grad.anchor_path[std::size_t(t) * na + a] += adj.x[v];
    adj.x[v].setZero();
  }
}

void ClothTape::reset(int vertices, int springs, int steps) {
  n_ = vertices;
  springs_ = springs;
  steps_ = steps;
  const std::size_t states = std::size_t(steps + 1) * vertices;
  if (x_.size() < states) {
    x_.resize(states);
    v_.resize(states);
  }
  if (vp_.size() < std::size_t(steps) * vertices) vp_.resize(std::size_t(steps) * vertices);
  if (contact_.size() < std::size_t(steps) * vertices) contact_.resize(std::size_t(steps) * vertices);
  if (lengths_.size() < std::size_t(steps) * springs) lengths_.resize(std::size_t(steps) * springs);
  if (scratch_.size() < std::size_t(vertices)) scratch_.resize(vertices);
}

ClothState cloth_rollout(const ClothModel& m, const ClothInputs& in, const ClothState& s0, int steps, ClothTape& tape) {
  check_inputs(m, in);
  if (in.anchor_path.size() < std::size_t(path_rows_needed(m, steps)) * m.anchors.size())
    throw std::invalid_argument("cloth: anchor_path has fewer rows than the episode reads");
  const int n = m.vertices();
  tape.reset(n, static_cast<int>(m.springs.size()), steps);
  ClothState s = s0;
  for (int t = 0; t < steps; ++t) {
    pin_anchors(m, in, t, s);
    std::copy(s.x.begin(), s.x.end(), tape.x(t).begin());
    std::copy(s.v.begin(), s.v.end(), tape.v(t).begin());
    cloth_step(m, in, t, s, tape.scratch(), tape.record(t));
  }
  std::copy(s.x.begin(), s.x.end(), tape.x(steps).begin());
  std::copy(s.v.begin(), s.v.end(), tape.v(steps).begin());
  return s;
}

void cloth_rollout_adjoint(
    const ClothModel& m, const ClothInputs& in, ClothTape& tape, const ClothAdjoint& final_bar,
    const std::function<void(int t, std::span<const Vec3> x, std::span<const Vec3> v, ClothAdjoint& adj)>& per_step,
    ClothGradient& grad) {
  check_inputs(m, in);
  const int T = tape.steps();
  grad.stiffness.assign(m.springs.size(), 0.0);
  grad.damping.assign(m.springs.size(), 0.0);
  grad.anchor_path.assign(in.anchor_path.size(), Vec3::Zero());
  grad.surface_params.resize(m.surfaces.size());
  for (std::size_t k = 0; k < m.surfaces.size(); ++k) grad.surface_params[k].assign(m.surfaces[k]->param_count(), 0.0);
  ClothAdjoint adj = final_bar;
  if (per_step) per_step(T, tape.x(T), tape.v(T), adj);
  for (int t = T - 1; t >= 0; --t) {
    cloth_step_adjoint(m, in, tape, t, adj, grad);
    if (per_step) per_step(t, tape.x(t), tape.v(t), adj);
  }
  // the recorded x(0) of an anchor held in step 0 is its pinned position p(0): what the loss
  // said about it belongs to the path, and x0 has no effect there
  if (T > 0) {
    for (int a = 0; a < m.anchor_count(); ++a) {
      if (!m.anchors[a].held_during(0)) continue;
      const int v = m.anchors[a].vertex;
      grad.anchor_path[a] += adj.x[v];
      adj.x[v].setZero();
    }
  }
  grad.x0 = adj.x;
  grad.v0 = adj.v;
}

ClothEnergy cloth_energy(const ClothModel& m, std::span<const double> stiffness, const ClothState& s) {
  ClothEnergy e;
  // kinetic 1/2 m |v|^2 and gravity -m g . x, vertex by vertex
  for (int i = 0; i < m.vertices(); ++i) {
    e.kinetic += 0.5 * m.mass[i] * s.v[i].squaredNorm();
    e.gravity -= m.mass[i] * m.gravity.dot(s.x[i]);
  }
  // springs 1/2 k (l - L0)^2
  for (std::size_t k = 0; k < m.springs.size(); ++k) {
    const Spring& sp = m.springs[k];
    const double stretch = (s.x[sp.j] - s.x[sp.i]).norm() - sp.rest_length;
    e.spring += 0.5 * stiffness[k] * stretch * stretch;
  }
  return e;
}

}  // namespace dsb::cloth
