#include "harness/plan/cost_model.hpp"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <memory>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "common/error.hpp"
#include "common/parallel.hpp"
#include "common/regular_file.hpp"
#include "git_sha.hpp"  // generated at build time: DSB_GIT_SHA

namespace dsb {
namespace {

std::string default_cache_path() {
  if (const char* p = std::getenv("DSB_COST_CACHE"); p && *p) return p;
  if (const char* x = std::getenv("XDG_CACHE_HOME"); x && *x)
    return std::string(x) + "/diffsim-bench/episode-costs.json";
  if (const char* h = std::getenv("HOME"); h && *h) return std::string(h) + "/.cache/diffsim-bench/episode-costs.json";
  return ".diffsim-bench-episode-costs.json";
}

// the build a calibration belongs to: the version and the commit (with "-dirty" when the tree
// differed from it), so that a binary never plans with what an older one measured
std::string harness_build() { return std::string(DSB_VERSION) + "+" + DSB_GIT_SHA; }

// the median of a non-empty sample (the upper one of an even count)
double median_of(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v[v.size() / 2];
}

// the median of repeated timings of f, repeated until `min_total_s` has passed (at least once,
// at most 25 times)
template <class F>
double median_seconds(F&& f, double min_total_s) {
  std::vector<double> times;
  double total = 0.0;
  while (times.empty() || (total < min_total_s && times.size() < 25)) {
    const auto start = std::chrono::steady_clock::now();
    f();
    const double t = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    times.push_back(t);
    total += t;
  }
  return median_of(std::move(times));
}

}  // namespace

std::string cpu_model_name() {
  std::ifstream in("/proc/cpuinfo");
  for (std::string line; std::getline(in, line);) {
    if (line.rfind("model name", 0) == 0) {
      const auto colon = line.find(':');
      if (colon != std::string::npos) {
        std::string name = line.substr(colon + 1);
        name.erase(0, name.find_first_not_of(' '));
        return name;
      }
    }
  }
  return "unknown";
}

std::string human_duration(double s) {
  if (s < 10.0) return fmt::format("{:.2g} s", s);
  if (s < 90.0) return fmt::format("{:.0f} s", s);
  if (s < 5400.0) return fmt::format("{:.0f} min", s / 60.0);
  if (s < 2.0 * 86400.0) return fmt::format("{:.1f} h", s / 3600.0);
  return fmt::format("{:.1f} days", s / 86400.0);
}

CostModel::CostModel() : path_(default_cache_path()), build_(harness_build()), cpu_(cpu_model_name()) {
  std::string text;
  try {
    text = read_regular_file("", path_);  // never blocks on a FIFO put in its place
  } catch (const UsageError&) {
    return;  // missing or unreadable: no measurements
  }
  try {
    const auto j = nlohmann::json::parse(text);
    for (const auto& [k, v] : j.at("costs").items()) {
      table_[k] = {v.at("forward_s").get<double>(), v.at("gradient_s").get<double>(), v.at("decisions").get<int>(),
                   true};
      // env|env config hash|build|CPU model: another build's measurement on this CPU
      const auto a = k.find('|'), b = a == std::string::npos ? a : k.find('|', a + 1),
                 c = b == std::string::npos ? b : k.find('|', b + 1);
      if (c != std::string::npos && k.compare(b + 1, c - b - 1, build_) != 0 &&
          k.compare(c + 1, std::string::npos, cpu_) == 0)
        other_builds_.insert(k.substr(0, b));
    }
    if (j.contains("runs"))
      for (const auto& [k, v] : j.at("runs").items())
        probes_[k] = {v.at("episodes").get<std::int64_t>(), v.at("seconds").get<double>(),
                      v.value("replay_s_per_episode", 0.0)};
  } catch (const std::exception&) {
    table_.clear();  // an unreadable cache is an empty one; `calibrate` rewrites it
    probes_.clear();
    other_builds_.clear();
  }
}

std::string CostModel::key(const std::string& env_name, const std::string& env_config_hash) const {
  return env_name + "|" + env_config_hash + "|" + build_ + "|" + cpu_;
}

bool CostModel::measured_by_other_build(const std::string& env_name, const std::string& env_config_hash) const {
  return other_builds_.count(env_name + "|" + env_config_hash) > 0;
}

std::string CostModel::run_key(const PlannedRun& run) const {
  return run.spec.env + "|" + run.key.env_config_hash + "|" + run.spec.optimizer + "|" + run.key.opt_config_hash + "|" +
      std::to_string(probe_episodes(run)) + "|" + build_ + "|" + cpu_;
}

std::int64_t CostModel::probe_episodes(const PlannedRun& run) const {
  const OptimizerEntry& opt = *run.spec.entry;
  if (opt.needs_rl) {
    const std::int64_t decisions = std::max(1, episode(run.spec).decisions);
    return std::min<std::int64_t>(run.spec.budget, (kProbeRlDecisions + decisions - 1) / decisions);
  }
  const bool modelled = static_cast<bool>(opt.costs.own_seconds);
  return std::min<std::int64_t>(run.spec.budget, modelled ? kProbeEpisodesModelled : kProbeEpisodesMax);
}

bool CostModel::probes(const PlannedRun& run) const {
  if (run.spec.ext) return false;
  const EpisodeCost c = episode(run.spec);
  // an RL learner needs the env's measured decisions per episode to size its probe
  if (run.spec.entry->needs_rl && c.decisions <= 0) return false;
  return c.measured && std::max(c.forward_s, c.gradient_s) <= kProbeMaxEpisodeSeconds;
}

std::optional<RunProbe> CostModel::probed(const PlannedRun& run) const {
  if (const auto it = probes_.find(run_key(run)); it != probes_.end() && it->second.episodes > 0) return it->second;
  return std::nullopt;
}

bool probe_timed_enough(int timings, double total_s) {
  if (timings <= 0) return false;
  if (timings >= kProbeRepeatsMax || total_s >= kProbeOnceSeconds) return true;
  return total_s >= kProbeRepeatSeconds && timings >= kProbeRepeatsMin;
}

void CostModel::calibrate_runs(const std::vector<PlannedRun>& runs, const ProbeTimer& time_once,
                               const std::function<void(const PlannedRun&)>& starting,
                               const std::function<void()>& after_round) {
  struct Pending {
    const PlannedRun* run;
    RunSpec spec;
    std::shared_ptr<const Env> env;
    std::vector<double> run_s, replay_s;
    std::int64_t episodes = 1;
    double total = 0.0;
    bool done() const { return probe_timed_enough(static_cast<int>(run_s.size()), total); }
  };
  std::vector<Pending> pending;
  for (const PlannedRun& run : runs) {
    RunSpec spec = run.spec;
    spec.budget = probe_episodes(run);
    pending.push_back({&run, spec, spec.resolved_env, {}, {}});
  }
  // a round times each pair not yet done once, in the order given (the grid's): a pair of a
  // second of runs is done after its first round, one of 0.1 ms after nine
  for (bool any = true; any;) {
    any = false;
    for (Pending& p : pending) {
      if (p.done()) continue;
      if (p.run_s.empty() && starting) starting(*p.run);
      const ProbeTiming t = time_once(p.spec, *p.env);
      p.episodes = t.episodes;
      p.run_s.push_back(t.run_s);
      p.replay_s.push_back(t.replay_s_per_episode);
      p.total += t.total_s;
      probes_[run_key(*p.run)] = {p.episodes, median_of(p.run_s), median_of(p.replay_s)};
      any = true;
    }
    if (any && after_round) after_round();
  }
}

EpisodeCost CostModel::episode(const RunSpec& spec) const {
  if (const auto it = table_.find(key(spec.env, spec.env_config->hash)); it != table_.end()) return it->second;
  const EnvInfo& info = spec.resolved_env->info();  // metadata: no model is built
  return {info.cost_hint_forward_s > 0.0 ? info.cost_hint_forward_s : info.cost_hint_s, info.cost_hint_s, 0, false};
}

double CostModel::run_seconds(const PlannedRun& run, double shared_share) const {
  const EpisodeCost c = episode(run.spec);
  if (run.spec.ext) {
    // an external optimizer: whether it asks for gradients is its own affair; counted at the
    // gradient episode's cost (the upper bound), its own time unknown
    return c.gradient_s * static_cast<double>(run.spec.budget);
  }
  const OptimizerEntry& opt = *run.spec.entry;
  const double g = opt.costs.gradient_share;
  double per_episode = opt.needs_gradient ? g * c.gradient_s + (1.0 - g) * c.forward_s : c.forward_s;
  if (opt.needs_rl) {
    // the hint alone knows no decision count: one per 5 env steps of a 50-step episode
    const int decisions = c.decisions > 0 ? c.decisions : 10;
    per_episode += decisions * opt.costs.learner_s_per_decision;
  }
  const int dim = run.spec.resolved_env->info().dim;  // metadata
  const auto own = [&](std::int64_t budget) {
    return opt.costs.own_seconds ? opt.costs.own_seconds(dim, budget) : 0.0;
  };
  const double budget = static_cast<double>(run.spec.budget);
  if (const auto p = probed(run)) {
    // measured: an optimizer with a modelled own time costs what the short run spent beyond its
    // episodes plus the model's growth from the probe's episodes to the budget (added, not scaled:
    // the probe's own time is mostly work the model does not grow, and scaling it by the model's
    // ratio put boleap's 1,000 episodes on rastrigin-10 at 13x what they took); any other costs
    // its measured seconds per episode
    const double probe_own = own(p->episodes);
    const double replayed = p->replay_s_per_episode * budget * shared_share;
    if (probe_own > 0.0) {
      const double measured_own = std::max(0.0, p->seconds - per_episode * static_cast<double>(p->episodes));
      return per_episode * budget * (1.0 - shared_share) + replayed + measured_own +
          std::max(0.0, own(run.spec.budget) - probe_own);
    }
    return p->seconds / static_cast<double>(p->episodes) * budget * (1.0 - shared_share) + replayed;
  }
  return per_episode * budget * (1.0 - shared_share) + own(run.spec.budget);
}

EpisodeCost CostModel::calibrate(const RunSpec& spec, std::size_t tape_memory_bytes) {
  const auto& env = spec.resolved_env;
  const auto ws = env->make_workspace();
  ws->tape_memory_bytes = tape_memory_bytes;
  const std::vector<double> x(static_cast<std::size_t>(env->dim()), 0.0);
  std::vector<double> grad(x.size());
  EpisodeCost c;
  c.measured = true;
  env->loss(x, *ws, serial_team());  // builds the model and warms the workspace, untimed
  c.forward_s = median_seconds([&] { env->loss(x, *ws, serial_team()); }, 0.2);
  if (env->differentiable()) env->loss_and_grad(x, grad, *ws, serial_team());  // sizes the tapes, untimed
  c.gradient_s = env->differentiable() ? median_seconds([&] { env->loss_and_grad(x, grad, *ws, serial_team()); }, 0.2)
                                       : c.forward_s;
  if (env->supports_rl()) {
    const auto rl = env->make_rl();
    c.decisions = (rl->horizon() + rl->action_repeat() - 1) / rl->action_repeat();
  }
  table_[key(spec.env, spec.env_config->hash)] = c;
  return c;
}

void CostModel::save() const {
  nlohmann::json costs = nlohmann::json::object();
  for (const auto& [k, c] : table_)
    costs[k] = {{"forward_s", c.forward_s}, {"gradient_s", c.gradient_s}, {"decisions", c.decisions}};
  nlohmann::json runs = nlohmann::json::object();
  for (const auto& [k, v] : probes_)
    runs[k] = {{"episodes", v.episodes}, {"seconds", v.seconds}, {"replay_s_per_episode", v.replay_s_per_episode}};
  const nlohmann::json j = {{"what",
                             "diffsim-bench seconds per episode, one core: costs by env|env config hash|harness "
                             "build (version+commit)|CPU model; runs (short runs of cheap pairs, the "
                             "optimizer's own work included) by env|env config hash|optimizer|optimizer "
                             "config hash|episodes|harness build|CPU model"},
                            {"costs", costs},
                            {"runs", runs}};
  std::error_code ec;
  const auto dir = std::filesystem::path(path_).parent_path();
  if (!dir.empty()) std::filesystem::create_directories(dir, ec);
  const std::string tmp = path_ + ".tmp";
  {
    std::ofstream out(tmp);
    out << j.dump(2) << "\n";
    if (!out) throw UsageError("cannot write the cost cache '" + tmp + "'");
  }
  std::filesystem::rename(tmp, path_, ec);
  if (ec) throw UsageError("cannot write the cost cache '" + path_ + "': " + ec.message());
}

}  // namespace dsb
