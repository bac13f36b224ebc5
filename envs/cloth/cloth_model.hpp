#pragma once
// The shared mass-spring cloth engine of the swing and flip tasks: the immutable ClothModel
// (vertices, springs, anchors, contact surfaces, constants), the mutable ClothState, the contact
// surfaces (a plug-in interface, the floor plane first) and a builder of rectangular grid meshes
// with structural, shear and bending springs. The step and its reverse: envs/cloth/cloth_dynamics.hpp.
//
// Units: SI (m, kg, s, N). Vertex i of a W x H grid is i = row * W + col.
#include <climits>
#include <memory>
#include <array>
#include <span>
#include <vector>

#include <Eigen/Dense>

namespace dsb::cloth {

using Vec3 = Eigen::Vector3d;
using Mat3 = Eigen::Matrix3d;

enum class SpringKind { structural, shear, bending, other };

struct Spring {
  int i = 0, j = 0;          // vertex indices, i != j
  double rest_length = 0.0;  // m, > 0
  double stiffness = 0.0;    // N/m: the default; an episode may override it (ClothInputs)
  double damping = 0.0;      // N s/m, dashpot along the spring
  SpringKind kind = SpringKind::other;
};

// A vertex held by a scripted motion: during steps t < release_step its position is the anchor
// path's row t at the start of the step and row t + 1 at the end, its velocity at the end is
// (row t+1 - row t) / dt (so a released vertex leaves with the anchor's velocity); from step
// release_step on it is a free vertex. The path itself is an episode input (ClothInputs).
struct Anchor {
  int vertex = 0;
  int release_step = INT_MAX;  // never released by default
  bool held_during(int step) const { return step < release_step; }
};

// What a contact surface reports about one point x at one step: a signed distance (< 0 inside),
// the unit outward normal and its Jacobian, and the surface's own velocity at x (moving surfaces,
// e.g. a pan) and its Jacobian. A rigidly moving surface has dvelocity_dx = [omega]_x.
struct SurfaceSample {
  double distance = 0.0;             // m, signed: <= 0 means at or inside the surface
  Vec3 normal = Vec3::UnitY();       // unit, pointing to the free side (3)
  Mat3 dnormal_dx = Mat3::Zero();    // d normal / d x (3 x 3)
  Vec3 velocity = Vec3::Zero();      // m/s, of the surface point at x (3)
  Mat3 dvelocity_dx = Mat3::Zero();  // d velocity / d x (3 x 3)
};

// A contact surface. Static surfaces implement sample() only. A surface driven by parameters of
// its own (a pan pose per step) reports how many (param_count) and, in the reverse pass, adds
// dLoss/d(its parameters) given dLoss/d(normal) and dLoss/d(velocity) of a sample taken at fixed
// x (the distance only gates the contact and has no derivative). `step` is the step index t: the
// sample is taken at the start of step t, time t dt.
class ContactSurface {
 public:
  virtual ~ContactSurface() = default;
  virtual SurfaceSample sample(int step, const Vec3& x) const = 0;
  virtual int param_count() const { return 0; }
  virtual void sample_adjoint(int step, const Vec3& x, const Vec3& normal_bar, const Vec3& velocity_bar,
                              std::span<double> param_bar) const {
    (void)step, (void)x, (void)normal_bar, (void)velocity_bar, (void)param_bar;
  }
};

// The static half-space {y : normal . (y - point) >= 0}; the floor is point 0, normal +y.
class PlaneSurface final : public ContactSurface {
 public:
  PlaneSurface(const Vec3& point, const Vec3& normal);  // normal is normalized; throws if zero
  static std::shared_ptr<const PlaneSurface> floor(double height = 0.0);
  SurfaceSample sample(int step, const Vec3& x) const override;

 private:
  Vec3 point_, normal_;
};

struct ClothModel {
  std::vector<Vec3> rest_position;                              // m (n): also the default initial positions
  std::vector<double> mass;                                     // kg (n), > 0
  std::vector<Spring> springs;                                  // (n_springs), in a fixed order: the order of every sum
  std::vector<Anchor> anchors;                                  // (n_anchors), distinct vertices
  std::vector<std::shared_ptr<const ContactSurface>> surfaces;  // applied in this order
  Vec3 gravity = Vec3(0.0, -9.81, 0.0);                         // m/s^2
  double dt = 1e-3;                                             // s, symplectic Euler step
  // global velocity damping (1/s): v is multiplied by exp(-damping dt) each step (DiffTaichi)
  double damping = 0.0;
  // contact: the tangential part of the relative velocity of a vertex in contact is multiplied
  // by this (1 = frictionless projection, the seed's "velocity perpendicular to the normal";
  // 0 = sticking, DiffTaichi mass_spring's "v = 0")
  double tangential_keep = 1.0;

  int vertices() const { return static_cast<int>(rest_position.size()); }
  int spring_count() const { return static_cast<int>(springs.size()); }
  int anchor_count() const { return static_cast<int>(anchors.size()); }
  std::vector<double> default_stiffness() const;  // (n_springs) from springs[s].stiffness
  // -1 when vertex v is not an anchor, else its index in `anchors`
  std::vector<int> anchor_of_vertex() const;
  // throws ConfigError naming the field (owner "cloth model")
  void validate() const;
};

struct ClothState {
  std::vector<Vec3> x;  // positions, m (n)
  std::vector<Vec3> v;  // velocities, m/s (n)
};

// at rest in the rest positions
ClothState rest_state(const ClothModel& m);

// mass-weighted mean of the positions x (n), summed in vertex order
Vec3 centre_of_mass(const ClothModel& m, std::span<const Vec3> x);

// A W x H grid in the plane origin + u axis_u + v axis_v, u in [0, width], v in [0, height];
// vertex (col, row) at origin + col du axis_u + row dv axis_v, index row * W + col. Springs, in
// this order: structural (horizontal row by row, then vertical), shear (both diagonals of each
// cell), bending (two apart, horizontal then vertical). Mass total_mass / (W H) per vertex.
struct GridSpec {
  int cols = 5, rows = 5;            // W, H >= 2
  double width = 0.2, height = 0.2;  // m
  Vec3 origin = Vec3::Zero();
  Vec3 axis_u = Vec3::UnitX(), axis_v = Vec3::UnitZ();                                    // unit, orthogonal
  double total_mass = 0.1;                                                                // kg
  double structural_stiffness = 100.0, shear_stiffness = 50.0, bending_stiffness = 20.0;  // N/m
  double structural_damping = 0.0, shear_damping = 0.0, bending_damping = 0.0;            // N s/m
};
// model with no anchors and no surfaces; gravity, dt, damping at their defaults
ClothModel build_grid(const GridSpec& spec);

// Upper bound on the highest angular frequency of the linearized spring network at rest, by
// Gershgorin over K / m: omega_max^2 <= max_i 2 sum_{s at i} k_s / m_i. Symplectic Euler is
// stable for omega dt < 2; tension adds a geometric stiffness k (1 - L0/l) < k per spring, which
// the bound's factor 2 does not cover for springs stretched far beyond rest.
double frequency_bound(const ClothModel& m, std::span<const double> stiffness);

// The RL views' 3 x 3 subsample of a cols x rows grid (build_grid's vertex order): rows and
// columns 0, (n - 1) / 2 and n - 1, row by row.
std::array<int, 9> grid_subsample_3x3(int cols, int rows);
// Appends the positions, then the velocities, of `vertices` to an observation (6 per vertex).
void append_vertex_states(std::vector<double>& observation, const ClothState& s, std::span<const int> vertices);

}  // namespace dsb::cloth
