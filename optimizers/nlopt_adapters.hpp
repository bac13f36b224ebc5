#pragma once
// NLopt 2.7.1 adapters (its documented behaviour):
//   `nlopt-lbfgs`    LD_LBFGS (Luksan's limited-memory BFGS, needs the gradient)
//   `nlopt-bobyqa`   LN_BOBYQA (Powell's bound-constrained quadratic models, derivative-free)
//   `nlopt-direct-l` GN_DIRECT_L (locally biased DIRECT, deterministic, derivative-free)
//   `nlopt-crs2`     GN_CRS2_LM (controlled random search with local mutation, derivative-free)
//
// All run on the normalized box [-1, 1]^n and spend the whole budget as a sequence of "starts"
// (one nlopt::opt::optimize call each):
//   - start 0: the whole box, x0 = box centre (for DIRECT-L x0 is not used; for CRS2 it is the
//     first member of the initial population);
//   - every later start, while budget remains (only with restart_from_random):
//       lbfgs, bobyqa, crs2: the whole box, x0 uniform in [-1, 1]^n (dsb::Rng); CRS2 also draws a
//         new random population (NLopt's own generator, seeded as below);
//       direct-l: DIRECT-L is deterministic, so a restart on the same box would repeat the same
//         points. It runs instead on a random axis-aligned sub-box: half-width w ~ U[0.25, 1)
//         (the same for every axis), centre c_i ~ U[-1 + w, 1 - w), so the sub-box lies inside the
//         box and its DIRECT grid differs from all earlier ones. The sub-box is not tied to the
//         best point: a DIRECT-L start only ends early after its best value stopped improving
//         (ftol) or its rectangles became tiny (xtol), so refining there is pointless and the
//         restart explores instead.
//   - before each optimize: nlopt::srand(seed) with seed = rng.next_u64() (NLopt's generator is
//     thread-local and its stream continues across calls, so it is re-seeded every time), maxeval
//     = f.remaining() (no margin), ftol_rel, xtol_rel, the initial step (bobyqa) and the
//     population (crs2) from the config.
// The run therefore ends when the budget is spent: with maxeval = remaining, NLopt stops exactly
// at the last allowed episode, and minimize then throws dsb::BudgetExhausted itself (just as the
// Objective would on the next ask). If NLopt asks for more anyway, the Objective throws inside
// the callback (seen with NLopt 2.7.1: GN_DIRECT_L with maxeval 1 and GN_CRS2_LM ask once more
// after maxeval); the adapter stores that exception, stops NLopt (nlopt::forced_stop), evaluates
// nothing more in that start (NLopt may call again before it notices the stop) and rethrows it
// after optimize. Any other exception from the Objective is carried out the same way (NLopt
// would otherwise turn it into a std::runtime_error).
//
// Early returns (minimize returns normally before the budget is spent; last_run().early_return
// says why):
//   - restart_from_random == false: after the first start ends by itself;
//   - three starts in a row that ended without a single episode (NLopt returning immediately,
//     e.g. a broken point): nothing is making progress, so the run stops instead of looping.
//
// Start endings that are normal (the next start follows): any positive nlopt::result,
// nlopt::roundoff_limited, nlopt::forced_stop not caused by the Objective, std::runtime_error
// (NLopt FAILURE). std::invalid_argument and std::bad_alloc from NLopt propagate (a bad setup is
// not an optimization outcome).
//
// Failed episodes (+infinity or NaN loss) are given to NLopt as a finite penalty:
//   penalty = min(w + max(1, |w|), 1e300), w = the worst finite loss seen so far in this run,
//   or 1e10 while no finite loss has been seen.
// So a failed point always looks worse than every finite point seen before it, without values
// like 1e300 or inf that overflow the line search of L-BFGS and the quadratic models of BOBYQA.
// The gradient of a failed episode is zero (as the Objective returns it); the penalty is larger
// than the current iterate's value, so L-BFGS's line search rejects the step and backtracks.
// Non-finite gradient components of a finite episode are set to 0.
//
// Points: NLopt keeps iterates inside the bounds, but every point is clamped to [-1, 1] anyway
// before it reaches the Objective. A point with a NaN coordinate ends the start (forced stop)
// without an episode.
//
// Same bits on every CPU: libnlopt imports exp, log, pow, sincos and tan from glibc's libm (whose
// variants depend on the CPU's FMA/AVX2), but only ISRES, ESCH, MLSL, ORIG_DIRECT and, in some
// trust-region paths, COBYLA and NEWUOA call them; the four algorithms here (and LD_LBFGS inside
// bo) make no such call (counted with an LD_PRELOAD shim over a grid of every env). Check any
// algorithm added here the same way (docs/determinism.md "Determinism").
//
// Gradients: the callback calls Objective::value_and_grad only when NLopt passes a gradient
// buffer (LD_LBFGS), otherwise Objective::value; the derivative-free adapters never ask for one.
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "common/config_fields.hpp"
#include "common/rng.hpp"
#include "optimizers/core/configured_optimizer.hpp"
#include "optimizers/core/optimizer.hpp"

