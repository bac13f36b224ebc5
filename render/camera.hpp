#pragma once
// Orthographic projection of scenes and the fit of a frame sequence to a panel of pixels.
#include <vector>

#include "envs/core/scene.hpp"

namespace dsb::render {

// a projected point: u right, v up (world units)
struct Projected {
  double u = 0.0, v = 0.0;
};

// side: (x, y); oblique: turned 30 degrees about y (the +x side away from the viewer), then seen
// from 25 degrees above
Projected project(Camera camera, const ScenePoint& p);

// world (u, v) to pixels of one panel: px = left + (u - u0) scale, py = bottom - (v - v0) scale
struct Viewport {
  int width = 0, height = 0;  // panel size (pixels)
  double u0 = 0.0, v0 = 0.0;  // world point at (left, bottom)
  double left = 0.0, bottom = 0.0;
  double scale = 1.0;  // pixels per metre
  double px(const Projected& p) const { return left + (p.u - u0) * scale; }
  double py(const Projected& p) const { return bottom - (p.v - v0) * scale; }
};

constexpr int kLabelHeight = 16;  // pixels above the drawing for the time label
constexpr int kMargin = 8;        // pixels around the drawing

// One viewport for every frame (same scale, so frames compare): the bounds of every item of every
// frame, centred in a panel `width` pixels wide whose height follows the bounds' aspect (between
// a third and twice the width). Throws std::invalid_argument for no frames or width < 64.
Viewport fit(const std::vector<Frame>& frames, int width);

}  // namespace dsb::render
