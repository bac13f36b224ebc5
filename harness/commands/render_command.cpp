#include "harness/commands/render_command.hpp"

#include <CLI/CLI.hpp>

#include <cmath>
#include <cstdio>
#include <iostream>
#include <memory>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "common/error.hpp"
#include "common/parallel.hpp"
#include "envs/registry.hpp"
#include "harness/commands/command.hpp"
#include "harness/commands/point_text.hpp"
#include "harness/core/output_path.hpp"
#include "harness/core/results_versions.hpp"
#include "render/encode.hpp"

namespace dsb {

namespace {

// `render --target`: the env's target shape alone (Env::target_frames), one panel
int render_target(const RenderArgs& a, const render::RenderOptions& options) {
  if (!a.x.empty() || !a.best_of.empty() || !a.optimizer.empty())
    throw UsageError("--target draws the env's target: it takes no --x, --best-of or --optimizer");
  if (a.frames_given) throw UsageError("--target draws one picture: it takes no --frames");
  const auto env = make_env(a.env);
  if (!env->renderable()) throw UsageError(fmt::format("env '{}' is not simulated: nothing to render", a.env));
  std::vector<Frame> frames = env->target_frames();
  if (frames.empty()) throw UsageError(fmt::format("--target: env '{}' has no target shape to draw", a.env));
  OutputFile file("--out", a.out, a.force);
  const std::vector<unsigned char> bytes = render::encode_frames(frames, options);
  file.stream().write(reinterpret_cast<const char*>(bytes.data()), static_cast<std::streamsize>(bytes.size()));
  file.commit();
  std::cout << fmt::format("render: the target of {} -> {} ({} bytes)\n", a.env, a.out, bytes.size());
  return 0;
}

}  // namespace

int command_render(const RenderArgs& a) {
  // arguments that need no env: output format, counts, the source of x
  render::RenderOptions options;
  options.width = a.width;
  if (!render::format_of_path(a.out, options.format))
    throw UsageError(fmt::format("--out: '{}' must end in .png or .gif", a.out));
  if (a.frames < 1 || a.frames > 20) throw UsageError(fmt::format("--frames must be from 1 to 20, got {}", a.frames));
  if (a.width < 64 || a.width > 2000) throw UsageError(fmt::format("--width must be from 64 to 2000, got {}", a.width));
  if (a.target) return render_target(a, options);
  if (a.x.empty() == a.best_of.empty()) throw UsageError("render needs exactly one of --x, --best-of and --target");
  if (!a.optimizer.empty() && a.best_of.empty())
    throw UsageError(fmt::format("--optimizer {} picks among --best-of's runs: it needs --best-of", a.optimizer));
  // the env, which must be simulated, and the point
  const auto env = make_env(a.env);
  if (!env->renderable()) throw UsageError(fmt::format("env '{}' is not simulated: nothing to render", a.env));
  std::string source = "--x";
  std::string x_text = a.x;
  if (!a.best_of.empty()) {
    const BestRun best = best_run_of(a.best_of, a.env, a.optimizer);
    x_text = best.best_x;
    source =
        fmt::format("best run of {} ({}, seed {}, loss {:.6g})", a.best_of, best.optimizer, best.seed, best.best_loss);
  }
  const auto x = checked_point(*env, x_text, a.best_of.empty() ? "--x" : "--best-of best_x");
  // open the output before the rollout, so an unusable path fails at once
  OutputFile file("--out", a.out, a.force);
  const std::vector<Frame> frames = env->frames(x, a.frames, serial_team());
  if (frames.empty()) throw std::runtime_error(fmt::format("env '{}' blew up before its first frame", a.env));
  const std::vector<unsigned char> bytes = render::encode_frames(frames, options);
  file.stream().write(reinterpret_cast<const char*>(bytes.data()), static_cast<std::streamsize>(bytes.size()));
  file.commit();
  std::cout << fmt::format("render: {} at {}: {} frames (t = {:.3f} .. {:.3f} s) -> {} ({} bytes)\n", a.env, source,
                           frames.size(), frames.front().time, frames.back().time, a.out, bytes.size());
  return 0;
}

Command render_command() {
  return {"render", "pictures of a rollout at a few time points (PNG strip or animated GIF)", [](CLI::App& app) {
            auto a = std::make_shared<RenderArgs>();
            app.add_option("--env", a->env, "env name (a simulated env)")->required();
            app.add_option("--x", a->x, "comma-separated parameters in [-1, 1]");
            app.add_option("--best-of", a->best_of, "harness database: render the best_x of the env's best done run");
            app.add_option("--optimizer", a->optimizer, "with --best-of: the best done run of this optimizer");
            app.add_option("--out", a->out, "FILE.png (frames side by side) or FILE.gif (animation)")->required();
            auto* frames = app.add_option("--frames", a->frames, "time points from the start to the end (default 5)");
            app.add_option("--width", a->width, "pixels per frame (default 320)");
            app.add_flag("--force", a->force, "write over an existing file (never over a database)");
            app.add_flag("--target", a->target,
                         "draw the env's target shape alone, no rollout (plb-*: the target grid's cells above 1% "
                         "of its maximum and PlasticineLab's bounding boxes)");
            return [a, frames] {
              a->frames_given = frames->count() > 0;
              return command_render(*a);
            };
          }};
}

}  // namespace dsb
