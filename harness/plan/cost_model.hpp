#pragma once
// What a run costs, before it runs: seconds per episode of each env on this machine, by kind of
// episode (forward, gradient, RL with the learner's own time), for `harness plan`, the order of a
// grid (cheap runs first) and the progress line's ETA.
//
// Costs come from `harness calibrate`, which times episodes of each env at the centre of its box
// and caches them per machine (the CPU's model name), harness version and env config hash in
// $DSB_COST_CACHE, else $XDG_CACHE_HOME/diffsim-bench/episode-costs.json, else
// ~/.cache/diffsim-bench/episode-costs.json. Envs not measured yet fall back to their cost hint
// (seconds of a gradient episode on the machine the hint was written on), and the plan says so.
// Reading the cache never builds an env model.
//
// An optimizer's own work (its updates, NLopt's models, a GP's fits, the budget wrapper's
// records) is invisible beside a particle task's episode but most of a cheap env's run: CMA-ES in
// 400-D spends 8-13 ms per episode beside a cartpole3 episode of 36 us, and BOBYQA's steps
// in 200-D cost nothing until its 401-point initial model is built, then milliseconds each. So
// `calibrate` also times a run of every (env, optimizer, config) pair of the grid whose episodes
// are cheap (at most kProbeMaxEpisodeSeconds): the whole budget (up to kProbeEpisodesMax) for an
// optimizer without a model of its own time, and kProbeEpisodesModelled episodes for one whose
// registry entry models it (a GP's fits grow with the run: 1,000 episodes of `bo` in 200-D take
// six minutes). The plan counts the first's measured seconds per episode; for the second the
// measured time beyond the episodes plus the model's growth from the probe's episodes to the budget.
// An RL learner's cost comes in updates spread over many decisions (one per 2,048 decisions for
// PPO's rollouts, one per decision for SAC), so it runs kProbeRlDecisions decisions, whole episodes,
// and the plan counts its measured seconds per episode; on an expensive env its registry entry's
// seconds per decision are added to the episodes instead. External optimizers are not run.
#include <cstdint>
#include <functional>
#include <map>
#include <optional>
#include <set>
#include <string>
#include <vector>

#include "envs/core/env.hpp"
#include "harness/core/probe_timing.hpp"
#include "harness/core/run_key.hpp"

namespace dsb {

inline constexpr std::int64_t kProbeEpisodesMax = 1000;
inline constexpr std::int64_t kProbeEpisodesModelled = 200;
inline constexpr double kProbeMaxEpisodeSeconds = 1e-3;
// a probe shorter than this (its runs and replays in all) is repeated, in rounds across the pairs
// (calibrate_runs), the median kept
inline constexpr double kProbeRepeatSeconds = 0.2;
inline constexpr int kProbeRepeatsMax = 9;
// and any probe is timed at least kProbeRepeatsMin times unless its timings reach
// kProbeOnceSeconds: on this 2-core machine one 200-episode run of `bo` on rastrigin-10 timed
// 1.59, 1.90, 2.09 and 2.35 s in four calibrations (the machine otherwise idle), so one timing of a
// GP run is as noisy as the plan check's 30% band; the median of three is not moved by one outlier
// (five calibrations with this rule gave 2.14, 2.03, 2.11, 2.11 and 1.55 s: the machine's fast and
// slow spells can outlast a pair's three timings, and six separate runs of the grid took 1.75-2.25 s).
// A probe of 10 s or more (an RL learner's, CMA-ES in 400-D) is timed once: its repeats would
// cost calibrate minutes.
inline constexpr int kProbeRepeatsMin = 3;
inline constexpr double kProbeOnceSeconds = 10.0;
// whether a pair's probe has been timed enough: `timings` runs (and replays) so far, `total_s`
// their seconds in all
bool probe_timed_enough(int timings, double total_s);
// two of PPO's 2,048-decision rollouts with their updates; 41 episodes of a cartpole
inline constexpr std::int64_t kProbeRlDecisions = 4096;

// a short run's wall seconds over its episodes, and the seconds per episode of replaying it from
// its journal (what a later seed pays for each episode it shares)
struct RunProbe {
  std::int64_t episodes = 0;
  double seconds = 0.0;
  double replay_s_per_episode = 0.0;
};

struct EpisodeCost {
  double forward_s = 0.0;   // one loss() rollout
  double gradient_s = 0.0;  // one loss_and_grad() rollout (= forward_s when not differentiable)
  int decisions = 0;        // RL decisions per episode (0: no RL view)
  bool measured = false;    // false: from the env's cost hint
};

class CostModel {
 public:
  // loads the cache (a missing or unreadable cache is empty)
  CostModel();