namespace dsb {

struct NloptConfig {
  std::string algorithm;            // "LD_LBFGS", "LN_BOBYQA", "GN_DIRECT_L", "GN_CRS2_LM"
  double ftol_rel = 1e-10;          // NLopt relative f tolerance per start (0 = off)
  double xtol_rel = 1e-10;          // NLopt relative x tolerance per start (0 = off)
  double initial_step = 0.0;        // LN_BOBYQA only: initial trust radius in the normalized box,
                                    // 0 = NLopt's heuristic; must be <= 1 (half the box width)
  int population = 0;               // GN_CRS2_LM only: 0 = NLopt default 10 (n + 1); else >= n + 1
  bool restart_from_random = true;  // restart while budget remains (see above); false = one start
  // throws ConfigError naming the field
  void validate() const;
  nlohmann::json to_json() const;
  // the stored fields, each named once (common/config_fields.hpp)
  DSB_CONFIG_FIELDS(algorithm, ftol_rel, xtol_rel, initial_step, population, restart_from_random)
};

// The defaults of the four registered adapters (chosen here): tolerances 1e-10, BOBYQA initial
// step 0.25, CRS2 population NLopt's default, restarts on.
NloptConfig nlopt_lbfgs_defaults();
NloptConfig nlopt_bobyqa_defaults();
NloptConfig nlopt_direct_l_defaults();
NloptConfig nlopt_crs2_defaults();

// Optimizer name of an algorithm ("LD_LBFGS" -> "nlopt-lbfgs" ...); throws ConfigError otherwise.
std::string nlopt_optimizer_name(const std::string& algorithm);

// One optimize call.
struct NloptStart {
  std::int64_t episodes = 0;         // episodes this start used
  int result = 0;                    // nlopt_result code it ended with (5 = MAXEVAL_REACHED, -4 =
                                     // ROUNDOFF_LIMITED, -5 = FORCED_STOP, -1 = FAILURE)
  std::vector<double> lower, upper;  // the bounds it ran in
  std::vector<double> x0;            // its start point
};

// NLopt's name of an nlopt_result code ("NLOPT_MAXEVAL_REACHED", "NLOPT_FORCED_STOP" ...);
// "NLOPT_UNKNOWN_<code>" for a code NLopt 2.7 does not define.
std::string nlopt_result_name(int code);

// What the last minimize() did (kept when it ends by an exception).
struct NloptRunStats {
  std::vector<NloptStart> starts;
  std::string early_return;  // empty unless minimize returned before the budget was spent
};

class NloptOptimizer : public ConfiguredOptimizer<NloptConfig> {
 public:
  explicit NloptOptimizer(const NloptConfig& cfg);
  // Throws std::invalid_argument when the gradient is needed and f has none, ConfigError when the
  // CRS2 population is below n + 1; otherwise runs until the budget is spent (BudgetExhausted)
  // or one of the early returns above.
  void minimize(Objective& f, Rng& rng) override;
  const NloptRunStats& last_run() const { return stats_; }
  // {"starts", "results": {name: count} (over all starts), "early_return" (or null),
  // "start_list": [{"result" (e.g. "NLOPT_MAXEVAL_REACHED"), "episodes"}] (capped),
  // "start_list_truncated"}
  nlohmann::json diagnostics() const override;

 private:
  NloptRunStats stats_;
};

std::unique_ptr<Optimizer> make_nlopt(const NloptConfig& cfg);
std::unique_ptr<Optimizer> make_nlopt_lbfgs();
std::unique_ptr<Optimizer> make_nlopt_bobyqa();
std::unique_ptr<Optimizer> make_nlopt_direct_l();
std::unique_ptr<Optimizer> make_nlopt_crs2();

}  // namespace dsb
