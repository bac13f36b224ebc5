#pragma once
// Synthetic test functions with analytic gradients: sphere-D, rosenbrock-D, rastrigin-D,
// ackley-D, styblinski-D on the physical box [-5, 5]^D, branin on [-5, 10] x [0, 15] and
// hartmann6 on [0, 1]^6. As for every env, the parameters x live in [-1, 1]^dim; the env maps
// them affinely to the physical point z = centre + halfwidth * x, returns g(z) and
// dg/dx = dg/dz * halfwidth.
//
// The five scalable families are shifted as COCO does (docs/envs.md "Environments"):
// g(z) = f(z - x_opt + z*), z* = f's classic minimizer in every coordinate (0; rosenbrock 1;
// styblinski -2.903534027771178), so g's minimizer is x_opt and its minimum f* is unchanged.
// x_opt is drawn once per (function, D) from a fixed seed: each coordinate uniform on a 2^-20 grid
// (in normalized units) inside [-4, 4], drawn again while |x_opt_i| < 0.5, so the optimum is
// neither at the box centre (where gd and the NLopt local methods start) nor near a face or a
// corner (synthetic.cpp, shifted_optimum). branin and hartmann6 keep their classic definitions.
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "envs/core/env_family.hpp"

namespace dsb {

// the largest D a name such as "sphere-D" may ask for
inline constexpr int kSyntheticMaxDim = 10000;

// Every constant that changes the loss of a synthetic env.
struct SyntheticConfig {
  std::string function;       // "sphere", "rosenbrock", "rastrigin", "ackley", "styblinski",
                              // "branin" or "hartmann6"
  int dim = 0;                // D
  std::vector<double> lower;  // physical box, size dim; x = -1 maps to lower
  std::vector<double> upper;  // x = +1 maps to upper
  std::vector<double> x_opt;  // the shifted minimizer (physical units), size dim for the five
                              // scalable families; empty for branin and hartmann6
  // throws ConfigError naming the field: unknown function, dim out of range for the function,
  // box of the wrong size, non-finite, or with lower >= upper, x_opt of the wrong size or
  // outside the box (or set for branin / hartmann6)
  void validate() const;
  nlohmann::json to_json() const;
};

// The families, in registration order: sphere-D, rosenbrock-D, rastrigin-D, ackley-D,
// styblinski-D, branin, hartmann6. Grid members: sphere-10 ... styblinski-10, branin, hartmann6.
std::vector<EnvFamily> synthetic_families();

// The standard configuration of a synthetic env name; nullopt when the name belongs to no
// synthetic family; throws UsageError for a malformed member ("sphere-0", "rosenbrock-1", ...).
std::optional<SyntheticConfig> synthetic_config_from_name(const std::string& name);

// A synthetic env from an explicit configuration (validated: ConfigError naming the field), e.g.
// a standard one with another x_opt; `name` is only its label.
std::unique_ptr<Env> make_synthetic_env(std::string name, SyntheticConfig config);

// The global minimum of a synthetic env, in physical units (for the shifted families: x_opt).
struct KnownOptimum {
  double value;                                       // f at the minimizers
  std::vector<double> x_physical;                     // one global minimizer
  std::vector<std::vector<double>> other_minimizers;  // the rest (branin has three in all)
};

// nullopt when the name belongs to no synthetic family; throws UsageError for a malformed member.
std::optional<KnownOptimum> synthetic_known_optimum(const std::string& name);

}  // namespace dsb
