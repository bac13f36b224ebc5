#include "harness/store/archive_reader.hpp"

#include <algorithm>
#include <cmath>
#include <filesystem>

#include <nlohmann/json.hpp>

#include "common/error.hpp"
#include "common/gzip_text.hpp"
#include "common/regular_file.hpp"
#include "common/shown_value.hpp"
#include "harness/core/results_versions.hpp"

namespace dsb {
namespace {

namespace fs = std::filesystem;

constexpr const char* kSuffix = ".runs.jsonl.gz";
constexpr int kFormat = 1;

bool is_archive_file(const fs::path& p) {
  const std::string name = p.filename().string();
  return name.size() > std::string(kSuffix).size() &&
      name.compare(name.size() - std::string(kSuffix).size(), std::string::npos, kSuffix) == 0;
}

[[noreturn]] void damaged(const std::string& file, std::size_t line, const std::string& why) {
  throw UsageError("--with: archive '" + shown_value(file) + "' line " + std::to_string(line) + ": " + why);
}

// one archive object as an exported run: its key and the improvements of its best loss
IohRun run_of(const nlohmann::json& j, const std::string& file, std::size_t line) {
  try {
    if (j.at("archive").get<int>() != kFormat) damaged(file, line, "not archive format 1");
    IohRun r;
    r.env = j.at("env").get<std::string>();
    r.optimizer = j.at("optimizer").get<std::string>();
    r.seed = j.at("seed").get<int>();
    r.budget = j.at("budget").get<std::int64_t>();
    r.env_hash = j.at("env_config_hash").get<std::string>();
    r.opt_hash = j.at("opt_config_hash").get<std::string>();
    r.version = j.at("harness_version").get<std::string>();
    r.results_versions = j.at("results_versions").get<std::string>();
    r.best_x = nlohmann::json::array();
    const auto& losses = j.at("loss");
    if (!losses.is_array() || static_cast<std::int64_t>(losses.size()) != j.at("episodes").get<std::int64_t>())
      damaged(file, line, "its losses are not one per episode");
    r.episodes = static_cast<std::int64_t>(losses.size());
    double best = 0.0;
    for (std::size_t k = 0; k < losses.size(); ++k) {
      if (losses[k].is_null()) continue;  // a failed episode
      const double loss = losses[k].get<double>();
      if (!std::isfinite(loss)) continue;
      if (r.rows.empty() || loss < best) {
        best = loss;
        r.rows.emplace_back(static_cast<std::int64_t>(k) + 1, loss);
      }
    }
    return r;
  } catch (const nlohmann::json::exception& e) {
    damaged(file, line, std::string("a field is missing or of the wrong type (") + e.what() + ")");
  }
}

}  // namespace

ArchivedRuns read_archive_runs(const std::string& folder, bool include_stale) {
  std::vector<fs::path> files;
  std::error_code ec;
  if (fs::is_regular_file(folder, ec)) {
    files.push_back(folder);
  } else if (fs::is_directory(folder, ec)) {
    for (auto it = fs::recursive_directory_iterator(folder, ec); !ec && it != fs::recursive_directory_iterator();
         it.increment(ec))
      if (it->is_regular_file() && is_archive_file(it->path())) files.push_back(it->path());
    std::sort(files.begin(), files.end());
  } else {
    throw UsageError("--with: '" + shown_value(folder) + "' is not a folder of archive files");
  }
  if (files.empty())
    throw UsageError("--with: '" + shown_value(folder) + "' holds no archive file (NAME" + kSuffix + ")");
  ArchivedRuns out;
  std::int64_t next_id = std::int64_t{1} << 40;  // after any database's run ids: a stable order
  for (const auto& f : files) {
    const std::string file = f.string();
    std::string text;
    try {
      text = gunzip(read_regular_file("--with", file));
    } catch (const GzipError& e) {
      throw UsageError("--with: archive '" + shown_value(file) + "': " + e.what());
    }
    ++out.files;
    std::size_t at = 0, line = 0;
    while (at < text.size()) {
      const std::size_t end = text.find('\n', at);
      const std::string_view one(text.data() + at, (end == std::string::npos ? text.size() : end) - at);
      at = end == std::string::npos ? text.size() : end + 1;
      ++line;
      if (one.empty()) continue;
      const auto j = nlohmann::json::parse(one, nullptr, false);
      if (j.is_discarded() || !j.is_object()) damaged(file, line, "not a JSON object");
      IohRun r = run_of(j, file, line);
      r.stale = !stale_reason(r.env, r.optimizer, stored_results_versions(r.results_versions)).empty();
      if (r.stale && !include_stale) {
        ++out.stale_left_out;
        continue;
      }
      r.run_id = next_id++;
      out.runs.push_back(std::move(r));
    }
  }
  return out;
}

}  // namespace dsb
