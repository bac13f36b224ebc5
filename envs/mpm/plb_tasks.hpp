#pragma once
// PlasticineLab's eight tasks as data (PlasticineLab's task files): the simulator's
// per-task overrides, the plasticine shapes and particle counts, the manipulators (primitives with
// their poses, sizes, bounds and action scales), PlasticineLab's target bounding box and centre of
// mass (to compare ours with), and our scripted reference motion, whose final state is the
// target (PlasticineLab ships targets made by undocumented reference solutions). A ninth task is
// one more entry of plb_tasks().
#include <array>
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
  // PlasticineLab's target (v1) bounding box of cells with mass > 1e-4 (x0, x1, y0, y1, z0, z1)
  // and centre of mass, where the facts give them (NaN where they do not)
  std::array<double, 6> plb_bbox{};
  Vec3 plb_centre = Vec3::Zero();
  // PlasticineLab's file of that target in its assets folder (plb/envs/assets), e.g. "Pinch3D-v1.npy"
  std::string plb_asset;
};

const std::vector<PlbTask>& plb_tasks();
const PlbTask* find_plb_task(const std::string& name);  // nullptr if unknown

}  // namespace dsb::mpm
