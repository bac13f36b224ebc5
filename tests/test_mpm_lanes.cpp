// The MPM engine's lanes paths (envs/mpm/lane_path.hpp) give the scalar path's bits: a forward and
// a gradient episode on a small model with every material and every primitive, through each path
// the CPU has, on one and two threads, compared byte for byte (particles, loss, gradient with
// respect to the actions, the initial state and the poses); and the scalar path still gives the
// bits recorded before the lanes existed.
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <string>
#include <string_view>
#include <vector>

#include <Eigen/Geometry>
#include <gtest/gtest.h>

#include "common/parallel.hpp"
#include "common/rng.hpp"
#include "envs/mpm/episode.hpp"
#include "envs/mpm/lane_path.hpp"
#include "support/mpm_models.hpp"

namespace dsb {
namespace {

using mpm::Mat3;
using mpm::Vec3;

// What an episode leaves: the final particles and loss of a forward episode, and the loss and
// every gradient of a gradient episode.
struct EpisodeBits {
  std::vector<mpm::Particle> particles;
  double loss = 0.0, grad_loss = 0.0;
  std::vector<double> action_grad;
  std::vector<mpm::ParticleAdjoint> state_grad;
  std::vector<mpm::PoseAdjoint> pose_grad;
};

constexpr int kEnvSteps = 3;

const mpm::MpmModel& every_primitive() {
  static const mpm::MpmModel m = testing::every_primitive_model(4);
  return m;
}

// F of a random state: near the identity, stretched and rotated (plastic flow), a singular
// value below the return mapping's floor of 0.05, inverted (det < 0), or zero
Mat3 random_deformation(Rng& rng) {
  Mat3 n;
  for (int i = 0; i < 9; ++i) n(i) = rng.normal();
  const Eigen::Quaterniond q(rng.normal(), rng.normal(), rng.normal(), rng.normal());
  const Mat3 R = q.normalized().toRotationMatrix();
  switch (rng.below(5)) {
    case 0: return Mat3::Identity() + 0.01 * n;
    case 1: return R * Vec3(rng.uniform(0.3, 3.0), rng.uniform(0.3, 3.0), rng.uniform(0.3, 3.0)).asDiagonal() * n;
    case 2: return R * Vec3(rng.uniform(0.5, 1.5), rng.uniform(0.001, 0.06), rng.uniform(0.5, 1.5)).asDiagonal();
    case 3: return R * Vec3(1.1, 0.9, -rng.uniform(0.5, 1.2)).asDiagonal();
    default: return Mat3::Zero();
  }
}

// Random states: 3,000 particles in bodies of 1 to 11 that cycle through a plastic material that
// flows at small strains, one that hardly flows, an elastic one and a fluid, so that every chunk
// of lanes mixes materials; random v, C, F (random_deformation) and J.
const mpm::MpmModel& random_model() {
  static const mpm::MpmModel m = [] {
    auto m = testing::empty_model(32, 1.0 / 32, 4e-4, 2, Vec3(0.0, -5.0, 0.0));
    m.materials = {testing::plastic(400.0, 0.2, 4.0), testing::plastic(5e3, 0.2, 500.0), testing::elastic(300.0, 0.3),
                   testing::fluid(200.0, 0.05)};
    Rng rng(17);
    for (int begin = 0; begin < 3000;) {
      const int size = 1 + static_cast<int>(rng.below(11));
      for (int i = 0; i < size; ++i) {
        mpm::Particle p;
        p.x = Vec3(rng.uniform(0.3, 0.7), rng.uniform(0.3, 0.7), rng.uniform(0.3, 0.7));
        m.initial.push_back(p);
      }
      const int material = static_cast<int>(m.bodies.size() % m.materials.size());
      m.bodies.push_back({"body", material, begin, begin + size, 1.0 / (64.0 * 64.0 * 64.0)});
      begin += size;
    }
    m.finalize("test");
    for (auto& p : m.initial) {
      p.v = Vec3(rng.normal(), rng.normal(), rng.normal());
      for (int i = 0; i < 9; ++i) p.C(i) = 2.0 * rng.normal();
      p.F = random_deformation(rng);
      p.J = rng.uniform(0.8, 1.2);
    }
    return m;
  }();
  return m;
}

std::vector<double> actions(const mpm::MpmModel& m, int env_steps) {
  Rng rng(43);
  std::vector<double> a(static_cast<std::size_t>(env_steps) * m.action_dim());
  for (auto& v : a) v = rng.uniform(-1.0, 1.0);
  return a;
}

EpisodeBits run(const mpm::MpmModel& m, int env_steps, SimdPath path, int threads) {
  const testing::SmoothObjective objective;
  ThreadTeam team(threads);
  mpm::MpmWorkspace ws(m);
  ws.lanes = path;
  const auto a = actions(m, env_steps);
  EpisodeBits r;
  r.loss = mpm::run_episode(m, ws, team, a, env_steps, objective);
  r.particles = ws.particles;
  r.action_grad.resize(a.size());
  r.grad_loss = mpm::run_episode_with_grad(m, ws, team, a, env_steps, objective, r.action_grad);
  r.state_grad = ws.adj;
  r.pose_grad = ws.pose_adj;
  return r;
}

EpisodeBits run(SimdPath path, int threads) { return run(every_primitive(), kEnvSteps, path, threads); }

template <class T>
std::string_view bytes(const std::vector<T>& v) {
  return {reinterpret_cast<const char*>(v.data()), v.size() * sizeof(T)};
}
std::string_view bytes(const double& d) { return {reinterpret_cast<const char*>(&d), sizeof d}; }

std::uint64_t digest(const EpisodeBits& r) {
  std::uint64_t h = fnv1a64(bytes(r.particles));
  for (auto b : {bytes(r.loss), bytes(r.grad_loss), bytes(r.action_grad), bytes(r.state_grad), bytes(r.pose_grad)})
    h = fnv1a64(b, h);
  return h;
}

// "" when the two byte strings are equal, else where they first differ
std::string first_difference(std::string_view got, std::string_view want) {
  if (got.size() != want.size()) return "sizes differ";
  if (std::memcmp(got.data(), want.data(), got.size()) == 0) return "";
  std::size_t i = 0;
  while (got[i] == want[i]) ++i;
  return "first differing byte " + std::to_string(i) + " of " + std::to_string(got.size());
}

void expect_same_bits(const EpisodeBits& got, const EpisodeBits& want, const char* what) {
  EXPECT_EQ(first_difference(bytes(got.particles), bytes(want.particles)), "") << what << ": particles";
  EXPECT_EQ(first_difference(bytes(got.loss), bytes(want.loss)), "") << what << ": loss";
  EXPECT_EQ(first_difference(bytes(got.grad_loss), bytes(want.grad_loss)), "") << what << ": gradient episode's loss";
  EXPECT_EQ(first_difference(bytes(got.action_grad), bytes(want.action_grad)), "") << what << ": gradient (actions)";
  EXPECT_EQ(first_difference(bytes(got.state_grad), bytes(want.state_grad)), "")
      << what << ": gradient (initial state)";
  EXPECT_EQ(first_difference(bytes(got.pose_grad), bytes(want.pose_grad)), "") << what << ": gradient (poses)";
}

const EpisodeBits& scalar_bits() {
  static const EpisodeBits r = run(SimdPath::scalar, 1);
  return r;
}

// Recorded with the scalar engine after its return mapping kept F_tmp inside the yield surface
// (PlasticineLab's form; before, with F rebuilt from max(sigma, 0.05), 0x0e5d6206809542ff since
// commit a46f158); a change here means the scalar path itself moved.
TEST(MpmLanes, ScalarPathGivesTheRecordedBits) {
  const EpisodeBits& r = scalar_bits();
  ASSERT_TRUE(std::isfinite(r.loss));
  ASSERT_TRUE(std::isfinite(r.grad_loss));
  EXPECT_EQ(digest(r), 0x9575597027a46661ULL) << std::hex << digest(r);
}

TEST(MpmLanes, Sse2PathGivesTheScalarBits) {
  expect_same_bits(run(SimdPath::sse2, 1), scalar_bits(), "sse2, 1 thread");
  expect_same_bits(run(SimdPath::sse2, 2), scalar_bits(), "sse2, 2 threads");
}

TEST(MpmLanes, Avx2PathGivesTheScalarBits) {
  if (!cpu_supports(SimdPath::avx2)) GTEST_SKIP() << "this CPU has no AVX2: only the SSE2 lanes run here";
  expect_same_bits(run(SimdPath::avx2, 1), scalar_bits(), "avx2, 1 thread");
  expect_same_bits(run(SimdPath::avx2, 2), scalar_bits(), "avx2, 2 threads");
}

// Each path from random states: one env step of two substeps, forward and gradient.
TEST(MpmLanes, EveryPathGivesTheScalarBitsFromRandomStates) {
  const EpisodeBits want = run(random_model(), 1, SimdPath::scalar, 1);
  ASSERT_TRUE(std::isfinite(want.loss));
  ASSERT_TRUE(std::isfinite(want.grad_loss));
  expect_same_bits(run(random_model(), 1, SimdPath::sse2, 1), want, "sse2");
  if (cpu_supports(SimdPath::avx2)) expect_same_bits(run(random_model(), 1, SimdPath::avx2, 1), want, "avx2");
}

TEST(MpmLanes, PathsComeFromTheOneDispatch) {
  // common/simd_path.hpp: names round-trip; the engine's default is the widest of scalar, sse2
  // and avx2 under the ceiling, available on this CPU, and avx2 exactly where the CPU has it
  // unless DSB_SIMD says narrower
  for (SimdPath p : {SimdPath::scalar, SimdPath::sse2, SimdPath::avx, SimdPath::avx2})
    EXPECT_EQ(parse_simd_path(simd_path_name(p)), p);
  EXPECT_FALSE(parse_simd_path("avx512").has_value());
  EXPECT_TRUE(cpu_supports(SimdPath::scalar));
  EXPECT_TRUE(cpu_supports(SimdPath::sse2));
  EXPECT_TRUE(cpu_supports(mpm::default_lane_path()));
  EXPECT_NE(mpm::default_lane_path(), SimdPath::avx);  // the engine has no AVX (without AVX2) lanes
  EXPECT_LE(mpm::default_lane_path(), simd_ceiling());
  const char* forced = std::getenv("DSB_SIMD");
  if (!forced || !*forced) {
    EXPECT_EQ(mpm::default_lane_path(), cpu_supports(SimdPath::avx2) ? SimdPath::avx2 : SimdPath::sse2);
  }
}

}  // namespace
}  // namespace dsb
