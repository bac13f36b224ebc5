#include "render/palette.hpp"

namespace dsb::render {

Rgb role_colour(Role role, bool faint) {
  // solid colours, and the faint tint: 70% of the way to white
  Rgb c;
  switch (role) {
    case Role::state: c = {220, 100, 0}; break;     // orange
    case Role::target: c = {200, 0, 0}; break;      // red
    case Role::tool: c = {30, 80, 200}; break;      // blue
    case Role::fixed: c = {120, 120, 120}; break;   // grey
    case Role::trace: c = {240, 170, 90}; break;    // light orange
    case Role::medium: c = {110, 170, 220}; break;  // light blue (syrup)
  }
  if (faint) c = {c.r + (255 - c.r) * 7 / 10, c.g + (255 - c.g) * 7 / 10, c.b + (255 - c.b) * 7 / 10};
  return c;
}

Palette allocate_palette(gdImagePtr im) {
  Palette p;
  p.background = gdImageColorAllocate(im, 255, 255, 255);
  p.text = gdImageColorAllocate(im, 0, 0, 0);
  p.frame = gdImageColorAllocate(im, 200, 200, 200);
  for (int r = 0; r < 6; ++r) {
    const Rgb s = role_colour(static_cast<Role>(r)), f = role_colour(static_cast<Role>(r), true);
    p.solid[r] = gdImageColorAllocate(im, s.r, s.g, s.b);
    p.faint[r] = gdImageColorAllocate(im, f.r, f.g, f.b);
  }
  return p;
}

}  // namespace dsb::render
