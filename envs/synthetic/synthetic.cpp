#include "envs/synthetic/synthetic.hpp"

#include <cmath>
#include <cstdint>
#include <memory>
#include <numbers>
#include <span>
#include <stdexcept>
#include <string_view>
#include <utility>

#include "common/det_math.hpp"
#include "common/error.hpp"
#include "common/parallel.hpp"
#include "common/rng.hpp"

namespace dsb {
namespace {

constexpr double kPi = std::numbers::pi;

// f(z) and, when g is not empty, df/dz into g (size of z). Physical units throughout. The sums
// of the scalable functions run on the team in blocks of kGrain coordinates (common/parallel.hpp):
// the same bits for every team size, and for D <= kGrain exactly the serial loop.
using Function = double (*)(std::span<const double> z, std::span<double> g, ThreadTeam& team);
constexpr std::int64_t kGrain = 4096;

std::int64_t size_of(std::span<const double> z) { return static_cast<std::int64_t>(z.size()); }

// sphere: f = sum z_i^2. Minimum 0 at z = 0.
double sphere(std::span<const double> z, std::span<double> g, ThreadTeam& team) {
  return parallel_sum(team, size_of(z), kGrain, 0.0, [&](std::int64_t begin, std::int64_t end, double f) {
    for (std::int64_t i = begin; i < end; ++i) {
      f += z[i] * z[i];
      if (!g.empty()) g[i] = 2.0 * z[i];
    }
    return f;
  });
}

// rosenbrock: f = sum_{i < D-1} 100 (z_{i+1} - z_i^2)^2 + (1 - z_i)^2. Minimum 0 at z = 1.
// df/dz_i = 200 t_{i-1} + (-400 z_i t_i - 2 u_i), t_i = z_{i+1} - z_i^2, u_i = 1 - z_i, each
// coordinate written by its own index (terms in the order the serial accumulation adds them).
double rosenbrock(std::span<const double> z, std::span<double> g, ThreadTeam& team) {
  const std::int64_t n = size_of(z);
  return parallel_sum(team, n, kGrain, 0.0, [&](std::int64_t begin, std::int64_t end, double f) {
    for (std::int64_t i = begin; i < end; ++i) {
      const bool has_term = i + 1 < n;
      const double t = has_term ? z[i + 1] - z[i] * z[i] : 0.0;
      const double u = 1.0 - z[i];
      if (has_term) f += 100.0 * t * t + u * u;
      if (!g.empty()) {
        double gi = 0.0;
        if (i > 0) gi += 200.0 * (z[i] - z[i - 1] * z[i - 1]);
        if (has_term) gi += -400.0 * z[i] * t - 2.0 * u;
        g[i] = gi;
      }
    }
    return f;
  });
}

// rastrigin: f = 10 D + sum (z_i^2 - 10 cos(2 pi z_i)). Minimum 0 at z = 0.
double rastrigin(std::span<const double> z, std::span<double> g, ThreadTeam& team) {
  const double init = 10.0 * static_cast<double>(z.size());
  return parallel_sum(team, size_of(z), kGrain, init, [&](std::int64_t begin, std::int64_t end, double f) {
    for (std::int64_t i = begin; i < end; ++i) {
      f += z[i] * z[i] - 10.0 * dm::cos(2.0 * kPi * z[i]);
      if (!g.empty()) g[i] = 2.0 * z[i] + 20.0 * kPi * dm::sin(2.0 * kPi * z[i]);
    }
    return f;
  });
}

// ackley: f = -20 exp(-0.2 r) - exp(s) + 20 + e, r = sqrt(sum z_i^2 / D),
// s = sum cos(2 pi z_i) / D, evaluated as 20 (1 - exp(-0.2 r)) - e expm1(s - 1) so that f(0) is
// exactly 0 (e - exp(1) is not: exp(1) need not round to e). Minimum 0 at
// z = 0. The first term is a cone in r, so the gradient is undefined at exactly z = 0; there it
// is returned as 0 (the second term's gradient vanishes at 0 too).
double ackley(std::span<const double> z, std::span<double> g, ThreadTeam& team) {
  const double d = static_cast<double>(z.size());
  struct Sums {
    double sq = 0.0, cos = 0.0;
  };
  const Sums sums = parallel_reduce<Sums>(
      team, size_of(z), kGrain, Sums{}, Sums{},
      [&](std::int64_t begin, std::int64_t end, Sums acc) {
        for (std::int64_t i = begin; i < end; ++i) {
          acc.sq += z[i] * z[i];
          acc.cos += dm::cos(2.0 * kPi * z[i]);
        }
        return acc;
      },
      [](Sums a, Sums b) {
        return Sums{a.sq + b.sq, a.cos + b.cos};
      });
  const double r = std::sqrt(sums.sq / d);
  const double e_r = dm::exp(-0.2 * r);
  const double e_cos = dm::exp(sums.cos / d);
  if (!g.empty()) {
    // d/dz_i of the first term: 4 exp(-0.2 r) z_i / (D r); of the second: (2 pi / D) e_cos sin
    const double radial = r > 0.0 ? 4.0 * e_r / (d * r) : 0.0;
    parallel_for(team, size_of(z), kGrain, [&](std::int64_t begin, std::int64_t end) {
      for (std::int64_t i = begin; i < end; ++i)
        g[i] = radial * z[i] + 2.0 * kPi / d * e_cos * dm::sin(2.0 * kPi * z[i]);
    });
  }
  return 20.0 * (1.0 - e_r) - std::numbers::e * dm::expm1(sums.cos / d - 1.0);
}

// Styblinski-Tang: f = 0.5 sum (z_i^4 - 16 z_i^2 + 5 z_i). Minimum -39.16616570377142 D at
// z_i = -2.903534027771178, the lower real root of the 1-D stationarity 4 z^3 - 32 z + 5 = 0.
constexpr double kStyblinskiArgmin = -2.903534027771178;
constexpr double kStyblinskiMinPerDim = -39.16616570377142;

double styblinski(std::span<const double> z, std::span<double> g, ThreadTeam& team) {
  return parallel_sum(team, size_of(z), kGrain, 0.0, [&](std::int64_t begin, std::int64_t end, double f) {
    for (std::int64_t i = begin; i < end; ++i) {
      const double zi = z[i], z2 = zi * zi;
      f += 0.5 * (z2 * z2 - 16.0 * z2 + 5.0 * zi);
      if (!g.empty()) g[i] = 0.5 * (4.0 * z2 * zi - 32.0 * zi + 5.0);
    }
    return f;
  });
}

// branin: f = a (z2 - b z1^2 + c z1 - r)^2 + s (1 - t) cos z1 + s with a = 1,
// b = 5.1 / (4 pi^2), c = 5 / pi, r = 6, s = 10, t = 1 / (8 pi). Minimum s t = 5 / (4 pi)
// = 0.397887357729738 at (-pi, 12.275), (pi, 2.275) and (3 pi, 2.475) (where the square is 0
// and cos z1 = -1).
double branin(std::span<const double> z, std::span<double> g, ThreadTeam&) {
  const double a = 1.0, b = 5.1 / (4.0 * kPi * kPi), c = 5.0 / kPi, r = 6.0, s = 10.0, t = 1.0 / (8.0 * kPi);
  const double u = z[1] - b * z[0] * z[0] + c * z[0] - r;
  if (!g.empty()) {
    g[0] = 2.0 * a * u * (c - 2.0 * b * z[0]) - s * (1.0 - t) * dm::sin(z[0]);
    g[1] = 2.0 * a * u;
  }
  return a * u * u + s * (1.0 - t) * dm::cos(z[0]) + s;
}

// hartmann6: f = -sum_{i=1..4} alpha_i exp(-sum_j A_ij (z_j - P_ij)^2) with the standard
// constants below (P_ij = table / 10000). Minimum -3.32236801141551 at
// (0.20168952, 0.15001069, 0.47687398, 0.27533243, 0.31165162, 0.65730054) (rounded).
constexpr double kHartmannAlpha[4] = {1.0, 1.2, 3.0, 3.2};
constexpr double kHartmannA[4][6] = {{10.0, 3.0, 17.0, 3.5, 1.7, 8.0},
                                     {0.05, 10.0, 17.0, 0.1, 8.0, 14.0},
                                     {3.0, 3.5, 1.7, 10.0, 17.0, 8.0},
                                     {17.0, 8.0, 0.05, 10.0, 0.1, 14.0}};
constexpr int kHartmannP[4][6] = {{1312, 1696, 5569, 124, 8283, 5886},
                                  {2329, 4135, 8307, 3736, 1004, 9991},
                                  {2348, 1451, 3522, 2883, 3047, 6650},
                                  {4047, 8828, 8732, 5743, 1091, 381}};

double hartmann6(std::span<const double> z, std::span<double> g, ThreadTeam&) {
  if (!g.empty())
    for (double& gi : g) gi = 0.0;
  double f = 0.0;
  for (int i = 0; i < 4; ++i) {
    double dz[6], q = 0.0;
    for (int j = 0; j < 6; ++j) {
      dz[j] = z[j] - kHartmannP[i][j] / 10000.0;
      q += kHartmannA[i][j] * dz[j] * dz[j];
    }
    const double term = kHartmannAlpha[i] * dm::exp(-q);
    f -= term;
    if (!g.empty())
      for (int j = 0; j < 6; ++j) g[j] += term * 2.0 * kHartmannA[i][j] * dz[j];
  }
  return f;
}

// One synthetic family. Scalable ones ("key-D") live on [-5, 5]^D and are shifted: the env
// evaluates f(z - x_opt + z_star), whose minimizer is x_opt; fixed ones ("key") have their own
// dimension and box and are not shifted.
struct Spec {
  std::string_view key;
  std::string_view description;
  Function function;
  int min_dim;                // scalable: smallest D
  int fixed_dim;              // 0 for scalable families
  std::vector<double> lower;  // fixed families: the box
  std::vector<double> upper;
  double z_star = 0.0;  // scalable: f's classic minimizer is z_star in every coordinate
};

const std::vector<Spec>& specs() {
  static const std::vector<Spec> all = {
      {"sphere", "sum z_i^2 on [-5,5]^D, shifted; min 0 at z = x_opt", sphere, 1, 0, {}, {}, 0.0},
      {"rosenbrock",
       "Rosenbrock valley on [-5,5]^D, D >= 2, shifted; min 0 at z = x_opt",
       rosenbrock,
       2,
       0,
       {},
       {},
       1.0},
      {"rastrigin",
       "Rastrigin (many local minima) on [-5,5]^D, shifted; min 0 at z = x_opt",
       rastrigin,
       1,
       0,
       {},
       {},
       0.0},
      {"ackley", "Ackley on [-5,5]^D, shifted; min 0 at z = x_opt", ackley, 1, 0, {}, {}, 0.0},
      {"styblinski",
       "Styblinski-Tang on [-5,5]^D, shifted; min -39.16616570377142 D at z = x_opt",
       styblinski,
       1,
       0,
       {},
       {},
       kStyblinskiArgmin},
      {"branin",
       "Branin on [-5,10]x[0,15]; min 0.397887357729738 at three points",
       branin,
       2,
       2,
       {-5.0, 0.0},
       {10.0, 15.0}},
      {"hartmann6", "Hartmann 6-D on [0,1]^6; min -3.32236801141551", hartmann6, 6, 6, std::vector<double>(6, 0.0),
       std::vector<double>(6, 1.0)},
  };
  return all;
}

const Spec* find_spec(std::string_view key) {
  for (const auto& spec : specs())
    if (spec.key == key) return &spec;
  return nullptr;
}

// The shifted minimizer of a scalable family on [-5, 5]^D (docs/envs.md "Environments"):
// x_opt_i = 5 k_i / 2^20 with k_i uniform on the integers of [-838860, 838860] (0.8 * 2^20), so
// x_opt_i lies in [-4, 4], at least 1 from every face; a coordinate with |x_opt_i| < 0.5 is drawn
// again (no coordinate near the centre, where gd and the NLopt local methods start). The 2^-20
// grid makes x_opt / 5, the normalized minimizer, exact. One stream per (function, D):
// Rng(fnv1a64("<function>-<D>") ^ kShiftSeed).
constexpr std::uint64_t kShiftSeed = 0x5348494654;  // "SHIFT" in ASCII
constexpr std::int64_t kShiftSteps = 838860;

std::vector<double> shifted_optimum(std::string_view function, int dim) {
  Rng rng(fnv1a64(std::string(function) + "-" + std::to_string(dim)) ^ kShiftSeed);
  std::vector<double> x_opt(dim);
  for (double& v : x_opt) {
    do {
      const auto k = static_cast<std::int64_t>(rng.below(2 * kShiftSteps + 1)) - kShiftSteps;
      v = 5.0 * static_cast<double>(k) / 1048576.0;
    } while (std::abs(v) < 0.5);
  }
  return x_opt;
}

SyntheticConfig standard_config(const Spec& spec, int dim) {
  SyntheticConfig config;
  config.function = std::string(spec.key);
  config.dim = dim;
  if (spec.fixed_dim > 0) {
    config.lower = spec.lower;
    config.upper = spec.upper;
  } else {
    config.lower.assign(dim, -5.0);
    config.upper.assign(dim, 5.0);
    config.x_opt = shifted_optimum(spec.key, dim);
  }
  return config;
}

// The config when `name` belongs to this family, nullopt when not; UsageError when malformed.
std::optional<SyntheticConfig> parse_name(const Spec& spec, const std::string& name) {
  if (spec.fixed_dim > 0) {
    if (name != spec.key) return std::nullopt;
    return standard_config(spec, spec.fixed_dim);
  }
  const std::string prefix = std::string(spec.key) + "-";
  if (name.compare(0, prefix.size(), prefix) != 0) return std::nullopt;
  const std::string digits = name.substr(prefix.size());
  // canonical decimal only: no sign, no leading zero, at most 5 digits (the cap is 10000)
  bool ok = !digits.empty() && digits.size() <= 5 && digits[0] != '0';
  for (char ch : digits) ok = ok && ch >= '0' && ch <= '9';
  const int dim = ok ? std::stoi(digits) : 0;
  if (!ok || dim < spec.min_dim || dim > kSyntheticMaxDim)
    throw UsageError("env '" + name + "': D must be an integer from " + std::to_string(spec.min_dim) + " to " +
                     std::to_string(kSyntheticMaxDim) + ", got '" + digits + "'");
  return standard_config(spec, dim);
}

// buffers of one rollout: the physical point z (D)
struct SyntheticWorkspace : Workspace {
  std::vector<double> z;
};

EnvInfo synthetic_info(std::string name, const SyntheticConfig& config) {
  EnvInfo info;
  info.name = std::move(name);
  info.dim = config.dim;
  info.differentiable = true;
  info.threaded = config.dim > kGrain;
  info.cost_hint_s = 1e-8 * config.dim + 1e-7;
  return info;
}

class SyntheticEnv final : public Env {
 public:
  SyntheticEnv(std::string name, SyntheticConfig config, Function function, double z_star)
      : Env(synthetic_info(std::move(name), config)), config_(std::move(config)), function_(function), z_star_(z_star) {
    config_.validate();
    for (int i = 0; i < config_.dim; ++i) {
      centre_.push_back(0.5 * (config_.lower[i] + config_.upper[i]));
      halfwidth_.push_back(0.5 * (config_.upper[i] - config_.lower[i]));
    }
  }

