#pragma once
// The published archive (docs/results.md "Compare your optimizer with the published runs";
// reports/dsb_report/archive.py writes it): files NAME.runs.jsonl.gz under a folder, gzip of one
// JSON object per 'done' run with its run key, results versions and per-episode losses. Read here
// for `harness export --format ioh --with DIR`, which puts them beside (or instead of) a
// database's runs in IOHprofiler's format.
#include <cstdint>
#include <string>
#include <vector>

#include "harness/store/export_ioh.hpp"

namespace dsb {

struct ArchivedRuns {
  std::vector<IohRun> runs;         // this binary's results versions (all with include_stale, marked)
  std::int64_t stale_left_out = 0;  // archived runs of other results versions, left out
  int files = 0;                    // archive files read
};

// Every run of the archive files under `folder` (recursively; or `folder` itself when it is a
// file), files in name order. UsageError "--with: ..." naming the file and line of a damaged one,
// or a folder without archive files.
ArchivedRuns read_archive_runs(const std::string& folder, bool include_stale);

}  // namespace dsb
