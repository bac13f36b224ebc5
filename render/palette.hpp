#pragma once
// The colours of the scene roles (the same indices in every image, so GIF frames share one
// palette and the bytes are deterministic).
#include <array>
#include <gd.h>

#include "envs/core/scene.hpp"

namespace dsb::render {

struct Rgb {
  int r = 0, g = 0, b = 0;
};

// the colour of a role; faint: the light tint of faint point clouds
Rgb role_colour(Role role, bool faint = false);

// palette indices of one image, allocated in a fixed order (background first)
struct Palette {
  int background = 0, text = 0, frame = 0;
  std::array<int, 6> solid{}, faint{};  // by Role
  int of(Role role, bool is_faint = false) const { return (is_faint ? faint : solid)[static_cast<int>(role)]; }
};

Palette allocate_palette(gdImagePtr im);

}  // namespace dsb::render