  nlohmann::json config() const override { return config_.to_json(); }
  std::unique_ptr<Workspace> make_workspace() const override {
    auto ws = std::make_unique<SyntheticWorkspace>();
    ws->z.resize(config_.dim);
    return ws;
  }

 protected:
  double rollout(std::span<const double> x, Workspace& ws, ThreadTeam& team) const override {
    return evaluate(x, {}, ws, team);
  }
  double rollout_with_grad(std::span<const double> x, std::span<double> grad, Workspace& ws,
                           ThreadTeam& team) const override {
    if (static_cast<int>(grad.size()) != config_.dim)
      throw std::invalid_argument("env '" + name() + "': gradient has size " + std::to_string(grad.size()) +
                                  ", expected " + std::to_string(config_.dim));
    return evaluate(x, grad, ws, team);
  }

 private:
  // f at z = centre + halfwidth * x, shifted to f(z - x_opt + z_star) when x_opt is set (unit
  // Jacobian); df/dx = df/dz * halfwidth into grad unless it is empty
  double evaluate(std::span<const double> x, std::span<double> grad, Workspace& workspace, ThreadTeam& team) const {
    if (static_cast<int>(x.size()) != config_.dim)
      throw std::invalid_argument("env '" + name() + "': x has size " + std::to_string(x.size()) + ", expected " +
                                  std::to_string(config_.dim));
    std::vector<double>& z = static_cast<SyntheticWorkspace&>(workspace).z;
    for (std::size_t i = 0; i < x.size(); ++i) z[i] = centre_[i] + halfwidth_[i] * x[i];
    if (!config_.x_opt.empty())
      for (std::size_t i = 0; i < x.size(); ++i) z[i] = (z[i] - config_.x_opt[i]) + z_star_;
    const double f = function_(z, grad, team);
    for (std::size_t i = 0; i < grad.size(); ++i) grad[i] *= halfwidth_[i];
    return f;
  }

