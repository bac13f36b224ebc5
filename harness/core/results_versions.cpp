#include "harness/core/results_versions.hpp"

#include <cstdio>
#include <stdexcept>

#include "envs/registry.hpp"
#include "optimizers/registry.hpp"

namespace dsb {

std::string ResultsVersions::text() const {
  if (env == 0 && optimizer == 0 && run == 0) return {};
  return "env " + std::to_string(env) + ", optimizer " + std::to_string(optimizer) + ", run " + std::to_string(run);
}

ResultsVersions parse_results_versions(const std::string& text) {
  ResultsVersions v;
  if (text.empty()) return v;
  int used = 0;
  if (std::sscanf(text.c_str(), "env %d, optimizer %d, run %d%n", &v.env, &v.optimizer, &v.run, &used) != 3 ||
      used != static_cast<int>(text.size()) || v.text() != text)
    throw std::invalid_argument("results versions '" + text + "' are not 'env E, optimizer O, run R'");
  return v;
}

ResultsVersions stored_results_versions(const std::string& text) {
  try {
    return parse_results_versions(text);
  } catch (const std::invalid_argument&) {
    return {};
  }
}

ResultsVersions current_results_versions(const std::string& env, const std::string& optimizer) {
  ResultsVersions v;
  v.env = env_results_version(env);
  if (optimizer.rfind("ext:", 0) == 0) {
    v.optimizer = kExtResultsVersion;
  } else {
    for (const auto& e : optimizer_entries())
      if (e.name == optimizer) v.optimizer = e.results_version;
  }
  v.run = kRunCodeResultsVersion;
  return v;
}

std::string stale_reason(const std::string& env, const std::string& optimizer, const ResultsVersions& stored) {
  const ResultsVersions now = current_results_versions(env, optimizer);
  if (stored == now && now.env > 0 && now.optimizer > 0) return {};
  if (stored.text().empty()) return "made before results versions (a database of schema 4 or older)";
  std::string why;
  const auto part = [&](const std::string& what, int was, int is) {
    if (was == is && is > 0) return;
    why += (why.empty() ? "" : "; ") + what + " version " + std::to_string(was) + ", this binary's " +
        (is > 0 ? std::to_string(is) : std::string("none (unknown here)"));
  };
  part("env " + env, stored.env, now.env);
  part("optimizer " + optimizer, stored.optimizer, now.optimizer);
  part("run code", stored.run, now.run);
  return why;
}

}  // namespace dsb
