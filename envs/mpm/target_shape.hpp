#pragma once
// The figures by which a target mass grid is compared with PlasticineLab's (its v1 asset files, as
// measured for the facts): the total mass, the centre of mass, the bounding box of the cells
// whose mass exceeds a fraction (1%) of the grid's maximum, and the bodies: the face-connected
// groups of those cells (6 neighbours), each with its mass, centre and bounding box. Positions are
// node positions, node (i, j, k) of a grid with `pad` nodes below 0 at ((i, j, k) - pad) dx.
#include <vector>

#include "envs/mpm/mpm_types.hpp"
#include "envs/mpm/target_grid.hpp"

namespace dsb::mpm {

struct TargetBody {
  double mass = 0.0;  // of the body's cells
  Vec3 centre = Vec3::Zero();
  Vec3 lo = Vec3::Zero(), hi = Vec3::Zero();  // positions of its extreme cells
  long cells = 0;
};

struct TargetShape {
  double mass = 0.0;                          // every node's value, in index order
  Vec3 centre = Vec3::Zero();                 // of every node's value
  Vec3 lo = Vec3::Zero(), hi = Vec3::Zero();  // bounding box of the cells above the threshold
  long cells = 0;                             // cells above the threshold
  double threshold = 0.0;                     // fraction x the grid's maximum
  std::vector<TargetBody> bodies;             // largest (most cells) first; ties by first cell
};

// The figures of g. fraction in (0, 1); g needs a positive value (std::invalid_argument otherwise,
// and when values.size() != size()).
TargetShape describe_target_shape(const NodeGrid& g, int pad, double dx, double fraction = 0.01);

// The intersection over union of two boxes of cells, [lo, hi] inclusive of the cells at lo and hi
// (node spacing dx): the cells both hold over the cells either holds. 0 when they do not overlap.
double box_iou(const Vec3& lo_a, const Vec3& hi_a, const Vec3& lo_b, const Vec3& hi_b, double dx);

}  // namespace dsb::mpm
