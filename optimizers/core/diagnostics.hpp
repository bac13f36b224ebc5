#pragma once
// Building blocks of run diagnostics (Optimizer::diagnostics(), the harness's objective side):
// summaries and capped lists, so that a run's diagnostics stay a few KB whatever its length.
// Everything here is deterministic: the same values give the same JSON.
#include <algorithm>
#include <cstddef>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

namespace dsb {

// Lists in diagnostics keep at most this many entries; the rest is only counted.
inline constexpr std::size_t kDiagnosticsListCap = 100;

// {"count", "min", "median", "max"}; median of an even count = mean of the two middle values;
// min, median and max are null when there are no values.
template <class T>
nlohmann::json summarize(std::vector<T> values) {
  nlohmann::json s = {{"count", values.size()}, {"min", nullptr}, {"median", nullptr}, {"max", nullptr}};
  if (values.empty()) return s;
  std::sort(values.begin(), values.end());
  const std::size_t n = values.size();
  // median: middle value, or the mean of the two middle values
  const double median = n % 2 == 1
      ? static_cast<double>(values[n / 2])
      : 0.5 * (static_cast<double>(values[n / 2 - 1]) + static_cast<double>(values[n / 2]));
  s["min"] = values.front();
  s["median"] = median;
  s["max"] = values.back();
  return s;
}

// out[key] = the first kDiagnosticsListCap items, each through to_json;
// out[key + "_truncated"] = how many were left out (0 when none).
template <class T, class F>
void put_capped(nlohmann::json& out, const std::string& key, const std::vector<T>& items, F&& to_json) {
  nlohmann::json list = nlohmann::json::array();
  const std::size_t kept = std::min(items.size(), kDiagnosticsListCap);
  for (std::size_t i = 0; i < kept; ++i) list.push_back(to_json(items[i], i));
  out[key] = std::move(list);
  out[key + "_truncated"] = items.size() - kept;
}

}  // namespace dsb
