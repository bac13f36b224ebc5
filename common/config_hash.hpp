#pragma once
// Content hash of a resolved configuration: FNV-1a 64 over the canonical JSON text (keys sorted
// by nlohmann::json's std::map objects, doubles printed with 17 significant digits).
#include <cstdio>
#include <string>

#include <nlohmann/json.hpp>

#include "common/rng.hpp"

namespace dsb {

inline std::string canonical_json(const nlohmann::json& j) { return j.dump(); }

inline std::string config_hash(const nlohmann::json& j) {
  char buf[17];
  std::snprintf(buf, sizeof buf, "%016llx",
                static_cast<unsigned long long>(fnv1a64(canonical_json(j))));
  return buf;
}

}  // namespace dsb
