#pragma once
// Error types that cross component boundaries. A UsageError is bad input from the user
// (unknown name, malformed number, wrong dimension, invalid config field): the harness prints
// its one-line message and exits with code 2 before anything stored is touched.
#include <stdexcept>
#include <string>

namespace dsb {

struct UsageError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

// invalid configuration; the message names the field and the bad value
struct ConfigError : UsageError {
  ConfigError(const std::string& owner, const std::string& field, const std::string& why)
      : UsageError(owner + " config: field '" + field + "' " + why) {}
};

}  // namespace dsb
