#pragma once
// One symplectic Euler step of the mass-spring cloth, its hand-written reverse, and whole
// episodes recorded on a tape and run backwards. Model and state: envs/cloth/cloth_model.hpp.
//
// Step t, from (x, v) at time t dt to time (t + 1) dt, vertex by vertex in index order:
//   pin       x_a = p_a(t) for every anchor a held during step t
//   forces    f_i = m_i g + sum over springs s = (i, j) at i of F_s e_s, with d = x_j - x_i,
//             l = |d|, e = d / l, F = k (l - L0) + c (v_j - v_i) . e   (Hooke + dashpot)
//   velocity  v'_i = exp(-damping dt) (v_i + dt f_i / m_i)
//   contact   for each surface in order, if distance(x_i) <= 0 and (v'_i - u) . n < 0 with the
//             surface's normal n and velocity u at x_i: w = v'_i - u, w_n = w . n,
//             v'_i = u + tangential_keep (w - w_n n)   (the normal part no longer points inward)
//   position  x'_i = x_i + dt v'_i
//   anchors   held a: x'_a = p_a(t + 1), v'_a = (p_a(t + 1) - p_a(t)) / dt  (no contact)
// The contact test uses the position at the start of the step (the seed's template, Taichi's
// cloth tutorial), so a vertex entering a surface penetrates it by at most dt |v| once, and from
// the next step on it never moves further in.
//
// Reverse pass: the exact derivative of this discrete map. Where it is not differentiable (the
// contact switch distance = 0 or w_n = 0) it is the one-sided derivative of the branch the
// forward pass took: the distance and the sign test only gate, so a contact that just started or
// ended contributes nothing of the switch itself (same convention as envs/rigid/contact.hpp).
#include <cstdint>
#include <functional>
#include <span>
#include <vector>

#include "envs/cloth/cloth_model.hpp"

namespace dsb::cloth {

// What an episode may vary on a fixed model.
struct ClothInputs {
  std::span<const double> stiffness;  // N/m per spring (n_springs)
  // anchor positions p_a(t), m, row-major ((rows) x n_anchors): row t is time t dt; rows needed:
  // 0 .. min(release_step, steps) for each anchor (the table may be longer)
  std::span<const Vec3> anchor_path;
};

// A path table ((steps + 1) x n_anchors) from a function of (anchor index, time in s).
std::vector<Vec3> anchor_path_from(const ClothModel& m, int steps,
                                   const std::function<Vec3(int anchor, double t)>& position);

// A spring's length l = |x_j - x_i| and 1 / l at the start of a step, as the forces used them.
struct SpringLength {
  double length = 0.0, inverse = 0.0;
};

// What one step leaves for the reverse pass (spans into a ClothTape; empty: not recorded).
struct StepRecord {
  std::span<Vec3> pre_contact_v;          // velocity after forces and damping, before contact (n)
  std::span<std::uint8_t> contact;        // bit k where surface k projected the velocity (n)
  std::span<SpringLength> spring_length;  // (n_springs): the reverse pass takes no square root
};

// Spring and gravity forces f_i (n) at state s (anchors not pinned here): the forces step's.
// When `lengths` (n_springs) is given it receives each spring's length and inverse.
void cloth_forces(const ClothModel& m, std::span<const double> stiffness, const ClothState& s, std::span<Vec3> f,
                  std::span<SpringLength> lengths = {});

// One step t in place. `force` is scratch (n); `record`, when given, receives what the reverse
// pass needs.
void cloth_step(const ClothModel& m, const ClothInputs& in, int t, ClothState& s, std::span<Vec3> force,
                const StepRecord& record = {});

// dLoss/d(state) at one time
struct ClothAdjoint {
  std::vector<Vec3> x, v;  // (n), (n)
  void reset(int n);       // zeros
};

// dLoss/d(episode inputs and initial state)
struct ClothGradient {
  std::vector<Vec3> x0, v0;                         // initial positions and velocities (n), (n)
  std::vector<double> stiffness;                    // per spring, N/m: dLoss/dk; dLoss/dlog k = k dLoss/dk (n_springs)
  std::vector<double> damping;                      // per spring dashpot, N s/m (n_springs)
  std::vector<Vec3> anchor_path;                    // same shape as the path table given to the episode
  std::vector<std::vector<double>> surface_params;  // per surface (param_count each)
};

// The history of one episode: states 0..T and the StepRecord of steps 0..T-1. Memory per step
// 73 bytes per vertex (x, v, pre-contact v, flags) and 16 per spring (length, inverse): the swing
// cloth (81 vertices, 398 springs, 1,600 steps) holds 19.6 MB, the pancake (81, 398, 1,000
// steps) 12.3 MB, so it is stored whole, not checkpointed (bench_cloth: peak RSS 22 and 14 MB).
// Buffers are kept between episodes (no allocation once the size is reached).
class ClothTape {
 public:
  void reset(int vertices, int springs, int steps);
  int steps() const { return steps_; }
  int vertices() const { return n_; }
  std::span<Vec3> x(int t) { return {x_.data() + std::size_t(t) * n_, std::size_t(n_)}; }  // after pinning
  std::span<Vec3> v(int t) { return {v_.data() + std::size_t(t) * n_, std::size_t(n_)}; }
  std::span<Vec3> pre_contact_v(int t) { return {vp_.data() + std::size_t(t) * n_, std::size_t(n_)}; }
  std::span<const Vec3> x(int t) const { return {x_.data() + std::size_t(t) * n_, std::size_t(n_)}; }
  std::span<const Vec3> v(int t) const { return {v_.data() + std::size_t(t) * n_, std::size_t(n_)}; }
  std::span<const Vec3> pre_contact_v(int t) const { return {vp_.data() + std::size_t(t) * n_, std::size_t(n_)}; }
  // bit k set where surface k projected the vertex's velocity in step t (n)
  std::span<std::uint8_t> contact(int t) { return {contact_.data() + std::size_t(t) * n_, std::size_t(n_)}; }
  std::span<const std::uint8_t> contact(int t) const {
    return {contact_.data() + std::size_t(t) * n_, std::size_t(n_)};
  }
  std::span<const SpringLength> spring_length(int t) const {
    return {lengths_.data() + std::size_t(t) * springs_, std::size_t(springs_)};
  }
  // where step t writes its record
  StepRecord record(int t) {
    return {pre_contact_v(t), contact(t), {lengths_.data() + std::size_t(t) * springs_, std::size_t(springs_)}};
  }
  std::span<Vec3> scratch() { return {scratch_.data(), scratch_.size()}; }

