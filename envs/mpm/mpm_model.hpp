#pragma once
// The immutable model of one MPM scene (MuJoCo's mjModel): constants, materials, the particles'
// initial state and per-particle constants, and the primitives. Built once per env and shared by
// every rollout and thread; rollouts keep their mutable state in an MpmWorkspace (mpm_workspace.hpp).
#include <string>
#include <vector>

#include "envs/mpm/grid.hpp"
#include "envs/mpm/material.hpp"
#include "envs/mpm/mpm_config.hpp"
#include "envs/mpm/mpm_types.hpp"
#include "envs/mpm/primitive.hpp"

namespace dsb::mpm {

// The state of one particle: position, velocity, APIC affine velocity C, deformation gradient F
// (solids) and volume ratio J (fluids). 25 doubles.
struct Particle {
  Vec3 x = Vec3::Zero();
  Vec3 v = Vec3::Zero();
  Mat3 C = Mat3::Zero();
  Mat3 F = Mat3::Identity();
  double J = 1.0;
};

// The same layout holds adjoints (dL/dx, dL/dv, dL/dC, dL/dF, dL/dJ).
using ParticleAdjoint = Particle;
inline ParticleAdjoint zero_adjoint() {
  ParticleAdjoint a;
  a.F.setZero();
  a.J = 0.0;
  return a;
}

// A group of particles of one material, contiguous in the particle arrays.
struct Body {
  std::string name;
  int material = 0;
  int begin = 0, end = 0;        // particle index range
  double particle_volume = 0.0;  // rest volume V_p of each of its particles
};

struct MpmModel {
  MpmConfig config;
  GridLayout layout;
  std::vector<Material> materials;
  std::vector<Body> bodies;
  std::vector<int> material_of;   // per particle: index into materials
  std::vector<double> volume;     // per particle: rest volume V_p (its body's)
  std::vector<double> mass;       // per particle: density x volume
  std::vector<Particle> initial;  // initial particle state
  std::vector<PrimitiveSpec> primitives;
  std::vector<Pose> initial_poses;

  int particles() const { return static_cast<int>(initial.size()); }
  int action_offset(int primitive) const;  // where a primitive's actions start in an env step's actions
  int action_dim() const;                  // sum of the primitives' action dims (the actions of one env step)
  // checks sizes and ranges, fills layout, material_of, volume, mass and initial_poses, and sorts
  // each body's particles by their starting grid block (memory order follows space); throws
  // ConfigError
  void finalize(const std::string& owner);
};

}  // namespace dsb::mpm
