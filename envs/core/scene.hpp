#pragma once
// What `harness render` draws: a scene description that envs fill and the rasteriser
// (render/) projects. Plain data in world units (m), 3-D points (x right, y up, z towards the
// viewer of the side view); 2-D envs leave z = 0. Every item has a colour role and a name (tests
// and captions find items by it). Nothing here simulates: an env records states of its own
// rollout and turns them into scenes (Env::frames).
#include <array>
#include <string>
#include <vector>

namespace dsb {

using ScenePoint = std::array<double, 3>;  // x, y, z (m)

// colour roles: the rasteriser owns the palette
enum class Role {
  state,   // what the rollout moves: links, ball, cloth, particles
  target,  // where the loss wants it
  tool,    // what the parameters move: cart, paddles, pan, ladle, manipulators
  fixed,   // static geometry: ground, walls, tank, board
  trace,   // the path the state took so far
  medium,  // other simulated matter around the state (the syrup around the sugar cube)
};

// how the 3-D scene is projected (orthographic)
enum class Camera {
  side,     // x right, y up (the 2-D rigid envs)
  oblique,  // a fixed view from the front right and above (the 3-D envs)
};

struct Polyline {
  Role role = Role::state;
  std::string name;
  std::vector<ScenePoint> points;  // (n x 3), n >= 2
  bool closed = false;             // joins the last point to the first
};

// a circle of world radius (a sphere seen from any side); filled or its outline
struct Disc {
  Role role = Role::state;
  std::string name;
  ScenePoint centre{};
  double radius = 0.0;  // m
  bool filled = true;
};

// many small dots (particles, target voxels); faint ones are drawn in a light tint, under the rest
struct PointCloud {
  Role role = Role::state;
  std::string name;
  std::vector<ScenePoint> points;  // (n x 3)
  bool faint = false;
};

struct Scene {
  Camera camera = Camera::side;
  std::vector<PointCloud> clouds;  // drawn first (faint ones before the others)
  std::vector<Polyline> lines;
  std::vector<Disc> discs;  // drawn last
};

// one picture of the rollout: the state after `step` env steps (time = step x the env's step)
struct Frame {
  int step = 0;
  double time = 0.0;  // s
  Scene scene;
};

// `n` steps evenly spread over 0..steps, round(k steps / (n - 1)) for k = 0..n-1: the first 0 and
// the last `steps` (n = 1: only the last); each step once, so fewer than n when n > steps + 1.
// n >= 1, steps >= 0
std::vector<int> frame_steps(int steps, int n);

}  // namespace dsb
