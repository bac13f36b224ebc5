#include "reference/bullet_adapter.hpp"

#include <array>
#include <cmath>
#include <stdexcept>
#include <string>

#include "envs/rigid/contact.hpp"

#if DSB_HAVE_BULLET
#include <btBulletDynamicsCommon.h>
#include <BulletDynamics/Featherstone/btMultiBody.h>
#include <BulletDynamics/Featherstone/btMultiBodyConstraintSolver.h>
#include <BulletDynamics/Featherstone/btMultiBodyDynamicsWorld.h>
#include <BulletDynamics/Featherstone/btMultiBodyJointMotor.h>
#include <BulletDynamics/Featherstone/btMultiBodyLinkCollider.h>
#endif

namespace dsb::reference {

double equivalent_restitution(const ContactConfig& contact, double mass, double dt) {
  // a ball of radius 1 touching the plane y = 0 with unit approach speed, integrated with our
  // own law (contact_force) and step (v += dt f / m; y += dt v) until it leaves the plane
  const double radius = 1.0;
  Eigen::Vector3d p(0.0, radius, 0.0), v(0.0, -1.0, 0.0);
  for (int t = 0; t < 1000000; ++t) {
    const auto g = plane_geometry<3>(p, Eigen::Vector3d::UnitY(), 0.0);
    const auto f = contact_force<3>(contact, radius, g, v);
    v += (dt / mass) * f.f;
    p += dt * v;
    if (p.y() >= radius && v.y() > 0.0) return v.y();
  }
  return 0.0;  // never left the plane: fully inelastic
}

#if DSB_HAVE_BULLET

bool bullet_available() { return true; }
std::string bullet_version() {
  const int v = btGetVersion();
  return std::to_string(v / 100) + "." + std::to_string(v % 100) + (sizeof(btScalar) == 8 ? " (double)" : " (single)");
}

namespace {

btVector3 bt(const Eigen::Vector3d& v) { return {v.x(), v.y(), v.z()}; }
Eigen::Vector3d eig(const btVector3& v) { return {v.x(), v.y(), v.z()}; }

// the collision and solver objects every Bullet world needs, owned together
template <class World, class Solver>
struct WorldParts {
  btDefaultCollisionConfiguration config;
  btCollisionDispatcher dispatcher{&config};
  btDbvtBroadphase broadphase;
  Solver solver;
  World world{&dispatcher, &broadphase, &solver, &config};
};

// contact solving for the ball setups: the impact is the restitution impulse alone; Bullet's
// default Baumgarte push-out (erp 0.2 of the penetration per step, baked into the velocity for
// shallow penetrations) would add up to a metre per second to every rebound
void impulse_only_contacts(btDiscreteDynamicsWorld& world) {
  btContactSolverInfo& info = world.getSolverInfo();
  info.m_erp = 0.0;
  info.m_erp2 = 0.0;
}

// a static (mass 0) rigid body with its shape, owned together
struct StaticBody {
  std::unique_ptr<btCollisionShape> shape;
  std::unique_ptr<btRigidBody> body;
  StaticBody(btCollisionShape* s, const btTransform& where, double friction, double restitution) : shape(s) {
    btRigidBody::btRigidBodyConstructionInfo info(0.0, nullptr, s, btVector3(0, 0, 0));
    info.m_startWorldTransform = where;
    body = std::make_unique<btRigidBody>(info);
    // Bullet combines friction and restitution as products: the statics carry 1, the ball the value
    body->setFriction(friction);
    body->setRestitution(restitution);
    body->setRollingFriction(0.0);
    body->setSpinningFriction(0.0);
  }
};

// the ball: a sphere that translates only (our ball is a point mass without spin)
std::unique_ptr<btRigidBody> make_ball(btCollisionShape* shape, double mass, double mu, double restitution,
                                       const btVector3& linear_factor) {
  btVector3 inertia(0, 0, 0);
  shape->calculateLocalInertia(mass, inertia);
  btRigidBody::btRigidBodyConstructionInfo info(mass, nullptr, shape, inertia);
  auto ball = std::make_unique<btRigidBody>(info);
  ball->setAngularFactor(btVector3(0, 0, 0));
  ball->setLinearFactor(linear_factor);
  ball->setDamping(0.0, 0.0);
  ball->setFriction(mu);
  ball->setRollingFriction(0.0);
  ball->setSpinningFriction(0.0);
  ball->setRestitution(restitution);
  ball->setActivationState(DISABLE_DEACTIVATION);
  // solve only touching contacts (distance <= 0), as our law acts only under penetration:
  // Bullet's speculative contacts (up to 2 % of the radius apart) would bounce a step early and
  // lower the rebound by gap / dt
  ball->setContactProcessingThreshold(0.0);
  return ball;
}

}  // namespace

// ---------------------------------- cartpole ------------------------------------------------

struct BulletCartpole::Impl {
  WorldParts<btMultiBodyDynamicsWorld, btMultiBodyConstraintSolver> parts;
  std::unique_ptr<btMultiBody> body;
  std::unique_ptr<btMultiBodyJointMotor> motor;
  std::unique_ptr<btBoxShape> cart_shape;
  std::unique_ptr<btMultiBodyLinkCollider> cart_collider;
  ~Impl() {
    if (motor) parts.world.removeMultiBodyConstraint(motor.get());
    if (cart_collider) parts.world.removeCollisionObject(cart_collider.get());
    if (body) parts.world.removeMultiBody(body.get());
  }
};

BulletCartpole::BulletCartpole(const CartpoleConfig& cfg)
    : EngineCartpole("BulletCartpole", cfg), impl_(std::make_unique<Impl>()) {
  cfg.validate();
  const int n = cfg.links;
  const double L = cfg.link_length;
  const double rod_radius = 0.02 * L;  // as the MuJoCo model: only the axial inertia uses it
  auto& world = impl_->parts.world;
  world.setGravity(btVector3(0, -cfg.gravity, 0));
  // fixed base (the rail), link 0 the cart (prismatic along x), links 1..n the rods (revolute
  // about z); a link's frame sits at its centre of mass
  auto mb = std::make_unique<btMultiBody>(n + 1, 1.0, btVector3(1, 1, 1), true, false);
  const double cart_inertia = cfg.cart_mass * 0.1 * 0.1 / 6.0;
  const btQuaternion identity(0, 0, 0, 1);
  const btVector3 zero(0, 0, 0), half_down(0, -0.5 * L, 0);
  mb->setupPrismatic(0, cfg.cart_mass, btVector3(cart_inertia, cart_inertia, cart_inertia), -1, identity,
                     btVector3(1, 0, 0), zero, zero, true);
  for (int i = 0; i < n; ++i) {
    const double m = cfg.link_masses[i];
    // uniform rod along the link's y axis: m L^2 / 12 across, m r^2 / 2 along
    const double across = m * L * L / 12.0, along = 0.5 * m * rod_radius * rod_radius;
    // the pivot is the cart's centre for the first rod, the previous rod's end otherwise
    mb->setupRevolute(1 + i, m, btVector3(across, along, across), i, identity, btVector3(0, 0, 1),
                      i == 0 ? zero : half_down, half_down, true);
  }
  mb->finalizeMultiDof();
  // no damping (Bullet's default is 0.04), no velocity clamp, no sleeping
  mb->setLinearDamping(0.0);
  mb->setAngularDamping(0.0);
  mb->setMaxCoordinateVelocity(1e30);
  mb->setMaxAppliedImpulse(1e30);
  mb->setCanSleep(false);
  world.addMultiBody(mb.get());
  // Bullet solves multibody constraints per simulation island, and a multibody's island comes
  // from its link colliders: the cart gets one that collides with nothing (group and mask 0)
  impl_->cart_shape = std::make_unique<btBoxShape>(btVector3(0.2, 0.1, 0.05));
  impl_->cart_collider = std::make_unique<btMultiBodyLinkCollider>(mb.get(), 0);
  impl_->cart_collider->setCollisionShape(impl_->cart_shape.get());
  world.addCollisionObject(impl_->cart_collider.get(), 0, 0);
  mb->getLink(0).m_collider = impl_->cart_collider.get();
  // velocity control of the cart: a motor row with unbounded impulse, kd = 1 (the full error in
  // one step), no position term
  impl_->motor = std::make_unique<btMultiBodyJointMotor>(mb.get(), 0, 0.0, 1e30);
  impl_->motor->setPositionTarget(0.0, 0.0);
  world.addMultiBodyConstraint(impl_->motor.get());
  impl_->body = std::move(mb);
  reset();
}

BulletCartpole::~BulletCartpole() = default;

void BulletCartpole::reset() {
  const auto& cfg = cfg_;
  btMultiBody& mb = *impl_->body;
  mb.setJointPos(0, 0.0);
  mb.setJointVel(0, 0.0);
  for (int i = 0; i < cfg.links; ++i) {
    mb.setJointPos(1 + i, cfg.start_joint_angles.empty() ? 0.0 : cfg.start_joint_angles[i]);
    mb.setJointVel(1 + i, cfg.start_joint_velocities.empty() ? 0.0 : cfg.start_joint_velocities[i]);
  }
  mb.clearForcesAndTorques();
}

void BulletCartpole::step(double u, const double* tau) {
  impl_->motor->setVelocityTarget(u, 1.0);
  for (int j = 0; j < cfg_.links; ++j) impl_->body->addJointTorque(1 + j, tau[j]);
  // exactly one internal step of dt (maxSubSteps = 0: the step is the given time)
  impl_->parts.world.stepSimulation(cfg_.dt, 0);
}

CartpoleState BulletCartpole::state() const {
  const btMultiBody& mb = *impl_->body;
  // link 0 the cart's prismatic joint, links 1..n the relative revolute joints
  std::array<double, kMaxLinks + 1> q{}, dq{};
  const std::size_t joints = static_cast<std::size_t>(cfg_.links) + 1;
  for (std::size_t i = 0; i < joints; ++i) {
    q[i] = mb.getJointPos(static_cast<int>(i));
    dq[i] = mb.getJointVel(static_cast<int>(i));
  }
  return state_from_joints({q.data(), joints}, {dq.data(), joints});
}

Eigen::Vector2d BulletCartpole::tip() const {
  // the far end of the last rod: half a length below its centre of mass, in its own frame
  const int last = cfg_.links;
  const btVector3 p = impl_->body->localPosToWorld(last, btVector3(0, -0.5 * cfg_.link_length, 0));
  return {p.x(), p.y()};
}

// ------------------------------ ball setups (bounce, pinball) ------------------------------

namespace {

// A ball (btRigidBody sphere, no spin) among static bodies, with Bullet's impulse contacts; what
// bounce and the pinballs share. The ball is added last, after every static body.
struct BallWorld {
  WorldParts<btDiscreteDynamicsWorld, btSequentialImpulseConstraintSolver> parts;
  std::vector<std::unique_ptr<StaticBody>> statics;
  std::unique_ptr<btSphereShape> ball_shape;
  std::unique_ptr<btRigidBody> ball;

