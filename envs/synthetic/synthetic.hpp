#pragma once
// Synthetic test functions with analytic gradients: sphere-D, rosenbrock-D, rastrigin-D,
// ackley-D, styblinski-D on the physical box [-5, 5]^D, branin on [-5, 10] x [0, 15] and
// hartmann6 on [0, 1]^6. As for every env, the parameters x live in [-1, 1]^dim; the env maps
// them affinely to the physical point z = centre + halfwidth * x, returns f(z) and
// df/dx = df/dz * halfwidth.
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "envs/core/registry.hpp"

namespace dsb {

// the largest D a name such as "sphere-D" may ask for
inline constexpr int kSyntheticMaxDim = 10000;

// Every constant that changes the loss of a synthetic env.
struct SyntheticConfig {
  std::string function;        // "sphere", "rosenbrock", "rastrigin", "ackley", "styblinski",
                               // "branin" or "hartmann6"
  int dim = 0;                 // D
  std::vector<double> lower;   // physical box, size dim; x = -1 maps to lower
  std::vector<double> upper;   // x = +1 maps to upper
  // throws ConfigError naming the field: unknown function, dim out of range for the function,
  // box of the wrong size, non-finite, or with lower >= upper
  void validate() const;
  nlohmann::json to_json() const;
};

// The families, in registration order: sphere-D, rosenbrock-D, rastrigin-D, ackley-D,
// styblinski-D, branin, hartmann6. Grid members: sphere-10 ... styblinski-10, branin, hartmann6.
std::vector<EnvFamily> synthetic_families();

// The standard configuration of a synthetic env name; nullopt when the name belongs to no
// synthetic family; throws UsageError for a malformed member ("sphere-0", "rosenbrock-1", ...).
std::optional<SyntheticConfig> synthetic_config_from_name(const std::string& name);

// The global minimum of a synthetic env, in physical units.
struct KnownOptimum {
  double value;                                     // f at the minimizers
  std::vector<double> x_physical;                   // one global minimizer
  std::vector<std::vector<double>> other_minimizers;  // the rest (branin has three in all)
};

// nullopt when the name belongs to no synthetic family; throws UsageError for a malformed member.
std::optional<KnownOptimum> synthetic_known_optimum(const std::string& name);

}  // namespace dsb
