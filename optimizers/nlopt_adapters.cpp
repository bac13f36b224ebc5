// NLopt adapters: restarts, budget accounting, failed-episode penalty. See nlopt_adapters.hpp for
// the behaviour; NLopt's documented behaviour is what it relies on.
#include "optimizers/nlopt_adapters.hpp"

#include <algorithm>
#include <climits>
#include <cmath>
#include <exception>
#include <span>
#include <stdexcept>

#include <nlopt.hpp>

#include "common/config_fields.hpp"
#include "common/error.hpp"
#include "common/field_check.hpp"
#include "common/number_text.hpp"
#include "optimizers/core/diagnostics.hpp"

namespace dsb {

namespace {

constexpr double kNoFinitePenalty = 1e10;     // penalty while no finite loss has been seen
constexpr double kMaxPenalty = 1e300;         // the penalty never grows beyond this
constexpr int kMaxIdleStarts = 3;             // starts in a row without an episode -> return
constexpr double kSubBoxMinHalfWidth = 0.25;  // DIRECT-L restart sub-box half-width in [0.25, 1)

struct AlgoInfo {
  const char* algorithm;
  const char* name;
  nlopt::algorithm id;
  bool gradient;
  bool global;
  bool random;  // draws from NLopt's own generator (seeded from the run's Rng before each start)
};

constexpr AlgoInfo kAlgos[] = {
    {"LD_LBFGS", "nlopt-lbfgs", nlopt::LD_LBFGS, true, false, false},
    {"LN_BOBYQA", "nlopt-bobyqa", nlopt::LN_BOBYQA, false, false, false},
    {"GN_DIRECT_L", "nlopt-direct-l", nlopt::GN_DIRECT_L, false, true, false},
    {"GN_CRS2_LM", "nlopt-crs2", nlopt::GN_CRS2_LM, false, true, true},
};

const AlgoInfo* find_algo(const std::string& algorithm) {
  for (const auto& a : kAlgos)
    if (algorithm == a.algorithm) return &a;
  return nullptr;
}

const AlgoInfo& algo_or_throw(const std::string& algorithm) {
  const AlgoInfo* a = find_algo(algorithm);
  if (!a)
    throw ConfigError("nlopt", "algorithm",
                      "must be one of LD_LBFGS, LN_BOBYQA, GN_DIRECT_L, GN_CRS2_LM (got '" + algorithm + "')");
  return *a;
}

// State shared with the NLopt callback for one minimize() call.
struct CallbackState {
  Objective* f = nullptr;
  std::vector<double> x;     // the clamped point handed to the Objective
  std::exception_ptr error;  // what the Objective threw (BudgetExhausted or anything else)
  bool stopping = false;     // this start was stopped: evaluate nothing more
  double worst = 0.0;        // worst finite loss seen in this run
  bool have_finite = false;

