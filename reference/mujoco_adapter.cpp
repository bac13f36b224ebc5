#include "reference/mujoco_adapter.hpp"

#include <cmath>
#include <cstdio>
#include <cstring>
#include <mutex>
#include <sstream>
#include <stdexcept>
#include <utility>

#include "common/number_text.hpp"

#if DSB_HAVE_MUJOCO
#include <mujoco/mujoco.h>
#endif

namespace dsb::reference {

Eigen::Vector3d to_mujoco(const Eigen::Vector3d& p) { return {p.x(), -p.z(), p.y()}; }
Eigen::Vector3d from_mujoco(const Eigen::Vector3d& q) { return {q.x(), q.z(), -q.y()}; }

MujocoContactParams mujoco_contact_params(const ContactConfig& c, double mass) {
  MujocoContactParams p;
  // constraint space of a point mass: acceleration = force / m along the normal, so our
  // ke (N/m) is a stiffness of ke / m (1/s^2) in MuJoCo's reference acceleration -b v - k r
  p.stiffness = c.ke / mass;
  // MuJoCo damps approach and rebound, ours only the approach: half the damping gives the same
  // restitution to first order in the damping ratio
  p.damping = 0.5 * c.kd / mass;
  // constant impedance close to 1: the constraint follows the reference acceleration
  p.impedance = 0.99;
  // Coulomb coefficient of the elliptic cone; MuJoCo 2.2's <pair> has no solreffriction, so its
  // friction rows relax the slip with the same damping inside the cone (reference/README.md: why its friction
  // is weaker than ours during impacts)
  p.friction = c.mu;
  return p;
}

namespace {

// full-precision number for the MJCF text
std::string num(double v) { return exact_number_text(v); }

std::string vec(const Eigen::Vector3d& v) { return num(v.x()) + " " + num(v.y()) + " " + num(v.z()); }

// a point of the planar setups (our x, y; z = 0) in MuJoCo's frame
Eigen::Vector3d planar(double x, double y) { return to_mujoco(Eigen::Vector3d(x, y, 0.0)); }

// <option> shared by every setup: semi-implicit Euler at the env's dt, gravity along -z
std::string option(double dt, double gravity, bool contacts) {
  std::string s = "  <option timestep=\"" + num(dt) + "\" gravity=\"0 0 " + num(-gravity) +
      "\" integrator=\"Euler\" cone=\"elliptic\">\n";
  s += contacts ? "    <flag contact=\"enable\"/>\n" : "    <flag contact=\"disable\"/>\n";
  return s + "  </option>\n";
}

// <pair> of the ball with one static geom, our contact law mapped to MuJoCo's soft constraint
std::string contact_pair(const std::string& geom, const MujocoContactParams& p) {
  const std::string d = num(p.impedance);
  return "    <pair geom1=\"ball\" geom2=\"" + geom + "\" condim=\"3\" friction=\"" + num(p.friction) + " " +
      num(p.friction) + " 0 0 0\" solref=\"" + num(-p.stiffness) + " " + num(-p.damping) + "\" solimp=\"" + d + " " +
      d + " 0.001 0.5 2\" margin=\"0\" gap=\"0\"/>\n";
}

// slide-only ball body: joints along the given MuJoCo axes, no rotational freedom
std::string ball_body(double mass, double radius, const std::vector<std::string>& axes) {
  // the inertia is irrelevant without rotational joints; a solid sphere's keeps MuJoCo's checks happy
  const double inertia = 0.4 * mass * radius * radius;
  std::string s = "    <body name=\"ball_body\" pos=\"0 0 0\">\n";
  const char* names[] = {"ball_x", "ball_y", "ball_z"};
  for (std::size_t i = 0; i < axes.size(); ++i)
    s += "      <joint name=\"" + std::string(names[i]) + "\" type=\"slide\" axis=\"" + axes[i] +
        "\" limited=\"false\" damping=\"0\" armature=\"0\" frictionloss=\"0\"/>\n";
  s += "      <inertial pos=\"0 0 0\" mass=\"" + num(mass) + "\" diaginertia=\"" + num(inertia) + " " + num(inertia) +
      " " + num(inertia) + "\"/>\n";
  s += "      <geom name=\"ball\" type=\"sphere\" size=\"" + num(radius) + "\" contype=\"0\" conaffinity=\"0\"/>\n";
  return s + "    </body>\n";
}

// static plane through `point` whose free side is along `normal` (both MuJoCo frame)
std::string plane(const std::string& name, const Eigen::Vector3d& point, const Eigen::Vector3d& normal) {
  return "    <geom name=\"" + name + "\" type=\"plane\" pos=\"" + vec(point) + "\" zaxis=\"" + vec(normal) +
      "\" size=\"0 0 1\" contype=\"0\" conaffinity=\"0\"/>\n";
}

}  // namespace

std::string cartpole_mjcf(const CartpoleConfig& cfg) {
  cfg.validate();
  const double L = cfg.link_length;
  const double rod_radius = 0.02 * L;  // visual thickness; sets only the rod's axial inertia
  std::ostringstream s;
  s << "<mujoco model=\"cartpole" << cfg.links << "\">\n"
    << "  <compiler angle=\"radian\" inertiafromgeom=\"false\"/>\n"
    << option(cfg.dt, cfg.gravity, false) << "  <worldbody>\n";
  // cart on a rail along x; the velocity control makes its mass irrelevant to the links
  const double cart_inertia = cfg.cart_mass * 0.1 * 0.1 / 6.0;
  s << "    <body name=\"cart\" pos=\"0 0 0\">\n"
    << "      <joint name=\"rail\" type=\"slide\" axis=\"1 0 0\" limited=\"false\" damping=\"0\""
       " armature=\"0\" frictionloss=\"0\"/>\n"
    << "      <inertial pos=\"0 0 0\" mass=\"" << num(cfg.cart_mass) << "\" diaginertia=\"" << num(cart_inertia) << " "
    << num(cart_inertia) << " " << num(cart_inertia) << "\"/>\n"
    << "      <geom type=\"box\" size=\"0.2 0.1 0.05\" contype=\"0\" conaffinity=\"0\"/>\n";
  // our hanging direction (0, -L) and rotation axis (+z) in MuJoCo's frame
  const Eigen::Vector3d down = to_mujoco(Eigen::Vector3d(0.0, -L, 0.0));
  const Eigen::Vector3d axis = to_mujoco(Eigen::Vector3d(0.0, 0.0, 1.0));
  std::string indent = "      ";
  for (int i = 0; i < cfg.links; ++i) {
    const double m = cfg.link_masses[i];
    // uniform rod: m L^2 / 12 about the centre across the rod, m r^2 / 2 along it
    const double across = m * L * L / 12.0, along = 0.5 * m * rod_radius * rod_radius;
    const Eigen::Vector3d pivot = i == 0 ? Eigen::Vector3d::Zero() : down;
    s << indent << "<body name=\"link" << i + 1 << "\" pos=\"" << vec(pivot) << "\">\n"
      << indent << "  <joint name=\"hinge" << i + 1 << "\" type=\"hinge\" pos=\"0 0 0\" axis=\"" << vec(axis)
      << "\" limited=\"false\" damping=\"0\" armature=\"0\" frictionloss=\"0\"/>\n"
      << indent << "  <inertial pos=\"" << vec(0.5 * down) << "\" mass=\"" << num(m) << "\" diaginertia=\""
      << num(across) << " " << num(across) << " " << num(along) << "\"/>\n"
      << indent << "  <geom type=\"capsule\" fromto=\"0 0 0 " << vec(down) << "\" size=\"" << num(rod_radius)
      << "\" contype=\"0\" conaffinity=\"0\"/>\n";
    if (i + 1 == cfg.links) s << indent << "  <site name=\"tip\" pos=\"" << vec(down) << "\"/>\n";
    indent += "  ";
  }
  for (int i = cfg.links; i >= 1; --i) {
    indent.resize(indent.size() - 2);
    s << indent << "</body>\n";
  }
  s << "    </body>\n  </worldbody>\n</mujoco>\n";
  return s.str();
}

std::string bounce_mjcf(const BounceConfig& cfg) {
  cfg.validate();
  const MujocoContactParams p = mujoco_contact_params(cfg.contact, cfg.mass);
  std::ostringstream s;
  s << "<mujoco model=\"bounce\">\n"
    << "  <compiler angle=\"radian\" inertiafromgeom=\"false\"/>\n"
    << option(cfg.dt, cfg.gravity, true)
    << "  <worldbody>\n"
    // ground y = 0 (normal +y) and wall x = wall_x (normal -x), ours
    << plane("ground", to_mujoco({0.0, 0.0, 0.0}), to_mujoco({0.0, 1.0, 0.0}))
    << plane("wall", to_mujoco({cfg.wall_x, 0.0, 0.0}), to_mujoco({-1.0, 0.0, 0.0}))
    << ball_body(cfg.mass, cfg.radius, {"1 0 0", "0 1 0", "0 0 1"}) << "  </worldbody>\n"
    << "  <contact>\n"
    << contact_pair("ground", p) << contact_pair("wall", p) << "  </contact>\n</mujoco>\n";
  return s.str();
}

std::string pinball_mjcf(const PinballConfig& cfg, std::span<const double> angles) {
  cfg.validate();
  if (static_cast<int>(angles.size()) != cfg.rows * cfg.cols)
    throw std::invalid_argument("pinball_mjcf: expected " + std::to_string(cfg.rows * cfg.cols) +
                                " paddle angles, got " + std::to_string(angles.size()));
  const MujocoContactParams p = mujoco_contact_params(cfg.contact, cfg.ball_mass);
  const double half = 0.5 * (cfg.paddle_length - cfg.paddle_thickness);
  const double radius = 0.5 * cfg.paddle_thickness;
  std::ostringstream s, pairs;
  s << "<mujoco model=\"pinball-" << cfg.rows << "x" << cfg.cols << "\">\n"
    << "  <compiler angle=\"radian\" inertiafromgeom=\"false\"/>\n"
    << option(cfg.dt, cfg.gravity, true) << "  <worldbody>\n"
    << plane("floor", planar(0.0, 0.0), to_mujoco({0.0, 1.0, 0.0}))
    << plane("left_wall", planar(0.0, 0.0), to_mujoco({1.0, 0.0, 0.0}))
    << plane("right_wall", planar(cfg.width, 0.0), to_mujoco({-1.0, 0.0, 0.0}));
  pairs << contact_pair("floor", p) << contact_pair("left_wall", p) << contact_pair("right_wall", p);
  // paddles: capsules (a segment of paddle_length - thickness, radius thickness / 2) through
  // their centres at their locked angles (0 = horizontal, counter-clockwise positive)
  for (int r = 0; r < cfg.rows; ++r)
    for (int c = 0; c < cfg.cols; ++c) {
      const double a = angles[r * cfg.cols + c];
      const auto centre = cfg.paddle_centre(r, c);
      const double dx = half * std::cos(a), dy = half * std::sin(a);
      const std::string name = "paddle_" + std::to_string(r) + "_" + std::to_string(c);
      s << "    <geom name=\"" << name << "\" type=\"capsule\" fromto=\"" << vec(planar(centre[0] - dx, centre[1] - dy))
        << " " << vec(planar(centre[0] + dx, centre[1] + dy)) << "\" size=\"" << num(radius)
        << "\" contype=\"0\" conaffinity=\"0\"/>\n";
      pairs << contact_pair(name, p);
    }
  // the ball moves in the board's plane: MuJoCo x (ours x) and z (ours y)
  s << ball_body(cfg.ball_mass, cfg.ball_radius, {"1 0 0", "0 0 1"}) << "  </worldbody>\n"
    << "  <contact>\n"
    << pairs.str() << "  </contact>\n</mujoco>\n";
  return s.str();
}

#if DSB_HAVE_MUJOCO

bool mujoco_available() { return true; }
std::string mujoco_version() { return mj_versionString(); }

struct MujocoSim::Impl {
  mjModel* m = nullptr;
  mjData* d = nullptr;
  ~Impl() {
    if (d) mj_deleteData(d);
    if (m) mj_deleteModel(m);
  }
};

MujocoSim::MujocoSim(const std::string& mjcf) : impl_(std::make_unique<Impl>()) {
  // MuJoCo 2.2's XML loader keeps global state (the last parsed model): one load at a time
  static std::mutex loading;
  const std::lock_guard<std::mutex> lock(loading);
  // compile from memory: one file in a virtual file system (about 2 MB, so on the heap)
  auto vfs = std::make_unique<mjVFS>();
  mj_defaultVFS(vfs.get());
  const char* name = "model.xml";
  if (mj_makeEmptyFileVFS(vfs.get(), name, static_cast<int>(mjcf.size())) != 0)
    throw std::runtime_error("MuJoCo: cannot create the in-memory model file");
  const int slot = mj_findFileVFS(vfs.get(), name);
  std::memcpy(vfs->filedata[slot], mjcf.data(), mjcf.size());
  char error[1000] = "";
  impl_->m = mj_loadXML(name, vfs.get(), error, sizeof error);
  mj_deleteVFS(vfs.get());
  if (!impl_->m) throw std::runtime_error(std::string("MuJoCo: model does not compile: ") + error);
  impl_->d = mj_makeData(impl_->m);
}

MujocoSim::~MujocoSim() = default;
MujocoSim::MujocoSim(MujocoSim&&) noexcept = default;
MujocoSim& MujocoSim::operator=(MujocoSim&&) noexcept = default;
const mjModel_* MujocoSim::model() const { return impl_->m; }
mjData_* MujocoSim::data() const { return impl_->d; }
void MujocoSim::reset() { mj_resetData(impl_->m, impl_->d); }

bool MujocoSim::healthy() const {
  const mjData* d = impl_->d;
  return d->warning[mjWARN_BADQPOS].number == 0 && d->warning[mjWARN_BADQVEL].number == 0 &&
      d->warning[mjWARN_BADQACC].number == 0;
}

// ---------------------------------- cartpole ------------------------------------------------

MujocoCartpole::MujocoCartpole(const CartpoleConfig& cfg)
    : EngineCartpole("MujocoCartpole", cfg), sim_(cartpole_mjcf(cfg)) {
  const int nv = sim_.model()->nv;
  mass_matrix_.assign(static_cast<std::size_t>(nv) * nv, 0.0);
  tip_site_ = mj_name2id(sim_.model(), mjOBJ_SITE, "tip");
  reset();
}

void MujocoCartpole::reset() {
  sim_.reset();
  mjData* d = sim_.data();
  // qpos = (cart x, theta_1..n) with relative joint angles, as in our config
  for (int i = 0; i < cfg_.links; ++i) {
    d->qpos[1 + i] = cfg_.start_joint_angles.empty() ? 0.0 : cfg_.start_joint_angles[i];
    d->qvel[1 + i] = cfg_.start_joint_velocities.empty() ? 0.0 : cfg_.start_joint_velocities[i];
  }
  mj_kinematics(sim_.model(), d);
}

void MujocoCartpole::step(double u, const double* tau) {
  const mjModel* m = sim_.model();
  mjData* d = sim_.data();
  const int nv = m->nv, n = nv - 1;
  // position- and velocity-dependent quantities: mass matrix qM and bias forces qfrc_bias
  mj_step1(m, d);
  mj_fullM(m, mass_matrix_.data(), d->qM);
  using RowMat = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;
  const Eigen::Map<const RowMat> M(mass_matrix_.data(), nv, nv);   // (nv x nv)
  const Eigen::Map<const Eigen::VectorXd> bias(d->qfrc_bias, nv);  // (nv)
  // velocity control: the cart's acceleration is fixed, a = (u - v) / dt; the links then obey
  // M_ll qacc_l = tau - bias_l - M_l0 a, and the cart force is the first row of M qacc + bias
  const double a = (u - d->qvel[0]) / m->opt.timestep;
  const Eigen::Map<const Eigen::VectorXd> torque(tau, n);
  const LinkVec M_l0 = M.block(1, 0, n, 1);              // (n), = M_0l by symmetry
  const LinkMat M_ll = M.block(1, 1, n, n);              // (n x n)
  const LinkVec rhs = torque - bias.tail(n) - M_l0 * a;  // (n)
  const LinkVec qacc_links = M_ll.llt().solve(rhs);      // (n)
  const double cart_force = M(0, 0) * a + M_l0.dot(qacc_links) + bias(0);
  d->qfrc_applied[0] = cart_force;
  for (int j = 0; j < n; ++j) d->qfrc_applied[1 + j] = tau[j];
  // forces -> qacc (MuJoCo's own factorization) -> semi-implicit Euler
  mj_step2(m, d);
  mj_kinematics(m, d);
}

CartpoleState MujocoCartpole::state() const {
  const mjData* d = sim_.data();
  // qpos, qvel: the cart's slide, then the relative hinges
  const std::size_t joints = static_cast<std::size_t>(cfg_.links) + 1;
  return state_from_joints({d->qpos, joints}, {d->qvel, joints});
}

Eigen::Vector2d MujocoCartpole::tip() const {
  const mjtNum* p = sim_.data()->site_xpos + 3 * tip_site_;
  const Eigen::Vector3d ours = from_mujoco(Eigen::Vector3d(p[0], p[1], p[2]));
  return ours.head<2>();
}

// ---------------------------------- bounce --------------------------------------------------

MujocoBounce::MujocoBounce(const BounceConfig& cfg)
    : cfg_(cfg), sim_(bounce_mjcf(cfg)), steps_(BounceModel::build(cfg).steps) {}

void MujocoBounce::start(const Eigen::Vector3d& v0) {
  sim_.reset();
  mjData* d = sim_.data();
  // the slide joints are MuJoCo's x, y, z: qpos is the ball centre in MuJoCo's frame
  const Eigen::Vector3d p = to_mujoco({cfg_.start[0], cfg_.start[1], cfg_.start[2]});
  const Eigen::Vector3d v = to_mujoco(v0);
  for (int i = 0; i < 3; ++i) {
    d->qpos[i] = p(i);
    d->qvel[i] = v(i);
  }
}

BallState MujocoBounce::read() const {
  const mjData* d = sim_.data();
  BallState s;
  s.position = from_mujoco({d->qpos[0], d->qpos[1], d->qpos[2]});
  s.velocity = from_mujoco({d->qvel[0], d->qvel[1], d->qvel[2]});
  return s;
}

std::vector<BallState> MujocoBounce::trajectory(const Eigen::Vector3d& v0) {
  start(v0);
  std::vector<BallState> states;
  states.reserve(steps_ + 1);
  states.push_back(read());
  for (int t = 0; t < steps_; ++t) {
    mj_step(sim_.model(), sim_.data());
    states.push_back(read());
  }
  return states;
}

BallState MujocoBounce::final_state(const Eigen::Vector3d& v0) {
  start(v0);
  for (int t = 0; t < steps_; ++t) mj_step(sim_.model(), sim_.data());
  return read();
}

// ---------------------------------- pinball -------------------------------------------------

MujocoPinball::MujocoPinball(const PinballConfig& cfg, std::span<const double> angles)
    : cfg_(cfg), sim_(pinball_mjcf(cfg, angles)), steps_(PinballModel::build(cfg).steps) {}

std::vector<Ball2State> MujocoPinball::trajectory() {
  sim_.reset();
  mjData* d = sim_.data();
  // slide joints along MuJoCo x and z carry our x and y; the ball starts at rest
  const Eigen::Vector3d p = planar(cfg_.start[0], cfg_.start[1]);
  d->qpos[0] = p.x();
  d->qpos[1] = p.z();
  auto read = [&] {
    Ball2State s;
    s.position = from_mujoco({d->qpos[0], 0.0, d->qpos[1]}).head<2>();
    s.velocity = from_mujoco({d->qvel[0], 0.0, d->qvel[1]}).head<2>();
    return s;
  };
  std::vector<Ball2State> states;
  states.reserve(steps_ + 1);
  states.push_back(read());
  for (int t = 0; t < steps_; ++t) {
    mj_step(sim_.model(), d);
    states.push_back(read());
  }
  return states;
}

#else  // no MuJoCo in this build: every entry point says so

namespace {
[[noreturn]] void missing() { throw std::runtime_error("this build has no MuJoCo (DSB_WITH_MUJOCO)"); }
}  // namespace

bool mujoco_available() { return false; }
std::string mujoco_version() { return "none"; }
struct MujocoSim::Impl {};
MujocoSim::MujocoSim(const std::string&) { missing(); }
MujocoSim::~MujocoSim() = default;
MujocoSim::MujocoSim(MujocoSim&&) noexcept = default;
MujocoSim& MujocoSim::operator=(MujocoSim&&) noexcept = default;
const mjModel_* MujocoSim::model() const { missing(); }
mjData_* MujocoSim::data() const { missing(); }
void MujocoSim::reset() { missing(); }
bool MujocoSim::healthy() const { missing(); }
MujocoCartpole::MujocoCartpole(const CartpoleConfig& cfg)
    : EngineCartpole("MujocoCartpole", cfg), sim_(std::string()) {}
void MujocoCartpole::reset() { missing(); }
void MujocoCartpole::step(double, const double*) { missing(); }
CartpoleState MujocoCartpole::state() const { missing(); }
Eigen::Vector2d MujocoCartpole::tip() const { missing(); }
MujocoBounce::MujocoBounce(const BounceConfig& cfg) : cfg_(cfg), sim_(std::string()) {}
std::vector<BallState> MujocoBounce::trajectory(const Eigen::Vector3d&) { missing(); }
BallState MujocoBounce::final_state(const Eigen::Vector3d&) { missing(); }
MujocoPinball::MujocoPinball(const PinballConfig& cfg, std::span<const double>) : cfg_(cfg), sim_(std::string()) {}
std::vector<Ball2State> MujocoPinball::trajectory() { missing(); }

#endif

}  // namespace dsb::reference
