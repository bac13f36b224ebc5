#pragma once
// The claims grid (`harness --claims`): exactly the (env, optimizer) runs that the report's claims
// table (reports/paper_claims.csv, compiled into the harness) needs, at the grid's seeds and
// budget, and nothing else. Per claim that the database can test (every kind but not_testable), on
// each of its envs: the optimizers of a and b; for an a_best claim every optimizer `--all` pairs
// with the env (its rivals), as the report's claim_runs.needed_optimizers takes them.
#include <string>
#include <vector>

#include "harness/plan/grid.hpp"

namespace dsb {

// the claims file the harness was built with (reports/paper_claims.csv, as text)
const char* paper_claims_csv();

struct ClaimsEnv {
  std::string env;
  bool every_optimizer = false;         // an a_best claim: every optimizer --all pairs with env
  std::vector<std::string> optimizers;  // else these, in the claims file's order
};

// The envs the claims need, in the file's order, each with its optimizers; UsageError naming a
// malformed file (a missing column, an unterminated quote).
std::vector<ClaimsEnv> claims_envs(const std::string& csv_text);

// The claims grid of `base` (its seeds, budget, --set, --ext settings; its envs and optimizers
// must be empty): one grid request per env of the claims, restricted to `only_envs` when given
// (UsageError naming an env that no claim needs). --set settings go to the requests whose env or
// optimizer they name (UsageError naming one that no request has).
std::vector<GridRequest> claims_requests(const GridRequest& base, const std::vector<std::string>& only_envs);

}  // namespace dsb
