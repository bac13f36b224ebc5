#include "render/encode.hpp"

#include <memory>
#include <stdexcept>

#include <gd.h>

#include "common/error.hpp"
#include "render/camera.hpp"
#include "render/draw.hpp"
#include "render/palette.hpp"

namespace dsb::render {

namespace {

struct ImageDeleter {
  void operator()(gdImage* im) const { gdImageDestroy(im); }
};
using Image = std::unique_ptr<gdImage, ImageDeleter>;

// a palette image with the fixed palette (background first, so it fills the image)
Image blank(int width, int height, Palette& pal) {
  Image im(gdImageCreate(width, height));
  if (!im)
    throw std::runtime_error("render: libgd could not create a " + std::to_string(width) + " x " +
                             std::to_string(height) + " image");
  pal = allocate_palette(im.get());
  return im;
}

// takes a buffer gd allocated and appends it to out
void append(std::vector<unsigned char>& out, void* data, int size) {
  if (!data) throw std::runtime_error("render: libgd could not encode the image");
  const auto* bytes = static_cast<const unsigned char*>(data);
  out.insert(out.end(), bytes, bytes + size);
  gdFree(data);
}

}  // namespace

void RenderOptions::validate() const {
  if (width < 64 || width > 2000) throw ConfigError("render", "width", "must be from 64 to 2000 pixels");
  if (gif_delay_cs < 1 || gif_delay_cs > 1000) throw ConfigError("render", "gif_delay_cs", "must be from 1 to 1000");
}

bool format_of_path(const std::string& path, ImageFormat& format) {
  auto ends_with = [&](const char* ext) {
    const std::string e(ext);
    return path.size() > e.size() && path.compare(path.size() - e.size(), e.size(), e) == 0;
  };
  if (ends_with(".png"))
    format = ImageFormat::png;
  else if (ends_with(".gif"))
    format = ImageFormat::gif;
  else
    return false;
  return true;
}

std::vector<unsigned char> encode_frames(const std::vector<Frame>& frames, const RenderOptions& options) {
  options.validate();
  const Viewport vp = fit(frames, options.width);
  const int n = static_cast<int>(frames.size());
  std::vector<unsigned char> out;
  Palette pal;
  int size = 0;
  if (options.format == ImageFormat::png) {
    // one image, the panels side by side
    Image im = blank(vp.width * n, vp.height, pal);
    for (int i = 0; i < n; ++i) draw_frame(im.get(), pal, vp, i * vp.width, frames[i]);
    void* png = gdImagePngPtrEx(im.get(), &size, 9);
    append(out, png, size);
    return out;
  }
  // GIF: a global palette (the first frame's, the same indices in every frame), looping forever
  std::vector<Image> images;
  for (int i = 0; i < n; ++i) {
    images.push_back(blank(vp.width, vp.height, pal));
    draw_frame(images.back().get(), pal, vp, 0, frames[i]);
  }
  // (each call sets size before its buffer is appended)
  void* part = gdImageGifAnimBeginPtr(images[0].get(), &size, 1, 0);
  append(out, part, size);
  for (int i = 0; i < n; ++i) {
    part = gdImageGifAnimAddPtr(images[i].get(), &size, 0, 0, 0, options.gif_delay_cs, gdDisposalNone, nullptr);
    append(out, part, size);
  }
  part = gdImageGifAnimEndPtr(&size);
  append(out, part, size);
  return out;
}

}  // namespace dsb::render
