#include "envs/mpm/plb_tasks.hpp"

#include <limits>

namespace dsb::mpm {

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

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
    a.reference = {{3, cmd({-1, 0, 0, 1, 0, 0})},     // squeeze
                   {18, cmd({1, 1, 0, 1, 1, 0})},     // lift towards the box
                   {15, cmd({1, 0, 0, 1, 0, 0})},     // over the box
                   {6, cmd({0, -0.5, 0, 0, -0.5, 0})},  // set it down
                   {4, cmd({1, 0, 0, -1, 0, 0})},     // open
                   {4, cmd({0, 1, 0, 0, 1, 0})}};     // up
    a.plb_bbox = {0.52, 0.69, 0.0, 0.28, 0.42, 0.58};
    a.plb_centre = Vec3(0.6, 0.136, 0.5);
    t.push_back(a);
  }
  {  // Pinch: press the sphere into the block's top
    PlbTask a;
    a.name = "pinch";
    a.plb_asset = "Pinch3D-v1.npy";
    a.floor_friction = 100.0;
    a.shapes = {box({0.5, 0.1, 0.5}, {0.2, 0.2, 0.2}, 6000)};
    auto s = mover("sphere", sphere_shape(0.04), {0.5, 0.35, 0.5}, Vec3::Constant(0.02));
    s.lower_bound = Vec3::Constant(0.1);
    s.upper_bound = Vec3::Constant(0.9);
    a.primitives = {s};
    a.reference = {{13, cmd({0, -1, 0})}, {13, cmd({0, 1, 0})}, {24, cmd({0, 0, 0})}};
    a.plb_bbox = {0.39, 0.61, 0.0, 0.22, 0.39, 0.61};
    a.plb_centre = Vec3::Constant(kNaN);
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
    a.reference = {{5, cmd({1, 0, -1})},  {10, cmd({-1, 0, -1})}, {10, cmd({1, 0, -1})},
                   {10, cmd({-1, 0, -1})}, {10, cmd({1, 0, 0})},   {5, cmd({-1, 0, 0})}};
    a.plb_bbox = {0.27, 0.72, 0.0, 0.11, 0.30, 0.70};
    a.plb_centre = Vec3::Constant(kNaN);
    t.push_back(a);
  }
  {  // Rope: push both ends forward around the pillar
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
    a.reference = {{2, cmd({0, 1, 0, 0, 1, 0})},  // to the rope's mid-height
                   {45, cmd({0.1, 0, -1, -0.6, 0, -1})},
                   {3, cmd({0, 0, 0, 0, 0, 0})}};
    a.plb_bbox = {0.23, 0.56, 0.0, 0.06, 0.33, 0.67};
    a.plb_centre = Vec3::Constant(kNaN);
    t.push_back(a);
  }
  {  // Table: push a leg out from under the table
    PlbTask a;
    a.name = "table";
    a.plb_asset = "Table3D-v1.npy";
    a.poisson_ratio = 0.05;
    a.floor_friction = 0.3;
    for (double dx : {-0.075, 0.075})
      for (double dz : {-0.075, 0.075}) a.shapes.push_back(box({0.5 + dx, 0.1, 0.5 + dz}, {0.04, 0.1, 0.04}, 2000));
    a.shapes.push_back(box({0.5, 0.18, 0.5}, {0.2, 0.05, 0.2}, 2000));
    a.primitives = {mover("sphere", sphere_shape(0.04), {0.5, 0.06, 0.5}, Vec3(0.03, 0.0, 0.03))};
    a.reference = {{40, cmd({0.08, 0, 0.08})}, {10, cmd({0, 0, 0})}};
    a.plb_bbox = {kNaN, kNaN, 0.05, 0.20, kNaN, kNaN};
    a.plb_centre = Vec3::Constant(kNaN);
    t.push_back(a);
  }
  {  // Torus: press the ring into the dough
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
    a.reference = {{32, cmd({0, -1, 0})}, {8, cmd({0, 1, 0})}, {10, cmd({0, 0, 0})}};
    a.plb_bbox = {0.31, 0.66, 0.0, 0.16, kNaN, kNaN};
    a.plb_centre = Vec3::Constant(kNaN);
    t.push_back(a);
  }
  {  // TripleMove: grab each block between two spheres, carry the left and middle ones back, lift, spread
    PlbTask a;
    a.name = "triplemove";
    a.plb_asset = "TripleMove3D-v1.npy";
    a.yield_stress = 200.0;
    for (double x : {0.3, 0.5, 0.7}) a.shapes.push_back(box({x, 0.05, 0.5}, {0.1, 0.1, 0.1}, 3333));
    const char* names[] = {"sphere_1", "sphere_2", "sphere_3", "sphere_4", "sphere_5", "sphere_6"};
    const double xs[] = {0.23, 0.37, 0.43, 0.57, 0.63, 0.77};
    for (int i = 0; i < 6; ++i) a.primitives.push_back(mover(names[i], sphere_shape(0.03), {xs[i], 0.05, 0.5}, Vec3::Constant(0.01)));
    // PlasticineLab's target (v1) holds the left and middle blocks low and far back (z about 0.19)
    // and the right one high at the start's z; its centre of mass (0.54, 0.25, 0.30). Ours: grab
    // (3 steps), lift all and take the left and middle pairs back (14), the middle up a little
    // more (3), the left and middle further back and the right higher (14), spread them in x, the
    // middle to the right (11), hold (5): blocks at about (0.19, 0.19, 0.19), (0.61, 0.22, 0.19),
    // (0.81, 0.33, 0.50) if the spheres carry them without slip.
    a.reference = {{3, cmd({1, 0, 0, -1, 0, 0, 1, 0, 0, -1, 0, 0, 1, 0, 0, -1, 0, 0})},
                   {14, cmd({0, 1, -1, 0, 1, -1, 0, 1, -1, 0, 1, -1, 0, 1, 0, 0, 1, 0})},
                   {3, cmd({0, 0, -1, 0, 0, -1, 0, 1, -1, 0, 1, -1, 0, 0, 0, 0, 0, 0})},
                   {14, cmd({0, 0, -1, 0, 0, -1, 0, 0, -1, 0, 0, -1, 0, 1, 0, 0, 1, 0})},
                   {11, cmd({-1, 0, 0, -1, 0, 0, 1, 0, 0, 1, 0, 0, 1, 0, 0, 1, 0, 0})},
                   {5, cmd({0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0})}};
    a.plb_bbox = {0.14, 0.86, 0.14, 0.39, 0.14, 0.56};
    a.plb_centre = Vec3(0.54, 0.25, 0.30);
    t.push_back(a);
  }
  {  // Writer: draw a stroke pattern into the dough's top with the pen
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
    a.reference = {{2, cmd({0, -0.5, 0})}, {9, cmd({1, 0, 0})}, {8, cmd({0, 0, 1})}, {12, cmd({-1, 0, 0})},
                   {12, cmd({0, 0, -1})}, {7, cmd({1, 0, 0})}};
    a.plb_bbox = {0.34, 0.66, 0.0, 0.13, kNaN, kNaN};
    a.plb_centre = Vec3::Constant(kNaN);
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
