#pragma once
// What the two ball scenes share: `bounce` (3-D) and `pinball-RxC` (2-D) both move one ball, a
// point mass with a contact radius and no spin, by semi-implicit Euler under gravity along -y and
// the penalty contacts of contact.hpp. Their state, their constants and the contact Jacobians a
// step keeps for its reverse pass are the same in D dimensions.
#include <cmath>

#include <Eigen/Dense>

#include "envs/rigid/contact_config.hpp"

namespace dsb {

// state of the ball, also used as its adjoint (dLoss/dposition, dLoss/dvelocity)
template <int D>
struct BallStateOf {
  Eigen::Matrix<double, D, 1> position = Eigen::Matrix<double, D, 1>::Zero();  // centre (m) (D)
  Eigen::Matrix<double, D, 1> velocity = Eigen::Matrix<double, D, 1>::Zero();  // (m/s) (D)
};

// constants of one ball rollout, from a validated config
struct BallConstants {
  double dt = 0.0;       // s
  int steps = 0;         // round(duration / dt)
  double mass = 0.0;     // kg
  double radius = 0.0;   // m, ball contact radius
  double gravity = 0.0;  // m/s^2 along -y
  ContactConfig contact;

  static BallConstants of(double dt, double duration, double mass, double radius, double gravity,
                          const ContactConfig& contact) {
    return {.dt = dt,
            .steps = static_cast<int>(std::lround(duration / dt)),
            .mass = mass,
            .radius = radius,
            .gravity = gravity,
            .contact = contact};
  }
};

// the part of a step's cache every ball scene keeps: the contact Jacobians summed over the surfaces
template <int D>
struct BallForceJacobians {
  Eigen::Matrix<double, D, D> df_dx = Eigen::Matrix<double, D, D>::Zero();  // d(total contact force)/d position (D x D)
  Eigen::Matrix<double, D, D> df_dv = Eigen::Matrix<double, D, D>::Zero();  // d(total contact force)/d velocity (D x D)
};

}  // namespace dsb
