#include "envs/rigid/cartpole_dynamics.hpp"

#include <cmath>

#include "common/det_math.hpp"

namespace dsb {

CartpoleModel CartpoleModel::build(const CartpoleConfig& cfg) {
  cfg.validate();
  CartpoleModel m;
  m.n = cfg.links;
  m.dt = cfg.dt;
  m.gravity = cfg.gravity;
  m.length = cfg.link_length;
  const int n = m.n;
  const double L = cfg.link_length;
  // lever a_ik of link k's angle on the centre of mass of link i: L for k < i, L/2 for k = i
  auto lever = [&](int i, int k) { return k < i ? L : (k == i ? 0.5 * L : 0.0); };
  m.mu = LinkMat::Zero(n, n);
  m.beta = LinkVec::Zero(n);
  // mu_jk = sum_i m_i a_ij a_ik + delta_jk m_j L^2 / 12;  beta_k = sum_i m_i a_ik   (Lagrangian of the chain)
  for (int i = 0; i < n; ++i) {
    const double mi = cfg.link_masses[i];
    for (int j = 0; j < n; ++j) {
      m.beta(j) += mi * lever(i, j);
      for (int k = 0; k < n; ++k) m.mu(j, k) += mi * lever(i, j) * lever(i, k);
    }
    m.mu(i, i) += mi * L * L / 12.0;
  }
  return m;
}

CartpoleState cartpole_initial_state(const CartpoleModel& m, const CartpoleConfig& cfg) {
  CartpoleState s;
  s.phi = LinkVec::Zero(m.n);
  s.dphi = LinkVec::Zero(m.n);
  // absolute angles are running sums of the joint angles: phi = T theta
  double phi = 0.0, dphi = 0.0;
  for (int i = 0; i < m.n; ++i) {
    if (!cfg.start_joint_angles.empty()) phi += cfg.start_joint_angles[i];
    if (!cfg.start_joint_velocities.empty()) dphi += cfg.start_joint_velocities[i];
    s.phi(i) = phi;
    s.dphi(i) = dphi;
  }
  return s;
}

void cartpole_step(const CartpoleModel& m, CartpoleState& s, double u, const double* tau, CartpoleStepCache* cache) {
  const int n = m.n;
  // velocity control: the cart reaches the commanded speed within the step
  const double cart_accel = (u - s.vx) / m.dt;
  LinkVec sn(n), cs(n);
  for (int j = 0; j < n; ++j) dm::sincos(s.phi(j), &sn(j), &cs(j));
  // joint mass matrix M_jk = mu_jk cos(phi_j - phi_k) (n x n) and
  // r_j = Q_j - sum_k mu_jk sin(phi_j - phi_k) dphi_k^2 - g beta_j sin phi_j - beta_j cos phi_j a_cart,
  // with generalized forces of the joint torques Q_j = tau_j - tau_{j+1}
  LinkMat A(n, n);
  LinkVec r(n);
  for (int j = 0; j < n; ++j) {
    double rj = tau[j] - (j + 1 < n ? tau[j + 1] : 0.0);
    for (int k = 0; k < n; ++k) {
      const double cjk = cs(j) * cs(k) + sn(j) * sn(k);  // cos(phi_j - phi_k)
      const double sjk = sn(j) * cs(k) - cs(j) * sn(k);  // sin(phi_j - phi_k)
      A(j, k) = m.mu(j, k) * cjk;
      if (k != j) rj -= m.mu(j, k) * sjk * s.dphi(k) * s.dphi(k);
    }
    rj -= m.gravity * m.beta(j) * sn(j);
    rj -= m.beta(j) * cs(j) * cart_accel;
    r(j) = rj;
  }
  // ddphi = M_ll^-1 r (M_ll is symmetric positive definite)
  const Eigen::LLT<LinkMat> llt(A);
  const LinkVec ddphi = llt.solve(r);
  if (cache) {
    cache->sin_phi = sn;
    cache->cos_phi = cs;
    cache->chol = llt.matrixL();
    cache->ddphi = ddphi;
    cache->cart_accel = cart_accel;
  }
  // semi-implicit Euler: velocities first, then positions with the new velocities
  s.vx = u;
  s.dphi += m.dt * ddphi;
  s.x += m.dt * s.vx;
  s.phi += m.dt * s.dphi;
}

void cartpole_step_adjoint(const CartpoleModel& m, const CartpoleState& before, const CartpoleStepCache& c,
                           CartpoleAdjoint& adj, double* u_bar, double* tau_bar) {
  const int n = m.n;
  const double dt = m.dt;
  const LinkVec& sn = c.sin_phi;
  const LinkVec& cs = c.cos_phi;

  // reverse of the position updates: phi' = phi + dt dphi',  x' = x + dt vx'
  const LinkVec dphi_after_bar = adj.dphi + dt * adj.phi;
  const double vx_after_bar = adj.vx + dt * adj.x;
  LinkVec phi_bar = adj.phi;
  // reverse of dphi' = dphi + dt ddphi
  LinkVec dphi_bar = dphi_after_bar;
  // reverse of vx' = u
  double ubar = vx_after_bar;
  double vx_bar = 0.0;

  // reverse of ddphi = A^-1 r: r_bar = A^-1 ddphi_bar (A = L L^T symmetric), A_bar = -r_bar ddphi^T
  LinkVec lam = dt * dphi_after_bar;
  c.chol.triangularView<Eigen::Lower>().solveInPlace(lam);
  c.chol.triangularView<Eigen::Lower>().transpose().solveInPlace(lam);
  double accel_bar = 0.0;
  for (int j = 0; j < n; ++j) {
    for (int k = 0; k < n; ++k) {
      if (k == j) continue;
      const double cjk = cs(j) * cs(k) + sn(j) * sn(k);  // cos(phi_j - phi_k)
      const double sjk = sn(j) * cs(k) - cs(j) * sn(k);  // sin(phi_j - phi_k)
      // A_jk = mu_jk cos(phi_j - phi_k), A_bar_jk = -lam_j ddphi_k
      const double a_bar = -lam(j) * c.ddphi(k);
      phi_bar(j) -= a_bar * m.mu(j, k) * sjk;
      phi_bar(k) += a_bar * m.mu(j, k) * sjk;
      // r_j -= mu_jk sin(phi_j - phi_k) dphi_k^2
      const double centripetal = m.mu(j, k) * cjk * before.dphi(k) * before.dphi(k);
      phi_bar(j) -= lam(j) * centripetal;
      phi_bar(k) += lam(j) * centripetal;
      dphi_bar(k) -= lam(j) * 2.0 * m.mu(j, k) * sjk * before.dphi(k);
    }
    // r_j -= g beta_j sin phi_j + beta_j cos phi_j a_cart
    phi_bar(j) += lam(j) * (-m.gravity * m.beta(j) * cs(j) + m.beta(j) * sn(j) * c.cart_accel);
    accel_bar -= lam(j) * m.beta(j) * cs(j);
    // Q_j = tau_j - tau_{j+1}  =>  tau_bar_k = lam_k - lam_{k-1}
    tau_bar[j] = lam(j) - (j > 0 ? lam(j - 1) : 0.0);
  }
  // a_cart = (u - vx) / dt
  ubar += accel_bar / dt;
  vx_bar -= accel_bar / dt;

  *u_bar = ubar;
  adj.phi = phi_bar;
  adj.dphi = dphi_bar;
  adj.vx = vx_bar;
  // adj.x unchanged: x' = x + dt vx' passes dLoss/dx' through
}

Eigen::Vector2d cartpole_tip(const CartpoleModel& m, const CartpoleState& s) {
  // tip = (x + L sum sin phi_i, -L sum cos phi_i)
  Eigen::Vector2d tip(s.x, 0.0);
  for (int i = 0; i < m.n; ++i) {
    tip.x() += m.length * dm::sin(s.phi(i));
    tip.y() -= m.length * dm::cos(s.phi(i));
  }
  return tip;
}

double cartpole_chain_energy(const CartpoleModel& m, const CartpoleState& s, const CartpoleConfig& cfg) {
  // E = sum_i 1/2 m_i |v_ci|^2 + 1/2 I_i dphi_i^2 + m_i g y_ci   (rods, centre of mass at L/2)
  const double L = m.length;
  double energy = 0.0;
  double px = s.x, py = 0.0, vx = s.vx, vy = 0.0;  // joint position and velocity
  for (int i = 0; i < m.n; ++i) {
    const double mi = cfg.link_masses[i];
    const double sp = dm::sin(s.phi(i)), cp = dm::cos(s.phi(i));
    const double cy = py - 0.5 * L * cp;
    const double cvx = vx + 0.5 * L * cp * s.dphi(i);
    const double cvy = vy + 0.5 * L * sp * s.dphi(i);
    energy +=
        0.5 * mi * (cvx * cvx + cvy * cvy) + 0.5 * (mi * L * L / 12.0) * s.dphi(i) * s.dphi(i) + mi * m.gravity * cy;
    px += L * sp;
    py -= L * cp;
    vx += L * cp * s.dphi(i);
    vy += L * sp * s.dphi(i);
  }
  return energy;
}

}  // namespace dsb
