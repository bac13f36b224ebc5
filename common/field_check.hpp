#pragma once
// The checks a config's validate() makes of its fields, written once: each throws a ConfigError
// naming the config (owner), the field and, where the message says so, the bad value, e.g.
//   FieldCheck check("bounce");
//   check.positive("radius", radius);  // bounce config: field 'radius' must be finite and > 0, got -1.000000
//   check.number_above("sigma0", sigma0, 0.0);  // ... must be a finite number > 0 (got -1)
// A nested config's checks name their fields under a prefix ("contact." -> 'contact.ke').
#include <array>
#include <cmath>
#include <cstddef>
#include <string>
#include <vector>

#include "common/error.hpp"
#include "common/number_text.hpp"

namespace dsb {

class FieldCheck {
 public:
  explicit FieldCheck(std::string owner, std::string prefix = "")
      : owner_(std::move(owner)), prefix_(std::move(prefix)) {}

  [[noreturn]] void fail(const std::string& field, const std::string& why) const {
    throw ConfigError(owner_, prefix_ + field, why);
  }
  // fails with `why` unless ok
  void require(bool ok, const std::string& field, const std::string& why) const {
    if (!ok) fail(field, why);
  }
  // finite and > 0, the value in the message
  void positive(const std::string& field, double v) const {
    require(std::isfinite(v) && v > 0.0, field, "must be finite and > 0, got " + std::to_string(v));
  }
  // finite and >= 0, the value in the message
  void nonnegative(const std::string& field, double v) const {
    require(std::isfinite(v) && v >= 0.0, field, "must be finite and >= 0, got " + std::to_string(v));
  }
  void finite(const std::string& field, double v) const { require(std::isfinite(v), field, "must be finite"); }
  // every component finite
  template <std::size_t N>
  void finite(const std::string& field, const std::array<double, N>& a) const {
    for (double v : a) finite(field, v);
  }
  // an integer >= least, the value in the message
  void at_least(const std::string& field, int v, int least) const {
    require(v >= least, field, "must be >= " + std::to_string(least) + ", got " + std::to_string(v));
  }
  // finite and > least, both numbers in the message as number_text writes them
  void number_above(const std::string& field, double v, double least) const {
    require(std::isfinite(v) && v > least, field,
            "must be a finite number > " + number_text(least) + " (got " + number_text(v) + ")");
  }
  // finite and >= least, both numbers in the message as number_text writes them
  void number_at_least(const std::string& field, double v, double least) const {
    require(std::isfinite(v) && v >= least, field,
            "must be a finite number >= " + number_text(least) + " (got " + number_text(v) + ")");
  }
  // dt and duration finite and > 0, and an episode of round(duration / dt) >= 1 steps (as a long)
  void time_steps(const std::string& duration_field, double duration, double dt) const {
    positive("dt", dt);
    positive(duration_field, duration);
    require(std::lround(duration / dt) >= 1, duration_field, "must be at least one step dt");
  }
  // every entry in [-1, 1] (normalized parameters)
  template <class Values>
  void in_unit_box(const std::string& field, const Values& xs) const {
    for (double x : xs) require(x >= -1.0 && x <= 1.0, field, "must lie in [-1, 1]");
  }

 private:
  std::string owner_;
  std::string prefix_;
};

}  // namespace dsb
