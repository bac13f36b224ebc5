#include "common/gzip_text.hpp"

#include <zlib.h>

#include <climits>
#include <new>

namespace dsb {

std::string gzip(const std::string& text) {
  if (text.size() > UINT_MAX) throw GzipError("text too large to compress");
  z_stream zs{};
  // level 9, windowBits 15 + 16 = gzip wrapper with a default header: no name, mtime 0
  if (deflateInit2(&zs, 9, Z_DEFLATED, 31, 8, Z_DEFAULT_STRATEGY) != Z_OK) throw std::bad_alloc();
  std::string out(deflateBound(&zs, static_cast<uLong>(text.size())), '\0');
  zs.next_in = reinterpret_cast<Bytef*>(const_cast<char*>(text.data()));
  zs.avail_in = static_cast<uInt>(text.size());
  zs.next_out = reinterpret_cast<Bytef*>(out.data());
  zs.avail_out = static_cast<uInt>(out.size());
  const int ret = deflate(&zs, Z_FINISH);
  out.resize(zs.total_out);
  deflateEnd(&zs);
  if (ret != Z_STREAM_END) throw GzipError("zlib deflate failed");
  return out;
}

std::string gunzip(const std::string& raw, std::size_t max_bytes) {
  if (raw.empty()) throw GzipError("empty file (not a gzip stream)");
  if (raw.size() > UINT_MAX) throw GzipError("file too large");
  z_stream zs{};
  if (inflateInit2(&zs, 31) != Z_OK) throw std::bad_alloc();  // gzip wrapper only
  struct End {
    z_stream* z;
    ~End() { inflateEnd(z); }
  } end{&zs};
  zs.next_in = reinterpret_cast<Bytef*>(const_cast<char*>(raw.data()));
  zs.avail_in = static_cast<uInt>(raw.size());
  std::string text;
  for (;;) {
    char buf[1 << 16];
    zs.next_out = reinterpret_cast<Bytef*>(buf);
    zs.avail_out = sizeof buf;
    const int ret = inflate(&zs, Z_NO_FLUSH);
    text.append(buf, sizeof buf - zs.avail_out);
    if (text.size() > max_bytes)
      throw GzipError("decompresses to more than " +
                      (max_bytes % (std::size_t{1} << 30) == 0 ? std::to_string(max_bytes >> 30) + " GiB"
                                                               : std::to_string(max_bytes) + " bytes"));
    if (ret == Z_STREAM_END) break;
    if (ret == Z_OK) continue;
    if (ret == Z_BUF_ERROR) throw GzipError("truncated gzip stream");
    if (ret == Z_MEM_ERROR) throw std::bad_alloc();
    throw GzipError(std::string("not a valid gzip stream (") + (zs.msg ? zs.msg : "zlib error") + ")");
  }
  if (zs.avail_in != 0) throw GzipError("data after the end of the gzip stream");
  return text;
}

}  // namespace dsb
