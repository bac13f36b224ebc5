#pragma once
// Results versions (docs/database.md "Results versions"): which code made a stored result. Each
// env family declares one beside its registration (envs/registry.cpp), each optimizer one in its
// registration (optimizers/registry.cpp), and the run code that every run shares (the budget
// wrapper, replay and the journal, seeding, the order of records) has kRunCodeResultsVersion. A
// commit that changes results bumps the version of what it changed, in the same commit. The
// three are part of the run key: a binary never resumes, counts as done, reports or exports as
// current a stored run whose versions differ from its own. Such a run is "stale"; it stays in
// the database, untouched.
#include <cstdint>
#include <string>

namespace dsb {

// the shared run code's results version: bump it with a change that alters every run's records
inline constexpr int kRunCodeResultsVersion = 1;
// an external optimizer's (ext:NAME): the adapter's; the program's own name and version are in
// its config
inline constexpr int kExtResultsVersion = 1;

struct ResultsVersions {
  int env = 0, optimizer = 0, run = 0;  // 0: unknown (a database from before versions, or a name no longer known)

  bool operator==(const ResultsVersions&) const = default;
  auto operator<=>(const ResultsVersions&) const = default;
  // "env 2, optimizer 1, run 1", as the run key stores it (runs.results_versions); "" when all 0
  std::string text() const;
};

// Reads text() back; all 0 for "" (an older database's rows); std::invalid_argument for any
// other text.
ResultsVersions parse_results_versions(const std::string& text);

// A stored runs.results_versions: parse_results_versions, or all 0 (unknown, so stale) for a text
// this binary cannot read.
ResultsVersions stored_results_versions(const std::string& text);

// This binary's versions for a run of `env` with `optimizer` (0 for a name it does not know; an
// ext:NAME optimizer has kExtResultsVersion).
ResultsVersions current_results_versions(const std::string& env, const std::string& optimizer);

// Why a stored run of env and optimizer with versions `stored` is stale for this binary, e.g.
// "env plb-pinch version 1, this binary's 2"; "" when it is not stale.
std::string stale_reason(const std::string& env, const std::string& optimizer, const ResultsVersions& stored);

// Stored runs whose results versions are not this binary's, of one env, optimizer and reason
// (store/stored_runs.hpp finds them; plan/plan_report.hpp prints them): never resumed or counted
// as done, left in the file as they are.
struct StaleRuns {
  std::string env, optimizer, reason;
  std::int64_t done = 0, unfinished = 0;  // 'done' runs; 'running' or 'failed' ones
};

}  // namespace dsb
