#pragma once
// A run key (harness/core/run_key.hpp) in SQL over the runs table: its columns are runs' UNIQUE
// key as declared in tables.hpp, in RunKey's order, so they are read, matched and bound here once.
#include <string>

#include "harness/core/run_key.hpp"
#include "harness/store/sqlite_db.hpp"

namespace dsb {

// the key's 8 columns read from a file of schema `version` (results_versions as '' before 5),
// joined with ", "
std::string run_key_columns(int version);
// the run key read from the 8 columns of run_key_columns starting at column `first`
RunKey read_run_key(const Statement& q, int first);

// "env=? AND optimizer=? AND ..." over the key's columns; without the seed (with_seed false) the
// key's group: the runs of one config whose seeds share their seed-free episodes
std::string run_key_match(bool with_seed = true);
// binds the key's values to run_key_match's parameters, the first at index `first`
void bind_run_key(Statement& st, int first, const RunKey& key, bool with_seed = true);

}  // namespace dsb
