#pragma once
// The grid of runs: env x optimizer x seed at one budget, in a canonical order (envs, then
// optimizers, in the order given; seeds ascending). Shards (harness/plan/plan.hpp) are cut from the
// run keys, not from this order.
#include <map>
#include <string>
#include <vector>

#include "envs/core/env_options.hpp"
#include "harness/core/run_spec.hpp"
#include "optimizers/core/knobs.hpp"
#include "optimizers/core/optimizer.hpp"
#include "optimizers/ext/ext_optimizer.hpp"

namespace dsb {

struct GridRequest {
  bool all = false;
  std::vector<std::string> envs;        // explicit names (empty with all = every grid env)
  std::vector<std::string> optimizers;  // explicit names (empty with all = every optimizer)
  int seeds = 1;
  std::int64_t budget = 1000;
  // --set OWNER.KEY=VALUE: owner -> key -> value, an env of the grid (its options) or an optimizer
  // (its knobs)
  std::map<std::string, KnobSettings> knobs;
  std::map<std::string, std::string> ext;      // NAME -> COMMAND of ext:NAME (--ext NAME=COMMAND)
  double ext_timeout_s = kExtDefaultTimeoutS;  // per reply of an external optimizer (--ext-timeout)
};

// "OPT.KNOB=0.3" into knobs["OPT"]["KNOB"] = "0.3" (an env's option the same way:
// "plb-pinch.target=F.npy"); UsageError naming a malformed one or a key given twice
void parse_knob_setting(const std::string& text, std::map<std::string, KnobSettings>& knobs);

// The options of one env from --set settings of a command that runs that env alone (`harness
// eval`): each must be ENV.KEY=VALUE for this env; UsageError naming one that is not.
EnvOptions parse_env_settings(const std::string& env, const std::vector<std::string>& settings);

// --set settings as a program in another working directory must read them (`harness slurm`'s
// array tasks): an env option that names a file made absolute, everything else as given.
std::vector<std::string> settings_with_absolute_paths(const std::vector<std::string>& settings);

// "my-opt=python3 opt.py" into ext["my-opt"] = "python3 opt.py"; UsageError naming a malformed one
void parse_ext_setting(const std::string& text, std::map<std::string, std::string>& ext);

// the largest --budget and --seeds a grid accepts (a run keeps its evals in memory: 48 bytes each)
inline constexpr std::int64_t kMaxBudget = 1'000'000;
inline constexpr int kMaxSeeds = 10'000;

// Validates names and applicability (UsageError naming the bad value) and expands the grid.
// A --set setting of an env of the grid is an option of that env (checked by making the env once:
// an unknown key, or a bad value such as an unreadable target file, is a UsageError); the others
// must name an optimizer of the grid and are checked by building it once.
// An external optimizer (ext:NAME) needs its --ext NAME=COMMAND and is probed once here (its name
// and version enter its config, so the run key); it pairs with every env.
// Pairs that are inapplicable (gradient optimizer on a non-differentiable env) are skipped when
// they come from --all and refused when both were named explicitly.
std::vector<RunSpec> expand_grid(const GridRequest& request);

}  // namespace dsb
