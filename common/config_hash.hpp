#pragma once
// Content hash of a resolved configuration: FNV-1a 64 over the canonical JSON text, which is
// nlohmann::json's dump() (as in Debian's nlohmann-json3 3.11.2; tests/test_store.cpp pins it):
//   - object keys sorted (objects are std::map), no whitespace;
//   - a double in the short form of Grisu2 that reads back to the same double through strtod
//     (0.1 -> 0.1, 1/3 -> 0.3333333333333333, 1e-9 -> 1e-09; usually the shortest such text, not
//     a fixed number of digits), ".0" appended to an integral one (1.0 -> 1.0), so different
//     doubles give different text; a JSON integer stays one (5 -> 5, unlike 5.0 -> 5.0);
//   - NaN and the infinities all print as null: they hash alike.
#include <cstdio>
#include <string>

#include <nlohmann/json.hpp>

#include "common/rng.hpp"

namespace dsb {

inline std::string canonical_json(const nlohmann::json& j) { return j.dump(); }

inline std::string config_hash(const nlohmann::json& j) {
  char buf[17];
  std::snprintf(buf, sizeof buf, "%016llx", static_cast<unsigned long long>(fnv1a64(canonical_json(j))));
  return buf;
}

}  // namespace dsb
