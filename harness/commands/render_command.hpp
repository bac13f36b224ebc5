#pragma once
// `harness render`: pictures of one rollout (Env::frames) as a PNG strip or an animated GIF.
#include <cstdint>
#include <string>

#include "harness/store/best_run.hpp"

namespace dsb {

struct RenderArgs {
  std::string env;
  std::string x;              // comma-separated point in [-1, 1]^dim, or
  std::string best_of;        // a harness database: the best_x of --env's best done run
  std::string optimizer;      // with best_of: of this optimizer's runs only
  std::string out;            // FILE.png (strip) or FILE.gif (animation)
  int frames = 5;             // 1 to 20 time points, from the start to the end of the episode
  bool frames_given = false;  // --frames on the command line
  int width = 320;            // pixels per frame, 64 to 2000
  bool force = false;         // write over an existing --out (never over a database: output_path.hpp)
  bool target = false;  // draw the env's target alone (Env::target_frames), no rollout: no --x, --best-of, --frames
};

// Checks every argument before any rollout (one-line UsageError naming the bad value: unknown or
// synthetic env, --x of the wrong dimension or outside the box, an extension other than .png or
// .gif, an unwritable or existing --out, --frames or --width out of range; --target with --x,
// --best-of or --frames, or for an env without a target shape; --optimizer without --best-of),
// renders and writes --out whole or
// not at all.
int command_render(const RenderArgs& args);

}  // namespace dsb
