#pragma once
// `random`: uniform random search in the normalized box (the paper's Rand).
#include <memory>

#include "optimizers/core/optimizer.hpp"

namespace dsb {

std::unique_ptr<Optimizer> make_random_search();

}  // namespace dsb