  double penalty() const {
    if (!have_finite) return kNoFinitePenalty;
    return std::min(worst + std::max(1.0, std::abs(worst)), kMaxPenalty);
  }
};

// nlopt::func: grad is null unless the algorithm asks for the gradient at this point.
double objective_callback(unsigned n, const double* x, double* grad, void* data) {
  auto& s = *static_cast<CallbackState*>(data);
  // Some algorithms (CRS2 while it builds its population, L-BFGS) call again after a forced stop
  // before they notice it: no more episodes once this start was stopped.
  if (s.stopping) throw nlopt::forced_stop();
  for (unsigned i = 0; i < n; ++i) {
    if (std::isnan(x[i])) {  // broken iterate: end this start
      s.stopping = true;
      throw nlopt::forced_stop();
    }
    s.x[i] = std::clamp(x[i], -1.0, 1.0);
  }
  double v;
  try {
    if (grad)
      v = s.f->value_and_grad(s.x, std::span<double>(grad, n));
    else
      v = s.f->value(s.x);
  } catch (...) {
    // NLopt would turn this into std::runtime_error; keep it and rethrow after optimize
    s.error = std::current_exception();
    s.stopping = true;
    throw nlopt::forced_stop();
  }
  if (!std::isfinite(v)) {
    if (grad) std::fill(grad, grad + n, 0.0);
    return s.penalty();
  }
  if (!s.have_finite || v > s.worst) s.worst = v;
  s.have_finite = true;
  if (grad)
    for (unsigned i = 0; i < n; ++i)
      if (!std::isfinite(grad[i])) grad[i] = 0.0;
  return v;
}

}  // namespace

// ---------------------------------------------------------------------------------------------
// config

std::string nlopt_optimizer_name(const std::string& algorithm) { return algo_or_throw(algorithm).name; }

void NloptConfig::validate() const {
  const AlgoInfo& a = algo_or_throw(algorithm);
  const FieldCheck check(a.name);
  check.number_at_least("ftol_rel", ftol_rel, 0.0);
  check.number_at_least("xtol_rel", xtol_rel, 0.0);
  check.require(initial_step >= 0.0 && initial_step <= 1.0, "initial_step",
                "must be in [0, 1] (0 = NLopt default; got " + number_text(initial_step) + ")");
  check.require(initial_step == 0.0 || a.id == nlopt::LN_BOBYQA, "initial_step",
                "is used only by LN_BOBYQA and must be 0 here (got " + number_text(initial_step) + ")");
  check.require(population >= 0, "population",
                "must be 0 (NLopt default 10 (n + 1)) or >= n + 1 (got " + std::to_string(population) + ")");
  check.require(population == 0 || a.id == nlopt::GN_CRS2_LM, "population",
                "is used only by GN_CRS2_LM and must be 0 here (got " + std::to_string(population) + ")");
}

nlohmann::json NloptConfig::to_json() const { return fields_json(*this); }

namespace {

// the defaults of the registered adapter of `algorithm`: NloptConfig's, and BOBYQA's initial step
NloptConfig adapter_defaults(const char* algorithm) {
  NloptConfig c;
  c.algorithm = algorithm;
  if (c.algorithm == "LN_BOBYQA") c.initial_step = 0.25;  // chosen here: an eighth of the box width
  return c;
}

}  // namespace

NloptConfig nlopt_lbfgs_defaults() { return adapter_defaults("LD_LBFGS"); }
NloptConfig nlopt_bobyqa_defaults() { return adapter_defaults("LN_BOBYQA"); }
NloptConfig nlopt_direct_l_defaults() { return adapter_defaults("GN_DIRECT_L"); }
NloptConfig nlopt_crs2_defaults() { return adapter_defaults("GN_CRS2_LM"); }

// ---------------------------------------------------------------------------------------------
// optimizer

// a bad algorithm: ConfigError from algo_or_throw, as validate() would throw it
NloptOptimizer::NloptOptimizer(const NloptConfig& cfg)
    : ConfiguredOptimizer(algo_or_throw(cfg.algorithm).name, algo_or_throw(cfg.algorithm).gradient, cfg) {}

void NloptOptimizer::minimize(Objective& f, Rng& rng) {
  stats_ = {};
  const AlgoInfo& algo = algo_or_throw(cfg_.algorithm);
  const int n = f.dim();
  if (n < 1) throw std::invalid_argument(name_ + ": dimension must be >= 1");
  if (algo.gradient && !f.has_gradient()) throw std::invalid_argument(name_ + " needs an objective with a gradient");
  if (algo.id == nlopt::GN_CRS2_LM && cfg_.population != 0 && cfg_.population < n + 1)
    throw ConfigError(
        name_, "population",
        "must be 0 or >= n + 1 = " + std::to_string(n + 1) + " (got " + std::to_string(cfg_.population) + ")");

  CallbackState cb;
  cb.f = &f;
  cb.x.assign(n, 0.0);
  int idle = 0;

  for (int start = 0;; ++start) {
    if (f.remaining() <= 0) throw BudgetExhausted{};  // as the Objective would on the next ask
    if (start > 0 && !cfg_.restart_from_random) {
      stats_.early_return = "restart_from_random is false: the single start ended";
      return;
    }

    NloptStart s;
    s.lower.assign(n, -1.0);
    s.upper.assign(n, 1.0);
    s.x0.assign(n, 0.0);  // start 0: box centre
    if (start > 0) {
      if (algo.id == nlopt::GN_DIRECT_L) {
        // random sub-box inside [-1, 1]^n (DIRECT-L would repeat itself on the same box)
        const double w = rng.uniform(kSubBoxMinHalfWidth, 1.0);
        for (int i = 0; i < n; ++i) {
          const double c = rng.uniform(-1.0 + w, 1.0 - w);
          s.lower[i] = std::max(-1.0, c - w);
          s.upper[i] = std::min(1.0, c + w);
          s.x0[i] = c;
        }
      } else {
        for (auto& xi : s.x0) xi = rng.uniform(-1.0, 1.0);
      }
    }

    nlopt::opt opt(algo.id, static_cast<unsigned>(n));
    opt.set_lower_bounds(s.lower);
    opt.set_upper_bounds(s.upper);
    opt.set_min_objective(objective_callback, &cb);
    opt.set_ftol_rel(cfg_.ftol_rel);
    opt.set_xtol_rel(cfg_.xtol_rel);
    opt.set_maxeval(static_cast<int>(std::min<std::int64_t>(f.remaining(), INT_MAX)));
    if (algo.id == nlopt::LN_BOBYQA && cfg_.initial_step > 0.0) opt.set_initial_step(cfg_.initial_step);
    if (algo.id == nlopt::GN_CRS2_LM && cfg_.population > 0) opt.set_population(static_cast<unsigned>(cfg_.population));
    // thread-local generator, stream continues across calls: re-seed before every optimize. An
    // algorithm that never draws from it does not use the seed, so that draw is not counted as a
    // use of the run's seed (the stream advances the same: the same bits either way), and its
    // episodes up to its first random restart are shared across seeds (harness/run/budget.hpp)
    const std::uint64_t nlopt_seed = algo.random ? rng.next_u64() : rng.skip_u64();
    nlopt::srand(static_cast<unsigned long>(nlopt_seed));

    std::vector<double> x = s.x0;
    double fx = 0.0;
    const std::int64_t used0 = f.used();
    cb.error = nullptr;
    cb.stopping = false;
    std::exception_ptr nlopt_error;
    int code;
    try {
      code = static_cast<int>(opt.optimize(x, fx));
    } catch (...) {
      nlopt_error = std::current_exception();
      code = static_cast<int>(opt.last_optimize_result());
    }
    s.episodes = f.used() - used0;
    s.result = code;
    stats_.starts.push_back(std::move(s));

    if (cb.error) std::rethrow_exception(cb.error);  // BudgetExhausted or an Objective failure
    if (nlopt_error) {
      try {
        std::rethrow_exception(nlopt_error);
      } catch (const std::runtime_error&) {
        // roundoff_limited, forced_stop (a broken iterate), FAILURE: a normal end of this start.
        // std::invalid_argument and std::bad_alloc are not runtime_errors and propagate.
      }
    }

    if (stats_.starts.back().episodes == 0) {
      if (++idle >= kMaxIdleStarts) {
        stats_.early_return = std::to_string(kMaxIdleStarts) + " starts in a row ended without an episode";
        return;
      }
    } else {
      idle = 0;
    }
  }
}

std::string nlopt_result_name(int code) {
  switch (code) {
    case NLOPT_FAILURE: return "NLOPT_FAILURE";
    case NLOPT_INVALID_ARGS: return "NLOPT_INVALID_ARGS";
    case NLOPT_OUT_OF_MEMORY: return "NLOPT_OUT_OF_MEMORY";
    case NLOPT_ROUNDOFF_LIMITED: return "NLOPT_ROUNDOFF_LIMITED";
    case NLOPT_FORCED_STOP: return "NLOPT_FORCED_STOP";
    case NLOPT_SUCCESS: return "NLOPT_SUCCESS";
    case NLOPT_STOPVAL_REACHED: return "NLOPT_STOPVAL_REACHED";
    case NLOPT_FTOL_REACHED: return "NLOPT_FTOL_REACHED";
    case NLOPT_XTOL_REACHED: return "NLOPT_XTOL_REACHED";
    case NLOPT_MAXEVAL_REACHED: return "NLOPT_MAXEVAL_REACHED";
    case NLOPT_MAXTIME_REACHED: return "NLOPT_MAXTIME_REACHED";
  }
  return "NLOPT_UNKNOWN_" + std::to_string(code);
}

nlohmann::json NloptOptimizer::diagnostics() const {
  nlohmann::json results = nlohmann::json::object();
  for (const auto& s : stats_.starts) {
    const std::string name = nlopt_result_name(s.result);
    results[name] = results.value(name, 0) + 1;
  }
  nlohmann::json d = {
      {"starts", stats_.starts.size()},
      {"results", std::move(results)},
      {"early_return", stats_.early_return.empty() ? nlohmann::json(nullptr) : nlohmann::json(stats_.early_return)}};
  put_capped(d, "start_list", stats_.starts, [](const NloptStart& s, std::size_t) {
    return nlohmann::json{{"result", nlopt_result_name(s.result)}, {"episodes", s.episodes}};
  });
  return d;
}

std::unique_ptr<Optimizer> make_nlopt(const NloptConfig& cfg) { return std::make_unique<NloptOptimizer>(cfg); }
std::unique_ptr<Optimizer> make_nlopt_lbfgs() { return make_nlopt(nlopt_lbfgs_defaults()); }
std::unique_ptr<Optimizer> make_nlopt_bobyqa() { return make_nlopt(nlopt_bobyqa_defaults()); }
std::unique_ptr<Optimizer> make_nlopt_direct_l() { return make_nlopt(nlopt_direct_l_defaults()); }
std::unique_ptr<Optimizer> make_nlopt_crs2() { return make_nlopt(nlopt_crs2_defaults()); }

}  // namespace dsb