  // the cost of one episode of the run's env (its config hash as stored with runs)
  EpisodeCost episode(const RunSpec& spec) const;
  // the estimated seconds of a whole run on one core, `shared_share` of its episodes taken from
  // another seed's run (replayed: at the probe's replay cost for a probed pair, else free)
  double run_seconds(const PlannedRun& run, double shared_share = 0.0) const;

  // times one forward and one gradient episode of the run's env (repeated to at least 0.2 s for
  // cheap envs: the median is kept; the gradient with `tape_memory_bytes` as a run has them) and
  // its RL view's decisions, and records them
  EpisodeCost calibrate(const RunSpec& spec, std::size_t tape_memory_bytes = 0);
  // whether `calibrate_runs` applies to the run: its env's measured episodes are cheap and its
  // optimizer is not external
  bool probes(const PlannedRun& run) const;
  // the short run of the run's (env, optimizer, configs), if one was timed
  std::optional<RunProbe> probed(const PlannedRun& run) const;
  // runs each run's optimizer on its env for probe_episodes(run) episodes with `time_once` (the
  // run's seed, its journal recorded as a grid's run records it, nothing stored: run/probe.hpp's
  // time_probe) and records its wall seconds, then the seconds per episode of replaying it from
  // that journal (0 without a replay when the optimizer drew before its first episode: no later
  // seed shares any of it).
  // The pairs are timed as a grid runs them: in rounds, one run (and its replay) of each pair per
  // round, so that a pair's repeats follow other pairs' runs, not its own (a short run repeated
  // back to back warms its own caches and predictors: on 10-D functions the first of nine repeats
  // took 1.1-2.5x their median; in seven alternating trials of 42 such pairs on 2 jobs, the
  // grid's runs took a median 1.27x a plan from back-to-back probes, 1.16x one from rounds). A
  // pair repeats until probe_timed_enough (while its runs and replays total under
  // kProbeRepeatSeconds, and at least kProbeRepeatsMin times unless they reach kProbeOnceSeconds;
  // at most kProbeRepeatsMax times); the medians are kept. `starting(run)` is told before a pair's first
  // run, `after_round()` after each round (the caller saves there: an interrupted calibration
  // keeps what it measured).
  using ProbeTimer = std::function<ProbeTiming(const RunSpec&, const Env&)>;
  void calibrate_runs(const std::vector<PlannedRun>& runs, const ProbeTimer& time_once,
                      const std::function<void(const PlannedRun&)>& starting, const std::function<void()>& after_round);
  // min(budget, kProbeEpisodesMax), or kProbeEpisodesModelled for an optimizer with a modelled own
  // time, or the episodes that hold kProbeRlDecisions of the env's RL view for an RL learner
  std::int64_t probe_episodes(const PlannedRun& run) const;
  // writes the cache (creating its folder); throws UsageError naming the file when it cannot
  void save() const;

  const std::string& path() const { return path_; }
  // whether the cache holds episode costs of the env on this CPU measured by another build of the
  // harness (which this one does not use)
  bool measured_by_other_build(const std::string& env_name, const std::string& env_config_hash) const;

 private:
  std::string key(const std::string& env_name, const std::string& env_config_hash) const;
  std::string run_key(const PlannedRun& run) const;
  std::string path_, build_, cpu_;
  std::map<std::string, EpisodeCost> table_;
  std::set<std::string> other_builds_;      // env|env config hash measured by other builds on this CPU
  std::map<std::string, RunProbe> probes_;  // by run_key
};

// the CPU's model name (/proc/cpuinfo), "unknown" when it cannot be read
std::string cpu_model_name();

// "3.2 h", "41 min", "12 s", "4.5 days"
std::string human_duration(double seconds);

}  // namespace dsb