 private:
  int n_ = 0, springs_ = 0, steps_ = 0;
  std::vector<Vec3> x_, v_, vp_, scratch_;
  std::vector<std::uint8_t> contact_;
  std::vector<SpringLength> lengths_;
};

// Runs `steps` steps from s0, recording every state on the tape (tape.x(t), tape.v(t) is the
// state at time t; x(t) of a held anchor is its pinned position). Returns the final state.
ClothState cloth_rollout(const ClothModel& m, const ClothInputs& in, const ClothState& s0, int steps, ClothTape& tape);

// Reverse of step t of the episode on `tape` (the state it started from after pinning and its
// record; surfaces are sampled again only where they acted). `adj` holds dLoss/d(state after the
// step) on entry and dLoss/d(state before) on exit; stiffness, damping, anchor path and surface
// gradients are added to `grad` (sized by the caller). Uses the tape's scratch.
void cloth_step_adjoint(const ClothModel& m, const ClothInputs& in, ClothTape& tape, int t, ClothAdjoint& adj,
                        ClothGradient& grad);

// Runs the episode recorded on `tape` backwards. `final_bar` is dLoss/d(final state); when
// `per_step` is given it is called at every t = T, T-1, ..., 0 with the state at time t and may
// add dLoss/d(state at t) to `adj` (at t = T on top of final_bar). `grad` is resized and filled
// (anchor_path like in.anchor_path).
void cloth_rollout_adjoint(
    const ClothModel& m, const ClothInputs& in, ClothTape& tape, const ClothAdjoint& final_bar,
    const std::function<void(int t, std::span<const Vec3> x, std::span<const Vec3> v, ClothAdjoint& adj)>& per_step,
    ClothGradient& grad);

// Mechanical energy: kinetic, spring (1/2 k (l - L0)^2 summed) and gravity (-m g . x) terms, J.
struct ClothEnergy {
  double kinetic = 0.0, spring = 0.0, gravity = 0.0;
  double total() const { return kinetic + spring + gravity; }
};
ClothEnergy cloth_energy(const ClothModel& m, std::span<const double> stiffness, const ClothState& s);

}  // namespace dsb::cloth
