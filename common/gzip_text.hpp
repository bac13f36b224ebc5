#pragma once
// Text in and out of gzip (zlib, Debian's zlib1g-dev): the target grids' files
// (envs/mpm/target_grid.hpp) and the published archive's (harness/store/archive_reader.hpp). gzip()
// writes the same bytes for the same text (level 9, a header without name or time stamp).
#include <cstddef>
#include <stdexcept>
#include <string>

namespace dsb {

// what is wrong with a gzip stream, as a phrase ("truncated gzip stream"); callers add the file
struct GzipError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

// the gzip stream of `text` (GzipError when it is over 4 GiB)
std::string gzip(const std::string& text);

// the text of a gzip stream of one member: GzipError when it is empty, damaged, truncated, has
// bytes after its end, or decompresses to more than max_bytes
std::string gunzip(const std::string& raw, std::size_t max_bytes = std::size_t{1} << 30);

}  // namespace dsb
