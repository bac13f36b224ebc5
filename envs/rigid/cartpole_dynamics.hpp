#pragma once
// Reduced-coordinate dynamics of a velocity-controlled cart carrying a planar chain of uniform
// rods, and the adjoint of one step. Immutable CartpoleModel + mutable CartpoleState.
//
// Coordinates: cart position x along the rail and the absolute link angles phi_i measured from
// hanging straight down (counter-clockwise positive; joint angle theta_i = phi_i - phi_{i-1}).
// Because phi = T theta with T constant, semi-implicit Euler in phi equals semi-implicit Euler in
// the joint angles theta that MuJoCo integrates.
#include <Eigen/Dense>

#include "envs/rigid/cartpole_config.hpp"

namespace dsb {

constexpr int kMaxLinks = 8;
using LinkVec = Eigen::Matrix<double, Eigen::Dynamic, 1, 0, kMaxLinks, 1>;
using LinkMat = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, 0, kMaxLinks, kMaxLinks>;

struct CartpoleModel {
  int n = 0;             // number of links
  double dt = 0.0;       // s
  double gravity = 0.0;  // m/s^2
  double length = 0.0;   // m, every link
  LinkMat mu;            // inertia couplings (n x n): M_jk = mu_jk cos(phi_j - phi_k)
  LinkVec beta;          // cart-link couplings (n): M_xk = beta_k cos(phi_k); gravity moment g beta_k sin(phi_k)

  static CartpoleModel build(const CartpoleConfig& cfg);
};

struct CartpoleState {
  double x = 0.0;   // cart position (m)
  double vx = 0.0;  // cart velocity (m/s)
  LinkVec phi;      // absolute link angles (n)
  LinkVec dphi;     // absolute angular velocities (n)
};

// adjoint of a CartpoleState: dLoss/d(each state variable)
struct CartpoleAdjoint {
  double x = 0.0, vx = 0.0;
  LinkVec phi, dphi;
};

// What the reverse pass needs from one forward step (kept by loss_and_grad, one per step).
struct CartpoleStepCache {
  LinkVec sin_phi, cos_phi;  // of the angles at the start of the step (n)
  LinkMat chol;              // lower Cholesky factor of M_ll at the start of the step (n x n)
  LinkVec ddphi;             // link accelerations of the step (n)
  double cart_accel = 0.0;   // (u - vx) / dt
};

// One semi-implicit Euler step with commanded cart speed u (m/s) and joint torques tau (n, N m):
// the cart reaches speed u in this step (a_cart = (u - vx)/dt), then v += dt a, q += dt v.
// Fills `cache` when given.
void cartpole_step(const CartpoleModel& m, CartpoleState& s, double u, const double* tau,
                   CartpoleStepCache* cache = nullptr);

// Reverse of cartpole_step. `before` is the state the step started from and `cache` what the step
// recorded; `adj` holds dLoss/d(state after the step) on entry and dLoss/d(before) on exit;
// dLoss/du and dLoss/dtau (n) are written.
void cartpole_step_adjoint(const CartpoleModel& m, const CartpoleState& before, const CartpoleStepCache& cache,
                           CartpoleAdjoint& adj, double* u_bar, double* tau_bar);

// Tip of the chain (world x, y) relative to the rail origin.
Eigen::Vector2d cartpole_tip(const CartpoleModel& m, const CartpoleState& s);

// Total mechanical energy of the chain (kinetic + potential, cart motion included), J.
double cartpole_chain_energy(const CartpoleModel& m, const CartpoleState& s, const CartpoleConfig& cfg);

CartpoleState cartpole_initial_state(const CartpoleModel& m, const CartpoleConfig& cfg);

}  // namespace dsb
