#include "render/draw.hpp"

#include <algorithm>
#include <cmath>
#include <string>

#include <gdfonts.h>
#include <fmt/format.h>

namespace dsb::render {

namespace {

// a pixel coordinate, rounded; far-away values are clamped (gd clips the rest)
int pixel(double v) { return static_cast<int>(std::lround(std::clamp(v, -1e6, 1e6))); }

bool finite(const Projected& p) { return std::isfinite(p.u) && std::isfinite(p.v); }

// line width in pixels by role: what moves is drawn heavier
int thickness(Role role) { return role == Role::state || role == Role::tool ? 2 : 1; }

void draw_line(gdImagePtr im, const Palette& pal, const Viewport& vp, int dx, Camera cam, const Polyline& l) {
  gdImageSetThickness(im, thickness(l.role));
  const int colour = pal.of(l.role);
  const std::size_t n = l.points.size();
  const std::size_t segments = l.closed && n > 2 ? n : n - 1;
  for (std::size_t i = 0; n >= 2 && i < segments; ++i) {
    const Projected a = project(cam, l.points[i]), b = project(cam, l.points[(i + 1) % n]);
    if (!finite(a) || !finite(b)) continue;
    gdImageLine(im, dx + pixel(vp.px(a)), pixel(vp.py(a)), dx + pixel(vp.px(b)), pixel(vp.py(b)), colour);
  }
  gdImageSetThickness(im, 1);
}

void draw_cloud(gdImagePtr im, const Palette& pal, const Viewport& vp, int dx, Camera cam, const PointCloud& c) {
  const int colour = pal.of(c.role, c.faint);
  // faint and target clouds one pixel per point (a target shell drawn over the state stays
  // see-through), the others 2 x 2
  const int size = c.faint || c.role == Role::target ? 1 : 2;
  for (const auto& p : c.points) {
    const Projected q = project(cam, p);
    if (!finite(q)) continue;
    const int x = dx + pixel(vp.px(q)), y = pixel(vp.py(q));
    if (size == 1)
      gdImageSetPixel(im, x, y, colour);
    else
      gdImageFilledRectangle(im, x, y - 1, x + 1, y, colour);
  }
}

void draw_disc(gdImagePtr im, const Palette& pal, const Viewport& vp, int dx, Camera cam, const Disc& d) {
  const Projected c = project(cam, d.centre);
  if (!finite(c)) return;
  // at least 5 pixels across, so a small ball stays visible
  const int diameter = std::max(5, pixel(2.0 * d.radius * vp.scale));
  const int x = dx + pixel(vp.px(c)), y = pixel(vp.py(c));
  if (d.filled) {
    gdImageFilledEllipse(im, x, y, diameter, diameter, pal.of(d.role));
  } else {
    gdImageSetThickness(im, 2);
    gdImageEllipse(im, x, y, diameter, diameter, pal.of(d.role));
    gdImageSetThickness(im, 1);
  }
}

}  // namespace

void draw_frame(gdImagePtr im, const Palette& pal, const Viewport& vp, int x_offset, const Frame& frame) {
  const Scene& sc = frame.scene;
  const Camera cam = sc.camera;
  gdImageSetClip(im, x_offset, 0, x_offset + vp.width - 1, vp.height - 1);
  // panel border and time label
  gdImageRectangle(im, x_offset, 0, x_offset + vp.width - 1, vp.height - 1, pal.frame);
  const std::string label = fmt::format("t = {:.3f} s", frame.time);
  gdImageString(im, gdFontGetSmall(), x_offset + kMargin, 2,
                reinterpret_cast<unsigned char*>(const_cast<char*>(label.c_str())), pal.text);
  // faint clouds, then fixed lines, then the other clouds
  for (const auto& c : sc.clouds)
    if (c.faint) draw_cloud(im, pal, vp, x_offset, cam, c);
  for (const auto& l : sc.lines)
    if (l.role == Role::fixed) draw_line(im, pal, vp, x_offset, cam, l);
  for (const auto& c : sc.clouds)
    if (!c.faint) draw_cloud(im, pal, vp, x_offset, cam, c);
  // the other lines, role by role, and the discs
  for (const Role r : {Role::trace, Role::medium, Role::tool, Role::target, Role::state})
    for (const auto& l : sc.lines)
      if (l.role == r) draw_line(im, pal, vp, x_offset, cam, l);
  for (const Role r : {Role::fixed, Role::trace, Role::medium, Role::target, Role::tool, Role::state})
    for (const auto& d : sc.discs)
      if (d.role == r) draw_disc(im, pal, vp, x_offset, cam, d);
  gdImageSetClip(im, 0, 0, gdImageSX(im) - 1, gdImageSY(im) - 1);
}

}  // namespace dsb::render