  SyntheticConfig config_;
  Function function_;
  double z_star_;
  std::vector<double> centre_, halfwidth_;
};

KnownOptimum known_optimum(const SyntheticConfig& config) {
  const int d = config.dim;
  const std::string& f = config.function;
  // shifted families: the minimizer is x_opt, the value f's classic minimum
  if (f == "sphere" || f == "rastrigin" || f == "ackley" || f == "rosenbrock") return {0.0, config.x_opt, {}};
  if (f == "styblinski") return {kStyblinskiMinPerDim * d, config.x_opt, {}};
  if (f == "branin") return {5.0 / (4.0 * kPi), {-kPi, 12.275}, {{kPi, 2.275}, {3.0 * kPi, 2.475}}};
  // hartmann6
  return {-3.32236801141551, {0.20168952, 0.15001069, 0.47687398, 0.27533243, 0.31165162, 0.65730054}, {}};
}

}  // namespace

void SyntheticConfig::validate() const {
  const Spec* spec = find_spec(function);
  if (spec == nullptr) throw ConfigError("synthetic", "function", "unknown: '" + function + "'");
  const int lo = spec->fixed_dim > 0 ? spec->fixed_dim : spec->min_dim;
  const int hi = spec->fixed_dim > 0 ? spec->fixed_dim : kSyntheticMaxDim;
  if (dim < lo || dim > hi)
    throw ConfigError("synthetic", "dim",
                      "must be from " + std::to_string(lo) + " to " + std::to_string(hi) + " for " + function +
                          ", got " + std::to_string(dim));
  if (static_cast<int>(lower.size()) != dim)
    throw ConfigError("synthetic", "lower",
                      "has size " + std::to_string(lower.size()) + ", expected " + std::to_string(dim));
  if (static_cast<int>(upper.size()) != dim)
    throw ConfigError("synthetic", "upper",
                      "has size " + std::to_string(upper.size()) + ", expected " + std::to_string(dim));
  for (int i = 0; i < dim; ++i) {
    if (!std::isfinite(lower[i]))
      throw ConfigError("synthetic", "lower", "is not finite at index " + std::to_string(i));
    if (!std::isfinite(upper[i]))
      throw ConfigError("synthetic", "upper", "is not finite at index " + std::to_string(i));
    if (!(lower[i] < upper[i]))
      throw ConfigError("synthetic", "upper", "must exceed lower at index " + std::to_string(i));
  }
  // scalable families are shifted (x_opt of size dim, inside the box); fixed ones are not
  if (spec->fixed_dim > 0) {
    if (!x_opt.empty()) throw ConfigError("synthetic", "x_opt", "must be empty for " + function + " (not shifted)");
    return;
  }
  if (static_cast<int>(x_opt.size()) != dim)
    throw ConfigError("synthetic", "x_opt",
                      "has size " + std::to_string(x_opt.size()) + ", expected " + std::to_string(dim));
  for (int i = 0; i < dim; ++i)
    if (!(x_opt[i] >= lower[i] && x_opt[i] <= upper[i]))
      throw ConfigError("synthetic", "x_opt", "is outside the box (or not finite) at index " + std::to_string(i));
}

nlohmann::json SyntheticConfig::to_json() const {
  nlohmann::json j = {{"function", function}, {"dim", dim}, {"lower", lower}, {"upper", upper}};
  if (!x_opt.empty()) j["x_opt"] = x_opt;  // branin and hartmann6 keep their unshifted JSON
  return j;
}

std::optional<SyntheticConfig> synthetic_config_from_name(const std::string& name) {
  for (const auto& spec : specs())
    if (auto config = parse_name(spec, name)) return config;
  return std::nullopt;
}

std::optional<KnownOptimum> synthetic_known_optimum(const std::string& name) {
  if (auto config = synthetic_config_from_name(name)) return known_optimum(*config);
  return std::nullopt;
}

std::unique_ptr<Env> make_synthetic_env(std::string name, SyntheticConfig config) {
  config.validate();
  const Spec* spec = find_spec(config.function);
  return std::make_unique<SyntheticEnv>(std::move(name), std::move(config), spec->function, spec->z_star);
}

std::vector<EnvFamily> synthetic_families() {
  std::vector<EnvFamily> families;
  for (const auto& spec : specs()) {
    const bool scalable = spec.fixed_dim == 0;
    const std::string key(spec.key);
    EnvFamily family;
    family.pattern = scalable ? key + "-D" : key;
    family.description = std::string(spec.description);
    family.grid_names = {scalable ? key + "-10" : key};
    family.try_make = [&spec](const std::string& name) -> std::unique_ptr<Env> {
      auto config = parse_name(spec, name);
      if (!config) return nullptr;
      return std::make_unique<SyntheticEnv>(name, std::move(*config), spec.function, spec.z_star);
    };
    families.push_back(std::move(family));
  }
  return families;
}

}  // namespace dsb
