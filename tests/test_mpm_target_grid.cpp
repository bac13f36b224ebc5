// Target mass grids (envs/mpm/target_grid): the exact distance field against brute force and
// closed forms, the soft IoU's closed forms and invariances, and the gzip files: bit-identical
// round trips, stable bytes, and a UsageError naming the file for every kind of damage; the
// figures of a target's shape (target_shape) by hand.
#include <gtest/gtest.h>
#include <unistd.h>
#include <zlib.h>

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <limits>
#include <string>
#include <utility>
#include <vector>

#include "common/error.hpp"
#include "common/rng.hpp"
#include "envs/mpm/target_grid.hpp"
#include "envs/mpm/target_shape.hpp"
#include "support/temp_dir_test.hpp"

namespace dsb::mpm {
namespace {

constexpr double kDx = 1.0 / 64.0;

// sparse random grid: about `density` of the nodes get a value in (1, 2], the rest a value in
// [-0.1, threshold] (never a target); at least one target node
NodeGrid random_target(Rng& rng, std::array<int, 3> n, double density, double threshold) {
  NodeGrid g = NodeGrid::zeros(n);
  for (double& v : g.values) v = rng.uniform() < density ? 1.0 + (1.0 - rng.uniform()) : rng.uniform(-0.1, threshold);
  g.values[rng.below(g.values.size())] = 1.5;
  return g;
}

// minimum over all target nodes of the world-space distance, in doubles
std::vector<double> brute_force_distance(const NodeGrid& g, double threshold, double dx) {
  std::vector<std::array<int, 3>> targets;
  for (int i = 0; i < g.n[0]; ++i)
    for (int j = 0; j < g.n[1]; ++j)
      for (int k = 0; k < g.n[2]; ++k)
        if (g.at(i, j, k) > threshold) targets.push_back({i, j, k});
  std::vector<double> out(g.size(), 1000.0);
  for (int i = 0; i < g.n[0]; ++i)
    for (int j = 0; j < g.n[1]; ++j)
      for (int k = 0; k < g.n[2]; ++k) {
        double best = std::numeric_limits<double>::infinity();
        for (const auto& t : targets) {
          const double x = (i - t[0]) * dx, y = (j - t[1]) * dx, z = (k - t[2]) * dx;
          best = std::min(best, std::sqrt(x * x + y * y + z * z));
        }
        if (!targets.empty()) out[g.index(i, j, k)] = best;
      }
  return out;
}

TEST(MpmTargetGrid, DistanceMatchesBruteForce) {
  Rng rng(20240611);
  const double threshold = 1e-4;
  const std::vector<std::array<int, 3>> shapes{{7, 9, 11}, {24, 24, 24}, {1, 1, 13}, {5, 1, 8}, {16, 3, 1}};
  const std::vector<double> densities{0.0, 0.002, 0.02, 0.1, 0.5};  // 0: only the forced node
  std::vector<std::pair<std::array<int, 3>, double>> grids;
  for (const auto& n : shapes)
    for (double density : densities) grids.push_back({n, density});
  for (double density : {0.0, 1e-4, 1e-3}) grids.push_back({{64, 64, 64}, density});  // the tasks' grid
  int cases = 0, nodes = 0;
  double worst = 0.0;
  for (const auto& [n, density] : grids)
    for (int rep = 0; rep < 2; ++rep) {
      const NodeGrid g = random_target(rng, n, density, threshold);
      const std::vector<double> d = distance_to_mass(g, threshold, kDx);
      const std::vector<double> ref = brute_force_distance(g, threshold, kDx);
      ASSERT_EQ(d.size(), g.size());
      for (std::size_t i = 0; i < d.size(); ++i) {
        if (g.values[i] > threshold) {
          ASSERT_EQ(d[i], 0.0);
        }
        const double err = std::abs(d[i] - ref[i]) / std::max(ref[i], kDx);
        worst = std::max(worst, err);
        ASSERT_LE(err, 1e-12) << "shape " << n[0] << "x" << n[1] << "x" << n[2] << " density " << density << " node "
                              << i << ": " << d[i] << " vs " << ref[i];
      }
      ++cases;
      nodes += static_cast<int>(d.size());
    }
  std::printf("distance_to_mass vs brute force: %d grids, %d nodes, worst relative difference %.3g\n", cases, nodes,
              worst);
}

TEST(MpmTargetGrid, DistanceSingleNodeClosedForm) {
  NodeGrid g = NodeGrid::zeros({7, 9, 11});
  g.at(2, 6, 3) = 0.5;
  const std::vector<double> d = distance_to_mass(g, 1e-4, kDx);
  for (int i = 0; i < 7; ++i)
    for (int j = 0; j < 9; ++j)
      for (int k = 0; k < 11; ++k) {
        const int di = i - 2, dj = j - 6, dk = k - 3;
        EXPECT_EQ(d[g.index(i, j, k)], std::sqrt(static_cast<double>(di * di + dj * dj + dk * dk)) * kDx);
      }
  EXPECT_EQ(d[g.index(6, 0, 10)], std::sqrt(16.0 + 36.0 + 49.0) / 64.0);  // the far corner
}

TEST(MpmTargetGrid, DistanceEmptyTarget) {
  NodeGrid g = NodeGrid::zeros({5, 6, 7});
  g.at(1, 2, 3) = 1e-4;  // equal to the threshold: not a target
  g.at(4, 5, 6) = -3.0;
  for (double v : distance_to_mass(g, 1e-4, kDx)) EXPECT_EQ(v, 1000.0);
  for (double v : distance_to_mass(g, 1e-4, kDx, 7.5)) EXPECT_EQ(v, 7.5);
  EXPECT_TRUE(distance_to_mass(NodeGrid::zeros({0, 4, 4}), 0.0, kDx).empty());
}

TEST(MpmTargetGrid, DistanceThresholdIsStrict) {
  const double threshold = 0.25;
  NodeGrid g = NodeGrid::zeros({4, 4, 4});
  g.at(0, 0, 0) = threshold;                       // equal: not a target
  g.at(3, 3, 3) = std::nextafter(threshold, 1.0);  // just above: a target
  const std::vector<double> d = distance_to_mass(g, threshold, 0.5);
  EXPECT_EQ(d[g.index(3, 3, 3)], 0.0);
  EXPECT_EQ(d[g.index(0, 0, 0)], std::sqrt(27.0) * 0.5);
  EXPECT_EQ(d[g.index(3, 3, 0)], 1.5);
}

// ---- soft IoU ----------------------------------------------------------------------------------

TEST(MpmTargetGrid, SoftIouIdenticalGrids) {
  Rng rng(7);
  NodeGrid binary = NodeGrid::zeros({6, 5, 4});
  for (double& v : binary.values) v = rng.uniform() < 0.3 ? 0.75 : 0.0;
  binary.values[3] = 0.75;
  EXPECT_EQ(soft_iou(binary, binary), 1.0);  // every value 0 or the max: exactly 1

  // general values: S / (2 A - S) with A = sum m / max m, S = sum (m / max m)^2
  NodeGrid g = NodeGrid::zeros({6, 5, 4});
  for (double& v : g.values) v = rng.uniform() < 0.5 ? rng.uniform(0.0, 2.0) : 0.0;
  const double mx = g.max();
  double a = 0.0, s = 0.0;
  for (double v : g.values) {
    a += v / mx;
    s += (v / mx) * (v / mx);
  }
  const double iou = soft_iou(g, g);
  EXPECT_NEAR(iou, s / (2.0 * a - s), 1e-15);
  EXPECT_LT(iou, 1.0);
  std::printf("soft IoU of a random grid with itself: %.17g (closed form %.17g)\n", iou, s / (2.0 * a - s));
}

TEST(MpmTargetGrid, SoftIouDisjointAndZero) {
  NodeGrid m = NodeGrid::zeros({3, 3, 3}), t = NodeGrid::zeros({3, 3, 3});
  m.at(0, 0, 0) = 2.0;
  m.at(0, 1, 0) = 1.0;
  t.at(2, 2, 2) = 5.0;
  EXPECT_EQ(soft_iou(m, t), 0.0);
  EXPECT_EQ(soft_iou(m, NodeGrid::zeros({3, 3, 3})), 0.0);  // all-zero grid: defined as 0
  EXPECT_EQ(soft_iou(NodeGrid::zeros({3, 3, 3}), t), 0.0);
  EXPECT_EQ(soft_iou(NodeGrid::zeros({3, 3, 3}), NodeGrid::zeros({3, 3, 3})), 0.0);
  EXPECT_THROW(soft_iou(m, NodeGrid::zeros({3, 3, 4})), std::invalid_argument);
}

TEST(MpmTargetGrid, SoftIouHandExample) {
  // m = (1, 2, 0), t = (0, 4, 4): max 2 and 4, S = (1 * 0 + 2 * 4 + 0 * 4) / 8 = 1,
  // sum m / max m = 1.5, sum t / max t = 2, IoU = 1 / (1.5 + 2 - 1) = 0.4
  const NodeGrid m{{1, 1, 3}, {1.0, 2.0, 0.0}}, t{{1, 1, 3}, {0.0, 4.0, 4.0}};
  EXPECT_DOUBLE_EQ(soft_iou(m, t), 0.4);
  EXPECT_DOUBLE_EQ(soft_iou(t, m), 0.4);
  // a small negative target value enters as it is: S = 1 - 0.5 * 0.01 / 4 ... computed by hand
  const NodeGrid t2{{1, 1, 3}, {-0.01, 4.0, 4.0}};
  const double s = 1.0 + 0.5 * (-0.01 / 4.0);
  EXPECT_DOUBLE_EQ(soft_iou(m, t2), s / (1.5 + (2.0 - 0.01 / 4.0) - s));
}

TEST(MpmTargetGrid, SoftIouScaleInvariant) {
  Rng rng(99);
  NodeGrid m = NodeGrid::zeros({8, 8, 8}), t = NodeGrid::zeros({8, 8, 8});
  for (std::size_t i = 0; i < m.values.size(); ++i) {
    m.values[i] = rng.uniform() < 0.4 ? rng.uniform(0.0, 1e-3) : 0.0;
    t.values[i] = rng.uniform() < 0.4 ? rng.uniform(0.0, 5.0) : 0.0;
  }
  const double iou = soft_iou(m, t);
  NodeGrid m3 = m, m4 = m;
  for (double& v : m3.values) v *= 3.0;
  for (double& v : m4.values) v *= 4.0;
  EXPECT_GT(iou, 0.05);
  EXPECT_NEAR(soft_iou(m3, t), iou, 1e-14 * iou);
  EXPECT_EQ(soft_iou(m4, t), iou);  // a power of two scales exactly
  std::printf("soft IoU %.17g, mass x3 %.17g\n", iou, soft_iou(m3, t));
}

// ---- files -------------------------------------------------------------------------------------

// target_shape: a hand-made grid (pad 1, dx 1/64) of two blocks, the figures by hand
TEST(MpmTargetShape, FiguresOfTwoBlocksByHand) {
  NodeGrid g = NodeGrid::zeros({12, 10, 8});
  // block A: nodes i 1..3, j 1..2, k 1 (6 cells of 1.0); block B: node (8, 5, 6) of 2.0 (the max)
  for (int i = 1; i <= 3; ++i)
    for (int j = 1; j <= 2; ++j) g.at(i, j, 1) = 1.0;
  g.at(8, 5, 6) = 2.0;
  // below 1% of the max (0.02): in the mass and centre, in no body
  g.at(10, 8, 7) = 0.015;
  const TargetShape s = describe_target_shape(g, 1, kDx);
  EXPECT_DOUBLE_EQ(s.threshold, 0.02);
  EXPECT_DOUBLE_EQ(s.mass, 8.015);
  // centre: sum of value x (index - pad) dx over the mass
  const double cx = (1.0 * (0 + 1 + 2) * 2 + 2.0 * 7 + 0.015 * 9) / 8.015 * kDx;
  EXPECT_NEAR(s.centre.x(), cx, 1e-15);
  ASSERT_EQ(s.bodies.size(), 2u);
  EXPECT_EQ(s.cells, 7);
  const TargetBody& a = s.bodies[0];  // most cells first
  EXPECT_EQ(a.cells, 6);
  EXPECT_DOUBLE_EQ(a.mass, 6.0);
  EXPECT_EQ(a.lo, Vec3(0, 0, 0));
  EXPECT_EQ(a.hi, Vec3(2 * kDx, kDx, 0));
  EXPECT_NEAR(a.centre.x(), kDx, 1e-15);
  EXPECT_NEAR(a.centre.y(), 0.5 * kDx, 1e-15);
  const TargetBody& b = s.bodies[1];
  EXPECT_EQ(b.cells, 1);
  EXPECT_EQ(b.centre, Vec3(7 * kDx, 4 * kDx, 5 * kDx));
  EXPECT_EQ(s.lo, Vec3(0, 0, 0));
  EXPECT_EQ(s.hi, Vec3(7 * kDx, 4 * kDx, 5 * kDx));
  // a threshold above block A leaves block B alone
  EXPECT_EQ(describe_target_shape(g, 1, kDx, 0.6).bodies.size(), 1u);
}

TEST(MpmTargetShape, BodiesJoinAcrossFacesOnly) {
  NodeGrid g = NodeGrid::zeros({4, 4, 4});
  g.at(1, 1, 1) = 1.0;
  g.at(2, 2, 1) = 1.0;  // an edge apart: two bodies
  EXPECT_EQ(describe_target_shape(g, 0, kDx).bodies.size(), 2u);
  g.at(2, 1, 1) = 1.0;  // the face between them: one
  const TargetShape s = describe_target_shape(g, 0, kDx);
  ASSERT_EQ(s.bodies.size(), 1u);
  EXPECT_EQ(s.bodies[0].cells, 3);
  EXPECT_THROW(describe_target_shape(NodeGrid::zeros({2, 2, 2}), 0, kDx), std::invalid_argument);
  EXPECT_THROW(describe_target_shape(g, 0, kDx, 1.0), std::invalid_argument);
}

TEST(MpmTargetShape, BoxIouCountsCells) {
  const Vec3 lo(0, 0, 0), hi(kDx, kDx, kDx);  // 2 x 2 x 2 cells
  EXPECT_DOUBLE_EQ(box_iou(lo, hi, lo, hi, kDx), 1.0);
  // one cell along x: 4 shared of 12
  EXPECT_DOUBLE_EQ(box_iou(lo, hi, lo + Vec3(kDx, 0, 0), hi + Vec3(kDx, 0, 0), kDx), 4.0 / 12.0);
  EXPECT_DOUBLE_EQ(box_iou(lo, hi, lo + Vec3(2 * kDx, 0, 0), hi + Vec3(2 * kDx, 0, 0), kDx), 0.0);
  // rounded coordinates (3 decimals, as the facts give them) count the same cells
  EXPECT_DOUBLE_EQ(
      box_iou(Vec3(0.391, 0.031, 0.359), Vec3(0.656, 0.219, 0.625), Vec3(25, 2, 23) * kDx, Vec3(42, 14, 40) * kDx, kDx),
      1.0);
}

class MpmTargetGridFile : public dsb::testing::TempDirTest {};

std::string read_bytes(const std::string& path) {
  std::ifstream f(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(f), std::istreambuf_iterator<char>()};
}

void write_bytes(const std::string& path, const std::string& bytes) {
  std::ofstream f(path, std::ios::binary | std::ios::trunc);
  f.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
}

// gzip of arbitrary text (to write damaged contents in a valid stream)
std::string gzip_text(const std::string& text) {
  z_stream zs{};
  EXPECT_EQ(deflateInit2(&zs, 6, Z_DEFLATED, 31, 8, Z_DEFAULT_STRATEGY), Z_OK);
  std::string out(deflateBound(&zs, text.size()), '\0');
  zs.next_in = reinterpret_cast<Bytef*>(const_cast<char*>(text.data()));
  zs.avail_in = static_cast<uInt>(text.size());
  zs.next_out = reinterpret_cast<Bytef*>(out.data());
  zs.avail_out = static_cast<uInt>(out.size());
  EXPECT_EQ(deflate(&zs, Z_FINISH), Z_STREAM_END);
  out.resize(zs.total_out);
  deflateEnd(&zs);
  return out;
}

NodeGrid random_storage_grid(Rng& rng, std::array<int, 3> n) {
  NodeGrid g = NodeGrid::zeros(n);
  const double specials[] = {std::numeric_limits<double>::denorm_min(),
                             2.2250738585072009e-308,
                             -4.9406564584124654e-322,
                             std::numeric_limits<double>::max(),
                             -1.0e300,
                             -1.0e-5,
                             -0.0,
                             0.1,
                             1.0 / 3.0,
                             std::numeric_limits<double>::min()};
  for (double& v : g.values) {
    const double u = rng.uniform();
    if (u < 0.6) continue;
    v = u < 0.7   ? specials[rng.below(std::size(specials))]
        : u < 0.8 ? -rng.uniform(0.0, 1e-3)
                  : rng.uniform(0.0, 2.0) * std::ldexp(1.0, static_cast<int>(rng.below(80)) - 40);
  }
  return g;
}

TEST_F(MpmTargetGridFile, RoundTripBitIdentical) {
  Rng rng(314159);
  const std::vector<std::array<int, 3>> shapes{{7, 9, 11}, {16, 16, 16}, {1, 1, 1}, {0, 3, 2}, {3, 1, 40}};
  int entries = 0;
  for (const auto& n : shapes)
    for (int rep = 0; rep < 3; ++rep) {
      const NodeGrid g = random_storage_grid(rng, n);
      write_grid_gz(path("g.gz"), g);
      const NodeGrid r = read_grid_gz(path("g.gz"));
      ASSERT_EQ(r.n, g.n);
      ASSERT_EQ(r.values.size(), g.values.size());
      for (std::size_t i = 0; i < g.values.size(); ++i) {
        ASSERT_EQ(std::bit_cast<std::uint64_t>(r.values[i]), std::bit_cast<std::uint64_t>(g.values[i]))
            << "node " << i << ": " << g.values[i];
        entries += std::bit_cast<std::uint64_t>(g.values[i]) != 0;
      }
    }
  std::printf("round trip: %d non-zero entries over %zu grids bit-identical\n", entries, 3 * shapes.size());
}

TEST_F(MpmTargetGridFile, StableBytes) {
  Rng rng(2718);
  const NodeGrid g = random_storage_grid(rng, {12, 10, 8});
  write_grid_gz(path("a.gz"), g);
  write_grid_gz(path("b.gz"), g);
  const std::string a = read_bytes(path("a.gz")), b = read_bytes(path("b.gz"));
  EXPECT_EQ(a, b);
  ASSERT_GE(a.size(), 10u);
  EXPECT_EQ(static_cast<unsigned char>(a[0]), 0x1f);  // gzip magic
  EXPECT_EQ(static_cast<unsigned char>(a[1]), 0x8b);
  EXPECT_EQ(a[3], 0);                               // flags: no name, no comment, no extra
  EXPECT_EQ(a.substr(4, 4), std::string(4, '\0'));  // mtime 0
  // the decoded text starts with the header
  NodeGrid small = NodeGrid::zeros({2, 1, 2});
  small.at(1, 0, 1) = 0.1;
  write_grid_gz(path("s.gz"), small);
  const NodeGrid r = read_grid_gz(path("s.gz"));
  EXPECT_EQ(r.at(1, 0, 1), 0.1);
  write_bytes(path("t.gz"), gzip_text("dsb-node-grid 1 2 1 2 1\n1 0 1 0.10000000000000001\n"));
  EXPECT_EQ(read_grid_gz(path("t.gz")).values, r.values);
}

TEST_F(MpmTargetGridFile, NonFiniteValuesAreNotWritten) {
  NodeGrid g = NodeGrid::zeros({2, 2, 2});
  g.at(1, 1, 0) = std::numeric_limits<double>::quiet_NaN();
  try {
    write_grid_gz(path("nan.gz"), g);
    FAIL() << "no exception";
  } catch (const UsageError& e) {
    EXPECT_NE(std::string(e.what()).find(path("nan.gz")), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("(1, 1, 0)"), std::string::npos) << e.what();
  }
}

TEST_F(MpmTargetGridFile, DamagedFilesThrowUsageError) {
  Rng rng(4242);
  const NodeGrid g = random_storage_grid(rng, {6, 6, 6});
  write_grid_gz(path("good.gz"), g);
  const std::string good = read_bytes(path("good.gz"));

  struct Case {
    std::string name, bytes, expect;  // expect: a word of the message
  };
  std::vector<Case> cases{
      {"truncated_half", good.substr(0, good.size() / 2), "truncated"},
      {"truncated_trailer", good.substr(0, good.size() - 3), "truncated"},
      {"empty", "", "empty"},
      {"plain_text", "dsb-node-grid 1 1 1 1 0\n", "gzip"},
      {"bad_crc", good.substr(0, good.size() - 8) + std::string(4, '\x55') + good.substr(good.size() - 4), "gzip"},
      {"trailing_data", good + "xyz", "after the end"},
      {"wrong_magic", gzip_text("dsb-grid 1 2 2 2 0\n"), "not a dsb-node-grid"},
      {"wrong_version", gzip_text("dsb-node-grid 2 2 2 2 0\n"), "version"},
      {"short_header", gzip_text("dsb-node-grid 1 2 2 0\n"), "bad header"},
      {"negative_extent", gzip_text("dsb-node-grid 1 2 -2 2 0\n"), "bad header"},
      {"huge_grid", gzip_text("dsb-node-grid 1 65536 65536 65536 0\n"), "exceeds"},
      {"count_too_big", gzip_text("dsb-node-grid 1 2 2 2 9\n"), "exceeds"},
      {"no_text", gzip_text(""), "no header"},
      {"index_out_of_range", gzip_text("dsb-node-grid 1 2 3 4 2\n0 0 0 1\n0 3 0 1\n"), "outside"},
      {"negative_index", gzip_text("dsb-node-grid 1 2 3 4 1\n0 0 -1 1\n"), "outside"},
      {"duplicate_index", gzip_text("dsb-node-grid 1 2 3 4 3\n0 0 1 1\n1 2 3 2\n0 0 1 1\n"), "duplicate"},
      {"bad_number", gzip_text("dsb-node-grid 1 2 3 4 1\n0 0 1 1.5x\n"), "bad number"},
      {"nan_number", gzip_text("dsb-node-grid 1 2 3 4 1\n0 0 1 nan\n"), "bad number"},
      {"overflow_number", gzip_text("dsb-node-grid 1 2 3 4 1\n0 0 1 1e999\n"), "bad number"},
      {"bad_index", gzip_text("dsb-node-grid 1 2 3 4 1\n0 a 1 1\n"), "bad node index"},
      {"extra_field", gzip_text("dsb-node-grid 1 2 3 4 1\n0 0 1 1 7\n"), "expected 'i j k value'"},
      {"double_space", gzip_text("dsb-node-grid 1 2 3 4 1\n0  0 1 1\n"), "expected 'i j k value'"},
      {"too_few_entries", gzip_text("dsb-node-grid 1 2 3 4 3\n0 0 1 1\n1 2 3 2\n"), "ends after 2 of the 3"},
      {"too_many_entries", gzip_text("dsb-node-grid 1 2 3 4 1\n0 0 1 1\n1 2 3 2\n"), "more entries"},
      {"no_final_newline", gzip_text("dsb-node-grid 1 2 3 4 1\n0 0 1 1"), "no end of line"},
  };
  for (const Case& c : cases) {
    const std::string p = path(c.name + ".gz");
    write_bytes(p, c.bytes);
    try {
      read_grid_gz(p);
      ADD_FAILURE() << c.name << ": no exception";
    } catch (const UsageError& e) {
      const std::string msg = e.what();
      EXPECT_NE(msg.find(p), std::string::npos) << c.name << ": " << msg;
      EXPECT_NE(msg.find(c.expect), std::string::npos) << c.name << ": " << msg;
      EXPECT_EQ(msg.find('\n'), std::string::npos) << c.name << ": " << msg;
      std::printf("  %-20s %s\n", c.name.c_str(), msg.c_str());
    }
  }
  const std::string missing = path("missing.gz");
  try {
    read_grid_gz(missing);
    ADD_FAILURE() << "missing file: no exception";
  } catch (const UsageError& e) {
    EXPECT_NE(std::string(e.what()).find(missing), std::string::npos) << e.what();
  }
  EXPECT_NO_THROW(read_grid_gz(path("good.gz")));
}

}  // namespace
}  // namespace dsb::mpm
