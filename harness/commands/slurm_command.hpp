#pragma once
// `harness slurm`: writes the scripts that run a grid as a Slurm job array (docs/running.md, "Running on a
// Slurm cluster"): DIR/array.sbatch (task I of N runs shard I/N of the grid in a node-local SQLite file,
// resumes from and copies back to DIR/shards/shard-I.sqlite, also when a time limit sends TERM),
// DIR/merge.sbatch (`harness merge` of the N shards into DIR/results.sqlite) and DIR/submit.sh
// (the array, then the merge after every task succeeded). It submits nothing itself. DIR must be
// new, empty or its own (slurm_dir.hpp); the scripts never write over a file they did not create:
// a task replaces only the shard file it resumed from, the merge never replaces results.sqlite.
#include <cstddef>
#include <cstdint>
#include <ostream>
#include <string>
#include <vector>

namespace dsb {

// the grid flags handed to every array task, exactly as given (already validated by the caller)
struct SlurmGridFlags {
  bool all = false;
  bool claims = false;  // --claims
  std::vector<std::string> envs, optimizers;
  int seeds = 1;
  std::string budget = "1000";
  std::vector<std::string> knobs;  // --set OPT.KNOB=VALUE
  std::vector<std::string> ext;    // --ext NAME=COMMAND
  std::string ext_timeout;         // --ext-timeout SECONDS (empty: not given)
};

// Slurm's default MaxArraySize is 1001: array indices 0..1000
inline constexpr int kMaxSlurmShards = 1000;

struct SlurmOptions {
  int shards = 0;         // N: array tasks 0..N-1
  std::string dir;        // where the scripts, logs, shards and the merged database go
  int cpus_per_task = 1;  // each task's --jobs
  std::string time;       // Slurm time limit per task ([D-]HH:MM:SS etc.); empty = the cluster's default
  std::string time_note;  // where `time` came from, when the harness chose it (printed)
  std::string partition;  // empty = the cluster's default
};

// Checks the options and DIR (UsageError naming the bad value; nothing is created before every
// check passed), creates DIR, DIR/logs and DIR/shards, writes the three scripts and prints what it
// wrote and how to submit. grid_runs is the size of the whole
// grid, shard_runs[I] the runs of shard I/N (shard_of); harness_path the binary the tasks run
// (absolute). Returns 0.
int command_slurm(const SlurmGridFlags& grid, std::size_t grid_runs, const std::vector<std::int64_t>& shard_runs,
                  const SlurmOptions& options, const std::string& harness_path, std::ostream& out);

// The time limit of an array task from the plan: the longest task's estimated wall (its runs'
// seconds over its CPUs, never less than its longest run) times kSlurmTimeMargin plus
// kSlurmTimeExtraS (start-up, copying the database back, a slower node), as Slurm's D-HH:MM:SS.
inline constexpr double kSlurmTimeMargin = 1.5;
inline constexpr double kSlurmTimeExtraS = 15 * 60;
std::string slurm_time_limit(double longest_task_s);

// The absolute path of the running program (/proc/self/exe).
std::string running_binary_path();

}  // namespace dsb
