#pragma once
// Draws one frame's scene into a panel of a palette image.
#include <gd.h>

#include "envs/core/scene.hpp"
#include "render/camera.hpp"
#include "render/palette.hpp"

namespace dsb::render {

// Draws `frame` into the panel whose left edge is at pixel x_offset (clipped to it): the time
// label at the top, then faint clouds, fixed lines, the other clouds, the other lines (trace,
// medium, tool, target, state) and the discs (fixed, target, tool, state).
void draw_frame(gdImagePtr im, const Palette& palette, const Viewport& vp, int x_offset, const Frame& frame);

}  // namespace dsb::render
