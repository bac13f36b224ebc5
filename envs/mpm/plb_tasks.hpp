#pragma once
// PlasticineLab's eight tasks as data (PlasticineLab's task files): the simulator's
// per-task overrides, the plasticine shapes and particle counts, the manipulators (primitives with
// their poses, sizes, bounds and action scales), the figures of PlasticineLab's target (to compare
// ours with), and our scripted reference motion, whose final state is the target (PlasticineLab
// ships targets made by undocumented reference solutions), or where no motion of ours reaches
// PlasticineLab's shape (rope) a constructed target. A ninth task is one more entry of plb_tasks().
#include <functional>
#include <string>
#include <vector>

#include "envs/mpm/mpm_types.hpp"
#include "envs/mpm/primitive.hpp"

namespace dsb::mpm {

// A plasticine shape, sampled uniformly (PlasticineLab's shape maker: a box uniformly in
// [-size/2, size/2] + centre; a sphere as a Gaussian direction x U^(1/3) x radius).
struct PlbShape {
  enum class Kind { box, sphere } kind = Kind::box;
  Vec3 centre = Vec3::Zero();
  Vec3 size = Vec3::Zero();  // box: full edge lengths
  double radius = 0.0;       // sphere
  int particles = 0;
};

// A segment of the scripted reference motion: `steps` env steps with these actions (all
// primitives' actions of one env step, in [-1, 1]).
struct PlbPhase {
  int steps = 0;
  std::vector<double> actions;
};

// A connected body of PlasticineLab's target (v1, measured from its asset file): target_shape.hpp's
// figures, cells above 1% of the grid's maximum, node (i, j, k) at (i, j, k)/64
struct PlbTargetBody {
  Vec3 centre = Vec3::Zero();
  Vec3 lo = Vec3::Zero(), hi = Vec3::Zero();  // bounding box of the body's cells
};

// Every PlasticineLab target grid sums to the mass of 10,000 particles, 10000 (dx/2)^2 = 0.6103516,
// Pinch's (6,000 particles) and TripleMove's (9,999) included: ours are scaled to it
// (tools/plb_targets.cpp).
constexpr int kPlbTargetParticles = 10000;

struct PlbTask {
  std::string name;  // the env is "plb-" + name
  // PlasticineLab's simulator overrides (defaults: its SIMULATOR node)
  double youngs_modulus = 5e3;
  double poisson_ratio = 0.2;
  double yield_stress = 50.0;
  double floor_friction = 1.5;
  std::vector<PlbShape> shapes;
  std::vector<PrimitiveSpec> primitives;  // the manipulators first, then static ones (action dim 0)
  std::vector<PlbPhase> reference;        // 50 env steps in all
  // A constructed target, where our scripted motions do not reach PlasticineLab's shape: where each
  // of the task's initial particles is placed (its position in, its place in the target out); the
  // target is then their grid mass, as a motion's final state gives it. Null: the target is the
  // reference motion's final state. `construction` says what it does, in words (in the env config).
  std::function<Vec3(const Vec3&)> target_placement;
  std::string construction;
  // PlasticineLab's target: its bodies (one, TripleMove's three blocks); a single body's centre is
  // the whole target's centre of mass
  std::vector<PlbTargetBody> plb_target;
  // PlasticineLab's file of that target in its assets folder (plb/envs/assets), e.g. "Pinch3D-v1.npy"
  std::string plb_asset;
};

const std::vector<PlbTask>& plb_tasks();
const PlbTask* find_plb_task(const std::string& name);  // nullptr if unknown

}  // namespace dsb::mpm
