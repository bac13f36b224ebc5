#include "envs/core/env_family.hpp"

#include <utility>

#include "common/error.hpp"

namespace dsb {

EnvFamily single_env_family(std::string name, std::string description, std::function<std::unique_ptr<Env>()> make) {
  EnvFamily f;
  f.pattern = name;
  f.description = std::move(description);
  f.grid_names = {name};
  f.try_make = [name, make = std::move(make)](const std::string& requested) -> std::unique_ptr<Env> {
    if (requested == name) return make();
    const bool variant = requested.size() > name.size() && requested.compare(0, name.size(), name) == 0 &&
        (requested[name.size()] == '-' || requested[name.size()] == '_');
    if (variant) throw UsageError("unknown env '" + requested + "' (" + name + " takes no variants)");
    return nullptr;
  };
  return f;
}

}  // namespace dsb