  explicit BallWorld(double gravity) {
    parts.world.setGravity(btVector3(0, -gravity, 0));
    impulse_only_contacts(parts.world);
  }
  ~BallWorld() {
    if (ball) parts.world.removeRigidBody(ball.get());
    for (auto& s : statics) parts.world.removeRigidBody(s->body.get());
  }
  // static plane n . p = c
  void add_plane(const btVector3& normal, double c) {
    btTransform identity;
    identity.setIdentity();
    add_static(new btStaticPlaneShape(normal, c), identity);
  }
  void add_static(btCollisionShape* shape, const btTransform& where) {
    statics.push_back(std::make_unique<StaticBody>(shape, where, 1.0, 1.0));
    parts.world.addRigidBody(statics.back()->body.get());
  }
  void add_ball(double radius, double mass, const ContactConfig& contact, double dt, const btVector3& linear_factor) {
    ball_shape = std::make_unique<btSphereShape>(radius);
    ball = make_ball(ball_shape.get(), mass, contact.mu, equivalent_restitution(contact, mass, dt), linear_factor);
    parts.world.addRigidBody(ball.get());
  }
  // restart from (start, v0), forgetting old contacts; steps + 1 (position, velocity) pairs
  std::vector<std::pair<Eigen::Vector3d, Eigen::Vector3d>> roll(const btVector3& start, const btVector3& v0, int steps,
                                                                double dt) {
    btTransform where;
    where.setIdentity();
    where.setOrigin(start);
    ball->setWorldTransform(where);
    ball->setInterpolationWorldTransform(where);
    ball->setLinearVelocity(v0);
    ball->setAngularVelocity(btVector3(0, 0, 0));
    ball->setInterpolationLinearVelocity(v0);
    ball->clearForces();
    parts.world.getBroadphase()->getOverlappingPairCache()->cleanProxyFromPairs(ball->getBroadphaseHandle(),
                                                                                parts.world.getDispatcher());
    std::vector<std::pair<Eigen::Vector3d, Eigen::Vector3d>> states;
    states.reserve(steps + 1);
    auto read = [&] {
      states.emplace_back(eig(ball->getWorldTransform().getOrigin()), eig(ball->getLinearVelocity()));
    };
    read();
    for (int t = 0; t < steps; ++t) {
      parts.world.stepSimulation(dt, 0);
      read();
    }
    return states;
  }
};

}  // namespace

// ---------------------------------- bounce --------------------------------------------------

struct BulletBounce::Impl {
  BounceConfig cfg;
  int steps = 0;
  BallWorld world;
  explicit Impl(const BounceConfig& c) : cfg(c), steps(BounceModel::build(c).steps), world(c.gravity) {}
};

BulletBounce::BulletBounce(const BounceConfig& cfg) : impl_(std::make_unique<Impl>(cfg)) {
  auto& w = impl_->world;
  // ground y = 0 (normal +y) and wall x = wall_x (normal -x): planes n . p = c
  w.add_plane(btVector3(0, 1, 0), 0.0);
  w.add_plane(btVector3(-1, 0, 0), -cfg.wall_x);
  w.add_ball(cfg.radius, cfg.mass, cfg.contact, cfg.dt, btVector3(1, 1, 1));
}

BulletBounce::~BulletBounce() = default;

std::vector<BallState> BulletBounce::trajectory(const Eigen::Vector3d& v0) {
  const auto& cfg = impl_->cfg;
  std::vector<BallState> states;
  for (const auto& [p, v] :
       impl_->world.roll(btVector3(cfg.start[0], cfg.start[1], cfg.start[2]), bt(v0), impl_->steps, cfg.dt))
    states.push_back({p, v});
  return states;
}

// ---------------------------------- pinball -------------------------------------------------

struct BulletPinball::Impl {
  PinballConfig cfg;
  int steps = 0;
  BallWorld world;
  explicit Impl(const PinballConfig& c) : cfg(c), steps(PinballModel::build(c).steps), world(c.gravity) {}
};

BulletPinball::BulletPinball(const PinballConfig& cfg, std::span<const double> angles) {
  cfg.validate();
  if (static_cast<int>(angles.size()) != cfg.rows * cfg.cols)
    throw std::invalid_argument("BulletPinball: expected " + std::to_string(cfg.rows * cfg.cols) +
                                " paddle angles, got " + std::to_string(angles.size()));
  impl_ = std::make_unique<Impl>(cfg);
  auto& w = impl_->world;
  // floor y = 0, walls x = 0 and x = width
  w.add_plane(btVector3(0, 1, 0), 0.0);
  w.add_plane(btVector3(1, 0, 0), 0.0);
  w.add_plane(btVector3(-1, 0, 0), -cfg.width);
  // paddles: capsules along their local x (segment paddle_length - thickness, radius
  // thickness / 2), turned about z by their angle around their centre
  const double segment = cfg.paddle_length - cfg.paddle_thickness;
  for (int r = 0; r < cfg.rows; ++r)
    for (int c = 0; c < cfg.cols; ++c) {
      const auto centre = cfg.paddle_centre(r, c);
      btTransform where;
      where.setIdentity();
      where.setOrigin(btVector3(centre[0], centre[1], 0.0));
      where.setRotation(btQuaternion(btVector3(0, 0, 1), angles[r * cfg.cols + c]));
      w.add_static(new btCapsuleShapeX(0.5 * cfg.paddle_thickness, segment), where);
    }
  // the board's plane: no motion along z
  w.add_ball(cfg.ball_radius, cfg.ball_mass, cfg.contact, cfg.dt, btVector3(1, 1, 0));
}

BulletPinball::~BulletPinball() = default;

std::vector<Ball2State> BulletPinball::trajectory() {
  const auto& cfg = impl_->cfg;
  std::vector<Ball2State> states;
  for (const auto& [p, v] :
       impl_->world.roll(btVector3(cfg.start[0], cfg.start[1], 0.0), btVector3(0, 0, 0), impl_->steps, cfg.dt))
    states.push_back({p.head<2>(), v.head<2>()});
  return states;
}

#else  // no Bullet in this build: every entry point says so

namespace {
[[noreturn]] void missing() { throw std::runtime_error("this build has no Bullet (DSB_WITH_BULLET)"); }
}  // namespace

bool bullet_available() { return false; }
std::string bullet_version() { return "none"; }
struct BulletCartpole::Impl {};
BulletCartpole::BulletCartpole(const CartpoleConfig& cfg) : EngineCartpole("BulletCartpole", cfg) { missing(); }
BulletCartpole::~BulletCartpole() = default;
void BulletCartpole::reset() { missing(); }
void BulletCartpole::step(double, const double*) { missing(); }
CartpoleState BulletCartpole::state() const { missing(); }
Eigen::Vector2d BulletCartpole::tip() const { missing(); }
struct BulletBounce::Impl {};
BulletBounce::BulletBounce(const BounceConfig&) { missing(); }
BulletBounce::~BulletBounce() = default;
std::vector<BallState> BulletBounce::trajectory(const Eigen::Vector3d&) { missing(); }
struct BulletPinball::Impl {};
BulletPinball::BulletPinball(const PinballConfig&, std::span<const double>) { missing(); }
BulletPinball::~BulletPinball() = default;
std::vector<Ball2State> BulletPinball::trajectory() { missing(); }

#endif

}  // namespace dsb::reference
