// `harness render`: the scenes the envs record (final frames against their losses, particle
// counts; the PlasticineLab targets' own pictures), the rasteriser (a known segment and dot at
// their pixels, decoded back with libgd), deterministic bytes, the command's errors, --best-of and
// --target.
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <string>
#include <vector>

#include <gd.h>
#include <gtest/gtest.h>

#include "common/parallel.hpp"
#include "common/rng.hpp"
#include "envs/cloth/flip_env.hpp"
#include "envs/mpm/fluid_env.hpp"
#include "envs/mpm/plb_env.hpp"
#include "envs/registry.hpp"
#include "harness/commands/render_command.hpp"
#include "render/camera.hpp"
#include "render/encode.hpp"
#include "render/palette.hpp"
#include "support/harness_process.hpp"
#include "support/temp_dir_test.hpp"

namespace dsb {
namespace {

namespace fs = std::filesystem;

// seeded point of the box
std::vector<double> point(int dim, std::uint64_t seed, double amplitude = 0.8) {
  Rng rng(seed);
  std::vector<double> x(dim);
  for (auto& v : x) v = rng.uniform(-amplitude, amplitude);
  return x;
}

const Disc& disc(const Scene& s, const std::string& name) {
  for (const auto& d : s.discs)
    if (d.name == name) return d;
  throw std::runtime_error("no disc " + name);
}

double distance(const ScenePoint& a, const ScenePoint& b) { return std::hypot(a[0] - b[0], a[1] - b[1], a[2] - b[2]); }

// mean over the pairs of discs named `state` and `target` (in order) of their distance
double mean_disc_distance(const Scene& s, const std::string& state) {
  std::vector<ScenePoint> a, b;
  for (const auto& d : s.discs) {
    if (d.name == state) a.push_back(d.centre);
    if (d.name == "target") b.push_back(d.centre);
  }
  EXPECT_EQ(a.size(), b.size());
  double sum = 0.0;
  for (std::size_t i = 0; i < a.size(); ++i) sum += distance(a[i], b[i]);
  return sum / static_cast<double>(a.size());
}

TEST(Render, FrameStepsSpreadFromStartToEnd) {
  EXPECT_EQ(frame_steps(100, 5), (std::vector<int>{0, 25, 50, 75, 100}));
  EXPECT_EQ(frame_steps(5, 5), (std::vector<int>{0, 1, 3, 4, 5}));
  EXPECT_EQ(frame_steps(1920, 4), (std::vector<int>{0, 640, 1280, 1920}));
  EXPECT_EQ(frame_steps(10, 1), (std::vector<int>{10}));
  EXPECT_EQ(frame_steps(2, 5), (std::vector<int>{0, 1, 2}));  // more frames than steps
}

TEST(Render, CartpoleFinalTipIsTheLossAwayFromTheTarget) {
  for (const char* name : {"cartpole1", "cartpole3"}) {
    const auto env = make_env(name);
    const auto x = point(env->dim(), 3);
    const auto frames = env->frames(x, 4, serial_team());
    ASSERT_EQ(frames.size(), 4u);
    EXPECT_EQ(frames.front().time, 0.0);
    EXPECT_NEAR(frames.back().time, 1.0, 1e-12);  // 100 steps of 0.01 s
    const Scene& last = frames.back().scene;
    EXPECT_NEAR(distance(disc(last, "tip").centre, disc(last, "target").centre), env->loss(x), 1e-12) << name;
  }
}

TEST(Render, RigidBallsEndTheLossAwayFromTheirTargets) {
  for (const char* name : {"bounce", "pinball-1x2", "pinball-4x4"}) {
    const auto env = make_env(name);
    const auto x = point(env->dim(), 5);
    const auto frames = env->frames(x, 3, serial_team());
    ASSERT_EQ(frames.size(), 3u);
    const Scene& last = frames.back().scene;
    EXPECT_NEAR(distance(disc(last, "ball").centre, disc(last, "target").centre), env->loss(x), 1e-12) << name;
  }
}

TEST(Render, ClothCornersEndTheLossAwayFromTheirTargets) {
  // corner losses: the mean over the 4 corners of |x_c - x_c*|
  for (const char* name : {"swing-velocity-corner", "flip"}) {
    const auto env = make_env(name);
    const auto x = point(env->dim(), 7, 0.5);
    const auto frames = env->frames(x, 2, serial_team());
    ASSERT_EQ(frames.size(), 2u);
    EXPECT_NEAR(mean_disc_distance(frames.back().scene, "corner"), env->loss(x), 1e-12) << name;
  }
  // single: the centre of mass to its target
  const auto env = make_env("swing-stiffness-single");
  const auto x = point(env->dim(), 8, 0.5);
  const auto frames = env->frames(x, 2, serial_team());
  EXPECT_NEAR(mean_disc_distance(frames.back().scene, "centre of mass"), env->loss(x), 1e-12);
}

// particles of the state and medium clouds of a frame: count and centre of mass
void expect_particles_inside(const Scene& s, int particles, double domain) {
  std::size_t n = 0;
  double c[3] = {0, 0, 0};
  for (const auto& cloud : s.clouds)
    if (cloud.role == Role::state || cloud.role == Role::medium)
      for (const auto& p : cloud.points) {
        ++n;
        for (int i = 0; i < 3; ++i) c[i] += p[i];
      }
  EXPECT_EQ(n, static_cast<std::size_t>(particles));
  for (double& v : c) {
    v /= static_cast<double>(n);
    EXPECT_TRUE(std::isfinite(v));
    EXPECT_GT(v, 0.0);
    EXPECT_LT(v, domain);
  }
}

TEST(Render, ParticleEnvsDrawEveryParticleInsideTheDomain) {
  {
    const auto env = make_env("fluid-h5");
    const auto& fluid = dynamic_cast<const mpm::FluidEnv&>(*env);
    const auto frames = env->frames(point(10, 11), 3, serial_team());
    ASSERT_EQ(frames.size(), 3u);
    EXPECT_EQ(frames.back().step, 5);
    const auto& cfg = fluid.model().config;
    expect_particles_inside(frames.back().scene, fluid.model().particles(), cfg.grid[0] * cfg.dx);  // 9,834 in 0.52 m
  }
  {
    const auto env = make_env("plb-pinch-h5");
    const auto& plb = dynamic_cast<const mpm::PlbEnv&>(*env);
    const auto frames = env->frames(point(env->dim(), 12), 2, serial_team());
    ASSERT_EQ(frames.size(), 2u);
    expect_particles_inside(frames.back().scene, plb.model().mpm.particles(), 1.0);  // 6,000 in the unit cube
    // the target shell and the manipulator outline are drawn
    std::size_t target = 0, tool = 0;
    for (const auto& c : frames.back().scene.clouds) {
      if (c.role == Role::target) target += c.points.size();
      if (c.role == Role::tool) tool += c.points.size();
    }
    EXPECT_GT(target, 100u);
    EXPECT_GT(tool, 100u);
  }
}

TEST(Render, PlbTargetFrameDrawsTheTargetsCellsAndPlasticineLabsBoxes) {
  const auto env = make_env("plb-triplemove");
  const auto& plb = dynamic_cast<const mpm::PlbEnv&>(*env);
  const auto frames = env->target_frames();
  ASSERT_EQ(frames.size(), 1u);
  // every drawn point a cell of the target above 1% of its maximum (node i at (i - pad) dx)
  const auto& g = plb.model().target;
  const int pad = plb.model().mpm.layout.pad;
  std::size_t tops = 0, sides = 0;
  for (const auto& d : frames[0].scene.discs) {
    const auto& p = d.centre;
    const int i = static_cast<int>(std::lround(p[0] * 64)) + pad, j = static_cast<int>(std::lround(p[1] * 64)) + pad,
              k = static_cast<int>(std::lround(p[2] * 64)) + pad;
    ASSERT_GT(g.at(i, j, k), 0.01 * g.max());
    // a lit face is a top face: no cell above it
    if (d.role == Role::state) {
      EXPECT_LE(g.at(i, j + 1, k), 0.01 * g.max());
    }
    tops += d.role == Role::state;
    sides += d.role == Role::trace;
  }
  // three blocks of about 8 x 8 top cells
  EXPECT_GT(tops, 150u);
  EXPECT_GT(sides, 300u);
  // PlasticineLab's three blocks' boxes: 6 polylines each (2 rectangles, 4 verticals), and the floor
  std::size_t boxes = 0, floor = 0;
  for (const auto& l : frames[0].scene.lines) {
    boxes += l.role == Role::target;
    floor += l.role == Role::fixed;
  }
  EXPECT_EQ(boxes, 18u);
  EXPECT_EQ(floor, 1u);
  EXPECT_TRUE(make_env("bounce")->target_frames().empty());
}

TEST(Render, SyntheticEnvsAreNotRenderable) {
  const auto env = make_env("sphere-10");
  EXPECT_FALSE(env->renderable());
  EXPECT_TRUE(env->frames(std::vector<double>(10, 0.0), 3, serial_team()).empty());
}

// a side-view frame with a state segment (0, 0) - (2, 1) and a medium dot at (2, 0)
std::vector<Frame> test_frames() {
  Frame f;
  f.scene.camera = Camera::side;
  f.scene.lines.push_back({Role::state, "segment", {{0, 0, 0}, {2, 1, 0}}});
  f.scene.clouds.push_back({Role::medium, "dot", {{2, 0, 0}}});
  return {f, f};
}

struct GdImage {
  gdImagePtr im = nullptr;
  ~GdImage() {
    if (im) gdImageDestroy(im);
  }
  render::Rgb at(int x, int y) const {
    const int c = gdImageGetPixel(im, x, y);
    return {gdImageRed(im, c), gdImageGreen(im, c), gdImageBlue(im, c)};
  }
};

void expect_rgb(const render::Rgb& got, const render::Rgb& want, const char* where) {
  EXPECT_EQ(got.r, want.r) << where;
  EXPECT_EQ(got.g, want.g) << where;
  EXPECT_EQ(got.b, want.b) << where;
}

TEST(Render, RasteriserDrawsAtTheFittedPixels) {
  // fit: bounds 2 x 1 m in a 200 px panel: 184 px inside the margins, so 92 px per metre and a
  // 92 px drawing, 124 px with margins and label; world (0, 0) at pixel (8, 116)
  const auto frames = test_frames();
  const render::Viewport vp = render::fit(frames, 200);
  EXPECT_EQ(vp.height, 124);
  EXPECT_DOUBLE_EQ(vp.scale, 92.0);
  render::RenderOptions png;
  png.width = 200;
  const auto bytes = render::encode_frames(frames, png);
  GdImage img{gdImageCreateFromPngPtr(static_cast<int>(bytes.size()), const_cast<unsigned char*>(bytes.data()))};
  ASSERT_NE(img.im, nullptr);
  EXPECT_EQ(gdImageSX(img.im), 400);  // two panels side by side
  EXPECT_EQ(gdImageSY(img.im), 124);
  const render::Rgb state = render::role_colour(Role::state), medium = render::role_colour(Role::medium);
  // the segment's midpoint (1, 0.5) at (100, 70), in both panels; the dot at (192, 116)
  expect_rgb(img.at(100, 70), state, "midpoint");
  expect_rgb(img.at(300, 70), state, "midpoint, second panel");
  expect_rgb(img.at(192, 116), medium, "dot");
  expect_rgb(img.at(100, 100), {255, 255, 255}, "background");
  // GIF: one panel per frame, the same pixels
  render::RenderOptions gif = png;
  gif.format = render::ImageFormat::gif;
  const auto anim = render::encode_frames(frames, gif);
  GdImage first{gdImageCreateFromGifPtr(static_cast<int>(anim.size()), const_cast<unsigned char*>(anim.data()))};
  ASSERT_NE(first.im, nullptr);
  EXPECT_EQ(gdImageSX(first.im), 200);
  EXPECT_EQ(gdImageSY(first.im), 124);
  expect_rgb(first.at(100, 70), state, "gif midpoint");
  // same frames, same bytes
  EXPECT_EQ(render::encode_frames(frames, png), bytes);
  EXPECT_EQ(render::encode_frames(frames, gif), anim);
}

class RenderCli : public dsb::testing::TempDirTest {
 protected:
  testing::HarnessResult harness(const std::string& args) { return testing::run_harness(dir_, args); }
  // one line on stderr that names `value`, exit 2, no output file
  void expect_usage_error(const std::string& args, const std::string& value) {
    const auto r = harness(args);
    EXPECT_EQ(r.code, 2) << args;
    EXPECT_NE(r.err.find(value), std::string::npos) << args << ": " << r.err;
    EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
  }
};

TEST_F(RenderCli, SameCommandSameBytes) {
  const std::string args = "render --env bounce --x 0.2,0.5,-0.3 --frames 4 --width 160 --out ";
  ASSERT_EQ(harness(args + path("a.png")).code, 0);
  ASSERT_EQ(harness(args + path("b.png")).code, 0);
  const std::string a = testing::read_file(path("a.png"));
  EXPECT_GT(a.size(), 1000u);
  EXPECT_EQ(a, testing::read_file(path("b.png")));
  ASSERT_EQ(harness(args + path("a.gif")).code, 0);
  ASSERT_EQ(harness(args + path("b.gif")).code, 0);
  EXPECT_EQ(testing::read_file(path("a.gif")), testing::read_file(path("b.gif")));
}

TEST_F(RenderCli, BadValuesExitTwoWithOneLine) {
  const std::string out = " --out " + path("r.png");
  expect_usage_error("render --env nosuchenv --x 0" + out, "nosuchenv");
  expect_usage_error("render --env sphere-10 --x 0,0,0,0,0,0,0,0,0,0" + out, "sphere-10");
  expect_usage_error("render --env bounce --x 0.1,0.2" + out, "--x has 2 values");
  expect_usage_error("render --env bounce --x 0.1,0.2,1.5" + out, "1.5");
  expect_usage_error("render --env bounce --x 0.1,0.2,abc" + out, "abc");
  expect_usage_error("render --env bounce --x 0,0,0 --out " + path("r.jpg"), "r.jpg");
  expect_usage_error("render --env bounce --x 0,0,0 --out " + path("no/such/dir/r.png"), "no/such/dir/r.png");
  expect_usage_error("render --env bounce --x 0,0,0 --frames 0" + out, "--frames");
  expect_usage_error("render --env bounce --x 0,0,0 --width 10" + out, "--width");
  expect_usage_error("render --env bounce" + out, "--best-of");
  expect_usage_error("render --env bounce --x 0,0,0 --best-of " + path("none.sqlite") + out, "--best-of");
  expect_usage_error("render --env bounce --best-of " + path("none.sqlite") + out, "none.sqlite");
  EXPECT_FALSE(fs::exists(path("r.png")));
}

TEST_F(RenderCli, TargetDrawsOnePanelOfTheTarget) {
  const auto r = harness("render --env plb-pinch --target --width 200 --out " + path("t.png"));
  ASSERT_EQ(r.code, 0) << r.err;
  const std::string bytes = testing::read_file(path("t.png"));
  GdImage img{gdImageCreateFromPngPtr(static_cast<int>(bytes.size()), const_cast<char*>(bytes.data()))};
  ASSERT_NE(img.im, nullptr);
  EXPECT_EQ(gdImageSX(img.im), 200);  // one panel
  const std::string out = " --out " + path("r.png");
  expect_usage_error("render --env plb-pinch --target --x 0" + out, "--x");
  expect_usage_error("render --env plb-pinch --target --frames 3" + out, "--frames");
  expect_usage_error("render --env bounce --target" + out, "bounce");
  expect_usage_error("render --env sphere-10 --target" + out, "sphere-10");
  EXPECT_FALSE(fs::exists(path("r.png")));
}

TEST_F(RenderCli, BestOfRendersTheBestDoneRun) {
  const std::string db = path("runs.sqlite");
  ASSERT_EQ(harness("--env bounce --optimizer random --seeds 2 --budget 5 --quiet --db " + db).code, 0);
  const BestRun best = best_run_of(db, "bounce");
  EXPECT_EQ(best.optimizer, "random");
  // the same run's best_x through --x gives the same picture, and its loss is the run's best_loss
  const auto r = harness("render --env bounce --best-of " + db + " --out " + path("best.png"));
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_NE(r.out.find("random, seed " + std::to_string(best.seed)), std::string::npos) << r.out;
  ASSERT_EQ(harness("render --env bounce --x " + best.best_x + " --out " + path("x.png")).code, 0);
  EXPECT_EQ(testing::read_file(path("best.png")), testing::read_file(path("x.png")));
  const auto env = make_env("bounce");
  std::vector<double> x;
  for (std::size_t pos = 0; pos <= best.best_x.size();) {
    const auto comma = std::min(best.best_x.find(',', pos), best.best_x.size());
    x.push_back(std::stod(best.best_x.substr(pos, comma - pos)));
    pos = comma + 1;
  }
  EXPECT_EQ(env->loss(x), best.best_loss);
  // an env without runs in it
  const auto none = harness("render --env cartpole1 --best-of " + db + " --out " + path("none.png"));
  EXPECT_EQ(none.code, 2);
  EXPECT_NE(none.err.find("no done run of env 'cartpole1'"), std::string::npos) << none.err;
}

TEST_F(RenderCli, BestOfOneOptimizerRendersThatOptimizersBestRun) {
  const std::string db = path("two.sqlite");
  ASSERT_EQ(harness("--env bounce --optimizer random,cmaes --seeds 2 --budget 6 --quiet --db " + db).code, 0);
  const BestRun overall = best_run_of(db, "bounce");
  const BestRun cmaes = best_run_of(db, "bounce", "cmaes");
  const BestRun random = best_run_of(db, "bounce", "random");
  EXPECT_EQ(cmaes.optimizer, "cmaes");
  EXPECT_EQ(random.optimizer, "random");
  // the overall best is the better of the two optimizers' bests
  EXPECT_EQ(overall.best_loss, std::min(cmaes.best_loss, random.best_loss));
  const std::string other = overall.optimizer == "cmaes" ? "random" : "cmaes";
  const BestRun& theirs = other == "cmaes" ? cmaes : random;
  const auto r = harness("render --env bounce --best-of " + db + " --optimizer " + other + " --out " + path("o.png"));
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_NE(r.out.find(other + ", seed " + std::to_string(theirs.seed)), std::string::npos) << r.out;
  ASSERT_EQ(harness("render --env bounce --x " + theirs.best_x + " --out " + path("ox.png")).code, 0);
  EXPECT_EQ(testing::read_file(path("o.png")), testing::read_file(path("ox.png")));
  // an optimizer without runs there, and --optimizer without --best-of: exit 2 naming it, no file
  const auto none = harness("render --env bounce --best-of " + db + " --optimizer gd --out " + path("n.png"));
  EXPECT_EQ(none.code, 2);
  EXPECT_NE(none.err.find("by optimizer 'gd'"), std::string::npos) << none.err;
  const auto alone = harness("render --env bounce --x 0,0,0 --optimizer cmaes --out " + path("n.png"));
  EXPECT_EQ(alone.code, 2);
  EXPECT_NE(alone.err.find("--optimizer cmaes"), std::string::npos) << alone.err;
  const auto target = harness("render --env plb-pinch --target --optimizer cmaes --out " + path("n.png"));
  EXPECT_EQ(target.code, 2);
  EXPECT_NE(target.err.find("--optimizer"), std::string::npos) << target.err;
  EXPECT_FALSE(fs::exists(path("n.png")));
}

}  // namespace
}  // namespace dsb
