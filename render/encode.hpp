#pragma once
// Frames to image bytes: a PNG strip of the frames side by side, or an animated GIF of them.
#include <string>
#include <vector>

#include "envs/core/scene.hpp"

namespace dsb::render {

enum class ImageFormat { png, gif };

struct RenderOptions {
  int width = 320;  // pixels per frame panel, 64 to 2000
  ImageFormat format = ImageFormat::png;
  int gif_delay_cs = 60;  // GIF: hundredths of a second per frame, 1 to 1000
  void validate() const;  // throws ConfigError naming the field
};

// png or gif from a file name's extension (case-sensitive .png, .gif); false for anything else
bool format_of_path(const std::string& path, ImageFormat& format);

// The image of the frames (at least one): every panel one viewport (camera.hpp fit), palette
// colours, no timestamps or other varying metadata, so the same frames give the same bytes.
std::vector<unsigned char> encode_frames(const std::vector<Frame>& frames, const RenderOptions& options);

}  // namespace dsb::render
