#pragma once
// The harness's commands other than `run`: list, eval, gradcheck. Each returns the exit code.
#include <cstdint>
#include <string>
#include <vector>

namespace dsb {

int command_list();
int command_eval(const std::string& env_name, const std::string& x_text, bool with_grad);
int command_gradcheck(const std::string& env_name, int points, std::uint64_t seed, double amplitude,
                      double step, double tolerance);

// Parses a comma-separated list of finite numbers; UsageError naming the bad token.
std::vector<double> parse_number_list(const std::string& option, const std::string& text);

}  // namespace dsb
