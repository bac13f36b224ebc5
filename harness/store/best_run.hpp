#pragma once
// `harness render --best-of DB`: which stored run to draw.
#include <cstdint>
#include <string>

namespace dsb {

// The best done run of an env in a harness database (read-only), of one optimizer when `optimizer`
// is not empty: the smallest best_loss, ties to the smallest run_id (reports/dsb_report/renders.py
// picks the same run). UsageError naming the file (and the optimizer) when it cannot be read or
// holds no such done run with a best_x.
struct BestRun {
  std::string optimizer;
  std::int64_t seed = 0;
  double best_loss = 0.0;
  std::string best_x;  // comma-separated
};
BestRun best_run_of(const std::string& db_path, const std::string& env, const std::string& optimizer = "");

}  // namespace dsb
