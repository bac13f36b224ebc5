#include "render/camera.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

namespace dsb::render {

Projected project(Camera camera, const ScenePoint& p) {
  if (camera == Camera::side) return {p[0], p[1]};
  // azimuth 30 degrees about y, then elevation 25 degrees (depth d grows away from the viewer)
  const double ca = 0.86602540378443865, sa = 0.5;
  const double ce = 0.90630778703664994, se = 0.42261826174069944;
  const double u = ca * p[0] - sa * p[2];
  const double d = sa * p[0] + ca * p[2];
  return {u, ce * p[1] - se * d};
}

Viewport fit(const std::vector<Frame>& frames, int width) {
  if (frames.empty()) throw std::invalid_argument("render: no frames to fit");
  if (width < 64) throw std::invalid_argument("render: panel width below 64 pixels");
  // bounds of the projected items (discs grown by their radius), finite points only
  double ulo = std::numeric_limits<double>::infinity(), vlo = ulo, uhi = -ulo, vhi = -ulo;
  auto add = [&](const Projected& q, double r) {
    if (!std::isfinite(q.u) || !std::isfinite(q.v)) return;
    ulo = std::min(ulo, q.u - r);
    uhi = std::max(uhi, q.u + r);
    vlo = std::min(vlo, q.v - r);
    vhi = std::max(vhi, q.v + r);
  };
  for (const Frame& f : frames) {
    const Camera cam = f.scene.camera;
    for (const auto& c : f.scene.clouds)
      for (const auto& p : c.points) add(project(cam, p), 0.0);
    for (const auto& l : f.scene.lines)
      for (const auto& p : l.points) add(project(cam, p), 0.0);
    for (const auto& d : f.scene.discs) add(project(cam, d.centre), std::isfinite(d.radius) ? d.radius : 0.0);
  }
  if (!(ulo <= uhi)) ulo = vlo = -1.0, uhi = vhi = 1.0;  // nothing finite: a unit view
  const double du = std::max(uhi - ulo, 1e-9), dv = std::max(vhi - vlo, 1e-9);
  Viewport vp;
  vp.width = width;
  const double inner = width - 2.0 * kMargin;
  const int drawing = static_cast<int>(std::lround(std::clamp(inner * dv / du, width / 3.0, 2.0 * width)));
  vp.height = drawing + 2 * kMargin + kLabelHeight;
  vp.scale = std::min(inner / du, drawing / dv);
  // centre the bounds in the drawing area
  vp.u0 = 0.5 * (ulo + uhi) - 0.5 * inner / vp.scale;
  vp.v0 = 0.5 * (vlo + vhi) - 0.5 * drawing / vp.scale;
  vp.left = kMargin;
  vp.bottom = vp.height - kMargin;
  return vp;
}

}  // namespace dsb::render
