#include "envs/mpm/plb_tasks.hpp"

#include <numbers>

#include "common/det_math.hpp"

namespace dsb::mpm {

namespace {

PlbShape box(Vec3 centre, Vec3 size, int particles) {
  PlbShape s;
  s.kind = PlbShape::Kind::box;
  s.centre = centre;
  s.size = size;
  s.particles = particles;
  return s;
}

PlbShape ball(Vec3 centre, double radius, int particles) {
  PlbShape s;
  s.kind = PlbShape::Kind::sphere;
  s.centre = centre;
  s.radius = radius;
  s.particles = particles;
  return s;
}

// a manipulator moved by 3 translation commands, `scale` per env step at command 1
PrimitiveSpec mover(const char* name, Shape shape, Vec3 position, Vec3 scale) {
  PrimitiveSpec p;
  p.name = name;
  p.shape = shape;
  p.position = position;
  p.friction = 0.9;  // PlasticineLab's primitive default
  p.motion = PrimitiveMotion::translate;
  p.action_axes = {0, 1, 2};
  p.action_scale = {scale.x(), scale.y(), scale.z()};
  return p;
}

Shape sphere_shape(double r) {
  Shape s;
  s.kind = ShapeKind::sphere;
  s.radius = r;
  return s;
}

// PlasticineLab's capsule (h, r): a segment of length h along local y; ours is by half length
Shape capsule_shape(double h, double r) {
  Shape s;
  s.kind = ShapeKind::capsule;
  s.half_height = h / 2;
  s.radius = r;
  return s;
}

// concatenated actions of several 3-command manipulators
std::vector<double> cmd(std::initializer_list<double> a) { return std::vector<double>(a); }

std::vector<PlbTask> make_tasks() {
  std::vector<PlbTask> t;

  {  // Assembly: grab the ball between the two spheres, lift it onto the box, let go
    PlbTask a;
    a.name = "assembly";
    a.plb_asset = "Assembly3D-v1.npy";
    a.yield_stress = 100.0;
    a.floor_friction = 100.0;  // sticky
    a.shapes = {box({0.6, 0.08, 0.5}, {0.16, 0.16, 0.16}, 6000), ball({0.3, 0.06, 0.5}, 0.06, 4000)};
    a.primitives = {mover("sphere_right", sphere_shape(0.04), {0.38, 0.06, 0.5}, Vec3::Constant(0.009)),
                    mover("sphere_left", sphere_shape(0.04), {0.22, 0.06, 0.5}, Vec3::Constant(0.009))};
    a.reference = {{3, cmd({-1, 0, 0, 1, 0, 0})},       // squeeze
                   {18, cmd({1, 1, 0, 1, 1, 0})},       // lift towards the box
                   {15, cmd({1, 0, 0, 1, 0, 0})},       // over the box
                   {6, cmd({0, -0.5, 0, 0, -0.5, 0})},  // set it down
                   {4, cmd({1, 0, 0, -1, 0, 0})},       // open
                   {4, cmd({0, 1, 0, 0, 1, 0})}};       // up
    a.plb_target = {{{0.600, 0.136, 0.500}, {0.516, 0.0, 0.406}, {0.719, 0.3125, 0.609}}};
    t.push_back(a);
  }
  {  // Pinch: dent the block's (+x, +z) top edge with the sphere
    PlbTask a;
    a.name = "pinch";
    a.plb_asset = "Pinch3D-v1.npy";
    a.floor_friction = 100.0;
    a.shapes = {box({0.5, 0.1, 0.5}, {0.2, 0.2, 0.2}, 6000)};
    auto s = mover("sphere", sphere_shape(0.04), {0.5, 0.35, 0.5}, Vec3::Constant(0.02));
    s.lower_bound = Vec3::Constant(0.1);
    s.upper_bound = Vec3::Constant(0.9);
    a.primitives = {s};
    // PlasticineLab's target is the block a little wider (+x, +z) and higher (to 0.25), its centre
    // of mass 0.01 towards -z: from above, the sphere comes down onto the (+x, +z) top edge to the
    // lower bound (13 steps), presses in towards the block's centre (6), backs out (6), and waits
    // (the commands found by a search over these phases against the figures of plb_target)
    a.reference = {
        {13, cmd({0.5, -1, 0.74})}, {6, cmd({-0.47, -0.83, -1})}, {6, cmd({0.46, 0.45, 1})}, {25, cmd({0, 0, 0})}};
    a.plb_target = {{{0.500, 0.104, 0.490}, {0.375, 0.0, 0.375}, {0.641, 0.25, 0.641}}};
    t.push_back(a);
  }
  {  // RollingPin: press and roll the dough flat along x
    PlbTask a;
    a.name = "rollingpin";
    a.plb_asset = "Rollingpin3D-v1.npy";
    a.shapes = {box({0.5, 0.05, 0.5}, {0.3, 0.1, 0.3}, 10000)};
    PrimitiveSpec pin;
    pin.name = "rolling_pin";
    pin.shape = capsule_shape(0.3, 0.03);
    pin.position = Vec3(0.5, 0.123, 0.5);
    pin.rotation = {0.7071067811865476, 0.7071067811865476, 0.0, 0.0};  // axis along z
    pin.friction = 0.9;
    pin.motion = PrimitiveMotion::rolling_pin;
    pin.action_scale = {0.6667, 0.0667, 0.001};  // roll (rad), yaw (rad), vertical per env step
    a.primitives = {pin};
    // back and forth along x (roll +1 moves the pin towards -x by 0.6667 x 0.03 per env step), pressing down
    a.reference = {{5, cmd({1, 0, -1})},   {10, cmd({-1, 0, -1})}, {10, cmd({1, 0, -1})},
                   {10, cmd({-1, 0, -1})}, {10, cmd({1, 0, 0})},   {5, cmd({-1, 0, 0})}};
    a.plb_target = {{{0.496, 0.046, 0.500}, {0.25, 0.0, 0.281}, {0.75, 0.141, 0.734}}};
    t.push_back(a);
  }
  {  // Rope: wrap the rope around the pillar
    PlbTask a;
    a.name = "rope";
    a.plb_asset = "Rope3D-v1.npy";
    a.floor_friction = 0.3;
    a.shapes = {box({0.5, 0.03, 0.73}, {0.6, 0.06, 0.06}, 10000)};
    PrimitiveSpec pillar;  // PlasticineLab's Cylinder(h = 0.1 radius, r = 0.2 half height), v1 position
    pillar.name = "pillar";
    pillar.shape.kind = ShapeKind::cylinder;
    pillar.shape.radius = 0.1;
    pillar.shape.half_height = 0.2;
    pillar.position = Vec3(0.3919, 0.0, 0.4991);
    pillar.friction = 0.9;
    a.primitives = {mover("sphere_left", sphere_shape(0.03), {0.22, 0.015, 0.82}, Vec3::Constant(0.01)),
                    mover("sphere_right", sphere_shape(0.03), {0.78, 0.015, 0.82}, Vec3::Constant(0.01)), pillar};
    // the reference motion pushes both ends forward (-z) around the pillar into a U; the target is
    // constructed (below)
    a.reference = {{2, cmd({0, 1, 0, 0, 1, 0})},  // to the rope's mid-height
                   {45, cmd({0.1, 0, -1, -0.6, 0, -1})},
                   {3, cmd({0, 0, 0, 0, 0, 0})}};
    a.plb_target = {{{0.393, 0.030, 0.499}, {0.219, 0.0, 0.328}, {0.578, 0.094, 0.6875}}};
    // the target: the rope wrapped fully around the pillar (the paper: BO-Leap "wraps the rope fully
    // around the pole"; PlasticineLab's target has its centre of mass on the pillar's axis), which
    // none of our scripted two-sphere motions reaches (they leave a U open behind the pillar), so
    // constructed: the rope's length goes once around the axis (its middle in front, +z, its ends
    // meeting behind), its depth (z from 0.7 to 0.76) from the pillar's surface out to kRingOuter,
    // its height as it is
    const Vec3 axis = pillar.position;
    a.target_placement = [axis](const Vec3& p) {
      constexpr double kRingOuter = 0.162, kHeight = 0.07 / 0.06;
      const double angle = 2.0 * std::numbers::pi * (p.x() - 0.5) / 0.6;
      const double radius = 0.1 + (p.z() - 0.7) / 0.06 * (kRingOuter - 0.1);
      return Vec3(axis.x() + radius * dm::sin(angle), kHeight * p.y(), axis.z() + radius * dm::cos(angle));
    };
    a.construction =
        "the rope wrapped once around the pillar's axis: a particle at (x, y, z) goes to angle "
        "2 pi (x - 0.5) / 0.6 from +z, radius 0.1 + (z - 0.7) / 0.06 x 0.055, height y";
    t.push_back(a);
  }
  {  // Table: push the (+x, -z) leg out from under the table
    PlbTask a;
    a.name = "table";
    a.plb_asset = "Table3D-v1.npy";
    a.poisson_ratio = 0.05;
    a.floor_friction = 0.3;
    for (double dx : {-0.075, 0.075})
      for (double dz : {-0.075, 0.075}) a.shapes.push_back(box({0.5 + dx, 0.1, 0.5 + dz}, {0.04, 0.1, 0.04}, 2000));
    a.shapes.push_back(box({0.5, 0.18, 0.5}, {0.2, 0.05, 0.2}, 2000));
    a.primitives = {mover("sphere", sphere_shape(0.04), {0.5, 0.06, 0.5}, Vec3(0.03, 0.0, 0.03))};
    // PlasticineLab's target reaches 0.05 beyond the table top at +x and 0.03 at -z, its centre of
    // mass moved by only (+0.004, -0.005): one leg pushed out. The sphere (under the table's centre)
    // backs off a little (20 steps), then pushes the (+x, -z) leg out towards +x and -z (20), and
    // waits (the commands found by a search against the figures of plb_target)
    a.reference = {{20, cmd({-0.047, 0, -0.05})}, {20, cmd({0.1, 0, -0.106})}, {10, cmd({0, 0, 0})}};
    a.plb_target = {{{0.504, 0.114, 0.495}, {0.391, 0.031, 0.359}, {0.656, 0.219, 0.625}}};
    t.push_back(a);
  }
  {  // Torus: press the ring into the dough, off-centre towards -x
    PlbTask a;
    a.name = "torus";
    a.plb_asset = "Torus3D-v1.npy";
    a.floor_friction = 100.0;
    a.shapes = {box({0.5, 0.05, 0.5}, {0.3, 0.1, 0.3}, 10000)};
    Shape ring;
    ring.kind = ShapeKind::torus;
    ring.major_radius = 0.05;
    ring.radius = 0.03;
    auto torus = mover("torus", ring, {0.5, 0.2, 0.5}, Vec3::Constant(0.004));
    torus.rotation = {0.0, 0.0, 0.0, 1.0};
    torus.lower_bound = Vec3(0.0, 0.05, 0.0);
    a.primitives = {torus};
    // PlasticineLab's target spreads 0.05 beyond the dough at -x and 0.03 at +-z and rises to 0.17:
    // the ring moves 0.03 towards -x and 0.01 towards -z (10 steps), then presses down to its
    // lower bound (40) (commands found by a search against the figures of plb_target)
    a.reference = {{10, cmd({-0.74, 0, -0.25})}, {30, cmd({0, -1, 0})}, {10, cmd({0, -0.72, 0})}};
    a.plb_target = {{{0.499, 0.051, 0.499}, {0.297, 0.0, 0.3125}, {0.672, 0.172, 0.6875}}};
    t.push_back(a);
  }
  {  // TripleMove: grab each block between two spheres and carry it to PlasticineLab's place for it
    PlbTask a;
    a.name = "triplemove";
    a.plb_asset = "TripleMove3D-v1.npy";
    a.yield_stress = 200.0;
    for (double x : {0.3, 0.5, 0.7}) a.shapes.push_back(box({x, 0.05, 0.5}, {0.1, 0.1, 0.1}, 3333));
    const char* names[] = {"sphere_1", "sphere_2", "sphere_3", "sphere_4", "sphere_5", "sphere_6"};
    const double xs[] = {0.23, 0.37, 0.43, 0.57, 0.63, 0.77};
    for (int i = 0; i < 6; ++i)
      a.primitives.push_back(mover(names[i], sphere_shape(0.03), {xs[i], 0.05, 0.5}, Vec3::Constant(0.01)));
    // PlasticineLab's target holds the three blocks in the air, undeformed: the left one at
    // (0.2, 0.2, 0.5), the middle one at (0.625, 0.344, 0.2), the right one at (0.8, 0.2, 0.2).
    // Grab (3 steps), carry each block in a straight line (30: the left one by (-0.1, +0.145, 0),
    // the middle one by (+0.125, +0.289, -0.3), the right one by (+0.099, +0.145, -0.3): each lift
    // 0.005 short, as the squeeze raises each block's centre by about that), hold (17)
    const std::vector<double> left = {-0.3333, 0.4837, 0}, middle = {0.4167, 0.9637, -1}, right = {0.33, 0.4833, -1};
    std::vector<double> carry;
    for (const auto* c : {&left, &left, &middle, &middle, &right, &right})
      carry.insert(carry.end(), c->begin(), c->end());
    a.reference = {{3, cmd({1, 0, 0, -1, 0, 0, 1, 0, 0, -1, 0, 0, 1, 0, 0, -1, 0, 0})},
                   {30, carry},
                   {17, std::vector<double>(18, 0.0)}};
    a.plb_target = {{{0.625, 0.344, 0.200}, {0.5625, 0.281, 0.141}, {0.703, 0.422, 0.281}},
                    {{0.200, 0.200, 0.502}, {0.141, 0.141, 0.4375}, {0.281, 0.281, 0.578}},
                    {{0.800, 0.199, 0.200}, {0.734, 0.141, 0.141}, {0.875, 0.281, 0.281}}};
    t.push_back(a);
  }
  {  // Writer: draw strokes into the dough's top with the pen
    PlbTask a;
    a.name = "writer";
    a.plb_asset = "Writer3D-v1.npy";
    a.floor_friction = 100.0;
    a.shapes = {box({0.5, 0.05, 0.5}, {0.3, 0.1, 0.3}, 10000)};
    auto pen = mover("pen", capsule_shape(0.06, 0.03), {0.5, 0.13, 0.5}, Vec3::Constant(0.01));
    pen.rotation = {0.0, 0.0, 0.0, 1.0};
    pen.lower_bound = Vec3(0.0, 0.05, 0.0);
    pen.friction = 0.0;
    a.primitives = {pen};
    // PlasticineLab's target spreads beyond the dough at +x and +z and rises to 0.17 with its centre
    // of mass where it was: the pen goes 0.02 down (5 steps), strokes 0.14 towards +x (14), back
    // diagonally towards -x and +z (14), and along the +z edge towards -x (14), then stops (commands
    // found by a search against the figures of plb_target)
    a.reference = {{5, cmd({0, -0.41, 0})},
                   {14, cmd({1, 0, -0.1})},
                   {14, cmd({-1, 0, 0.97})},
                   {14, cmd({-0.7, 0, 0.21})},
                   {3, cmd({0, 0, 0})}};
    a.plb_target = {{{0.501, 0.051, 0.499}, {0.328, 0.0, 0.344}, {0.6875, 0.172, 0.703}}};
    t.push_back(a);
  }
  return t;
}

}  // namespace

const std::vector<PlbTask>& plb_tasks() {
  static const std::vector<PlbTask> tasks = make_tasks();
  return tasks;
}

const PlbTask* find_plb_task(const std::string& name) {
  for (const auto& t : plb_tasks())
    if (t.name == name) return &t;
  return nullptr;
}

}  // namespace dsb::mpm
