#pragma once
// Points and number lists given as text on the command line (--x, --center, --dims).
#include <string>
#include <vector>

#include "envs/core/env.hpp"

namespace dsb {

// Parses a comma-separated list of finite numbers; UsageError naming the bad token.
std::vector<double> parse_number_list(const std::string& option, const std::string& text);
// A point of env's box from text: UsageError for a malformed number, a wrong dimension or a value
// outside [-1, 1], naming the option and the value.
std::vector<double> checked_point(const Env& env, const std::string& x_text, const std::string& option = "--x");

}  // namespace dsb
