// The MPM engine's lanes paths (envs/mpm/lane_path.hpp) give the scalar path's bits: a forward and
// a gradient episode on a small scene with every material and every primitive, through each path
// the CPU has, on one and two threads, compared byte for byte (particles, loss, gradient with
// respect to the actions, the initial state and the poses); and the scalar path still gives the
// bits recorded before the lanes existed.
#include <cmath>
#include <cstring>
#include <string>
#include <string_view>
#include <vector>

#include <gtest/gtest.h>

#include "common/parallel.hpp"
#include "common/rng.hpp"
#include "envs/mpm/episode.hpp"
#include "envs/mpm/lane_path.hpp"
#include "support/mpm_scenes.hpp"

namespace dsb {
namespace {

using mpm::LanePath;

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

const mpm::MpmModel& scene() {
  static const mpm::MpmModel m = testing::every_primitive_scene(4);
  return m;
}

std::vector<double> actions() {
  Rng rng(43);
  std::vector<double> a(static_cast<std::size_t>(kEnvSteps) * scene().action_dim());
  for (auto& v : a) v = rng.uniform(-1.0, 1.0);
  return a;
}

EpisodeBits run(LanePath path, int threads) {
  const auto& m = scene();
  const testing::SmoothObjective objective;
  ThreadTeam team(threads);
  mpm::MpmWorkspace ws(m);
  ws.lanes = path;
  const auto a = actions();
  EpisodeBits r;
  r.loss = mpm::run_episode(m, ws, team, a, kEnvSteps, objective);
  r.particles = ws.particles;
  r.action_grad.resize(a.size());
  r.grad_loss = mpm::run_episode_with_grad(m, ws, team, a, kEnvSteps, objective, r.action_grad);
  r.state_grad = ws.adj;
  r.pose_grad = ws.pose_adj;
  return r;
}

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
  EXPECT_EQ(first_difference(bytes(got.state_grad), bytes(want.state_grad)), "") << what << ": gradient (initial state)";
  EXPECT_EQ(first_difference(bytes(got.pose_grad), bytes(want.pose_grad)), "") << what << ": gradient (poses)";
}

const EpisodeBits& scalar_bits() {
  static const EpisodeBits r = run(LanePath::scalar, 1);
  return r;
}

// Recorded with the engine before the lanes paths existed (commit a46f158); a change here means
// the scalar path itself moved.
TEST(MpmLanes, ScalarPathGivesTheRecordedBits) {
  const EpisodeBits& r = scalar_bits();
  ASSERT_TRUE(std::isfinite(r.loss));
  ASSERT_TRUE(std::isfinite(r.grad_loss));
  EXPECT_EQ(digest(r), 0x0e5d6206809542ffULL) << std::hex << digest(r);
}

TEST(MpmLanes, Sse2PathGivesTheScalarBits) {
  expect_same_bits(run(LanePath::sse2, 1), scalar_bits(), "sse2, 1 thread");
  expect_same_bits(run(LanePath::sse2, 2), scalar_bits(), "sse2, 2 threads");
}

TEST(MpmLanes, Avx2PathGivesTheScalarBits) {
  if (!mpm::lane_path_available(LanePath::avx2)) GTEST_SKIP() << "this CPU has no AVX2: only the SSE2 lanes run here";
  expect_same_bits(run(LanePath::avx2, 1), scalar_bits(), "avx2, 1 thread");
  expect_same_bits(run(LanePath::avx2, 2), scalar_bits(), "avx2, 2 threads");
}

TEST(MpmLanes, PathsByName) {
  for (LanePath p : {LanePath::scalar, LanePath::sse2, LanePath::avx2})
    EXPECT_EQ(mpm::parse_lane_path(mpm::lane_path_name(p)), p);
  EXPECT_FALSE(mpm::parse_lane_path("avx512").has_value());
  EXPECT_TRUE(mpm::lane_path_available(LanePath::scalar));
  EXPECT_TRUE(mpm::lane_path_available(LanePath::sse2));
  EXPECT_TRUE(mpm::lane_path_available(mpm::best_lane_path()));
  EXPECT_TRUE(mpm::lane_path_available(mpm::default_lane_path()));
}

}  // namespace
}  // namespace dsb
