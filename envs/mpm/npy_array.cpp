#include "envs/mpm/npy_array.hpp"

#include <sys/stat.h>

#include <bit>
#include <cerrno>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <limits>
#include <map>
#include <stdexcept>
#include <string_view>

#include "common/error.hpp"
#include "common/regular_file.hpp"
#include "common/shown_value.hpp"

namespace dsb::mpm {

static_assert(std::endian::native == std::endian::little, "the .npy reader copies little-endian values as they are");

namespace {

constexpr std::size_t kMaxValues = std::size_t{1} << 27;
constexpr std::size_t kMaxHeaderBytes = std::size_t{1} << 20;  // np.save writes about a hundred

// A value of the header's Python literal: only the kinds a .npy header holds.
struct PyValue {
  enum class Kind { string, boolean, none, integer, tuple, list } kind = Kind::none;
  std::string text;            // string
  bool flag = false;           // boolean
  std::uint64_t number = 0;    // integer (non-negative, as shapes are)
  std::vector<PyValue> items;  // tuple or list
};

// Recursive descent over the header text, by Python's literal rules as numpy reads the header
// (ast.literal_eval), a subset of what they allow: what we accept, numpy accepts. In particular
// `(64)` is the integer 64, not a tuple (a one-value tuple needs its comma: `(64,)`); `[64]` is a
// list; a nonzero integer has no leading zero (`064` is a syntax error in Python 3; `00` is 0);
// Python 2's long suffix (`64L`) only in format versions 1.0 and 2.0, whose headers numpy reads
// again with the suffixes dropped (version 3.0 has no such fallback). The header starts with its
// '{' as np.save writes it (Python before 3.10 refuses leading spaces). std::runtime_error says
// what is wrong where.
class HeaderParser {
 public:
  HeaderParser(std::string_view text, bool long_suffix) : t_(text), long_suffix_(long_suffix) {}

  // the whole header: one dict of string keys, then only spaces and the newline
  std::map<std::string, PyValue> dict() {
    std::map<std::string, PyValue> d;
    if (t_.empty() || t_[0] != '{') fail("'{' expected first");
    expect('{');
    while (!eat('}')) {
      const PyValue key = value();
      if (key.kind != PyValue::Kind::string) fail("a key that is not a string");
      expect(':');
      if (!d.emplace(key.text, value()).second) fail("key '" + shown_value(key.text) + "' twice");
      if (!eat(',')) {
        expect('}');
        break;
      }
    }
    space();
    if (pos_ != t_.size()) fail("text after the dict");
    return d;
  }

 private:
  [[noreturn]] void fail(const std::string& what) const {
    throw std::runtime_error(what + " at character " + std::to_string(pos_));
  }
  void space() {
    while (pos_ < t_.size() && (t_[pos_] == ' ' || t_[pos_] == '\t' || t_[pos_] == '\n' || t_[pos_] == '\r')) ++pos_;
  }
  bool eat(char c) {
    space();
    if (pos_ < t_.size() && t_[pos_] == c) {
      ++pos_;
      return true;
    }
    return false;
  }
  void expect(char c) {
    if (!eat(c)) fail(std::string("'") + c + "' expected");
  }
  bool word(std::string_view w) {
    space();
    if (t_.substr(pos_, w.size()) != w) return false;
    pos_ += w.size();
    return true;
  }

  PyValue value() {
    space();
    if (pos_ >= t_.size()) fail("a value expected");
    PyValue v;
    const char c = t_[pos_];
    if (c == '\'' || c == '"') {
      ++pos_;
      const std::size_t end = t_.find(c, pos_);
      if (end == std::string_view::npos) fail("an unterminated string");
      v.kind = PyValue::Kind::string;
      v.text = std::string(t_.substr(pos_, end - pos_));
      if (v.text.find('\\') != std::string::npos) fail("an escape in a string");
      pos_ = end + 1;
    } else if (c == '(' || c == '[') {
      const char close = c == '(' ? ')' : ']';
      ++pos_;
      v.kind = c == '(' ? PyValue::Kind::tuple : PyValue::Kind::list;
      bool comma = false;  // a comma after a value: (64,) is a tuple, (64) the integer 64
      while (!eat(close)) {
        v.items.push_back(value());
        comma = eat(',');
        if (!comma) {
          expect(close);
          break;
        }
      }
      if (v.kind == PyValue::Kind::tuple && v.items.size() == 1 && !comma) return v.items.front();
    } else if (c >= '0' && c <= '9') {
      v.kind = PyValue::Kind::integer;
      const std::size_t start = pos_;
      bool nonzero = false;
      while (pos_ < t_.size() && t_[pos_] >= '0' && t_[pos_] <= '9') {
        const std::uint64_t digit = static_cast<std::uint64_t>(t_[pos_] - '0');
        if (v.number > (std::numeric_limits<std::uint64_t>::max() - digit) / 10) fail("an integer too large");
        v.number = v.number * 10 + digit;
        nonzero = nonzero || digit != 0;
        ++pos_;
      }
      if (t_[start] == '0' && nonzero)
        fail("the integer '" + std::string(t_.substr(start, pos_ - start)) +
             "' with a leading zero, which Python's literals (and so numpy) refuse");
      if (pos_ < t_.size() && t_[pos_] == 'L') {  // Python 2's long suffix, as old numpy wrote shapes
        if (!long_suffix_) fail("Python 2's long suffix 'L', which numpy reads in format versions 1.0 and 2.0 only");
        ++pos_;
      }
    } else if (word("True")) {
      v.kind = PyValue::Kind::boolean;
      v.flag = true;
    } else if (word("False")) {
      v.kind = PyValue::Kind::boolean;
    } else if (word("None")) {
      v.kind = PyValue::Kind::none;
    } else {
      fail("an unexpected '" + shown_value(std::string_view(&t_[pos_], 1)) + "'");
    }
    return v;
  }

  std::string_view t_;
  bool long_suffix_;
  std::size_t pos_ = 0;
};

[[noreturn]] void refuse(const std::string& path, const std::string& problem) {
  throw UsageError(shown_value(path) + ": " + problem);
}

std::uint64_t little_endian(const unsigned char* b, int bytes) {
  std::uint64_t v = 0;
  for (int i = bytes - 1; i >= 0; --i) v = v << 8 | b[i];
  return v;
}

// the header text for a message: one line (control characters escaped; the padding and the
// newline that end it dropped), at most 120 characters of it
std::string shown(std::string_view header) {
  std::string_view s = header.substr(0, 120);
  while (!s.empty() && (s.back() == ' ' || s.back() == '\n')) s.remove_suffix(1);
  return shown_value(s) + (header.size() > 120 ? " ..." : "");
}

}  // namespace

std::string npy_shape_text(const std::vector<std::size_t>& shape) {
  std::string s = "(";
  for (std::size_t i = 0; i < shape.size(); ++i) s += (i ? ", " : "") + std::to_string(shape[i]);
  return s + (shape.size() == 1 ? ",)" : ")");
}

NpyArray read_npy(const std::string& path) {
  // opened without blocking and checked as a regular file (a FIFO would wait for a writer forever),
  // then read through the open descriptor, so the file checked is the file read
  RegularFile checked;
  if (const std::string problem = open_regular_problem(path, checked); !problem.empty()) refuse(path, problem);
  std::ifstream in("/proc/self/fd/" + std::to_string(checked.fd()), std::ios::binary);
  if (!in) refuse(path, std::string("cannot open: ") + std::strerror(errno));
  struct stat st {};
  if (::fstat(checked.fd(), &st) != 0) refuse(path, std::string("cannot read its size: ") + std::strerror(errno));
  const auto file_size = static_cast<std::uintmax_t>(st.st_size);

  unsigned char lead[12] = {};
  in.read(reinterpret_cast<char*>(lead), 8);
  static const unsigned char kMagic[6] = {0x93, 'N', 'U', 'M', 'P', 'Y'};
  if (in.gcount() < 6 || std::memcmp(lead, kMagic, 6) != 0)
    refuse(path, "not a .npy file (it does not start with NumPy's magic bytes \\x93NUMPY)");
  if (in.gcount() < 8) refuse(path, "truncated: the file ends inside the version bytes");
  const int major = lead[6], minor = lead[7];
  const std::string version = std::to_string(major) + "." + std::to_string(minor);
  if (!((major == 1 || major == 2 || major == 3) && minor == 0))
    refuse(path, "unsupported .npy version " + version + " (versions 1.0, 2.0 and 3.0 are read)");
  const int length_bytes = major == 1 ? 2 : 4;
  in.read(reinterpret_cast<char*>(lead + 8), length_bytes);
  if (in.gcount() < length_bytes) refuse(path, "truncated: the file ends inside the header length");
  const std::uint64_t header_bytes = little_endian(lead + 8, length_bytes);
  if (header_bytes > kMaxHeaderBytes) refuse(path, "header length " + std::to_string(header_bytes) + " is implausible");
  std::string header(static_cast<std::size_t>(header_bytes), '\0');
  in.read(header.data(), static_cast<std::streamsize>(header.size()));
  if (static_cast<std::uint64_t>(in.gcount()) < header_bytes)
    refuse(path,
           "truncated header: " + std::to_string(in.gcount()) + " of its " + std::to_string(header_bytes) + " bytes");
  for (char c : header)
    if (c == '\0') refuse(path, "malformed header: it holds a zero byte");

  std::map<std::string, PyValue> fields;
  try {
    fields = HeaderParser(header, major <= 2).dict();
  } catch (const std::runtime_error& e) {
    refuse(path, std::string("malformed header (") + e.what() + "): " + shown(header));
  }
  for (const char* key : {"descr", "fortran_order", "shape"})
    if (!fields.count(key)) refuse(path, std::string("malformed header: no '") + key + "' in " + shown(header));
  if (fields.size() != 3)
    refuse(path, "malformed header: keys other than descr, fortran_order and shape in " + shown(header));

  NpyArray a;
  const PyValue& descr = fields.at("descr");
  if (descr.kind != PyValue::Kind::string)
    refuse(path, "dtype is a structured type; only float64 '<f8' and float32 '<f4' are read");
  a.dtype = descr.text;
  if (a.dtype != "<f8" && a.dtype != "<f4")
    refuse(path,
           "dtype '" + shown_value(a.dtype) + "' is not read; only float64 '<f8' and float32 '<f4' (little-endian)");
  const PyValue& order = fields.at("fortran_order");
  if (order.kind != PyValue::Kind::boolean) refuse(path, "malformed header: fortran_order is not True or False");
  if (order.flag)
    refuse(path,
           "Fortran order (fortran_order: True) is not read; save the array in C order, e.g. "
           "np.save(path, np.ascontiguousarray(a))");
  const PyValue& shape = fields.at("shape");
  if (shape.kind != PyValue::Kind::tuple) refuse(path, "malformed header: shape is not a tuple in " + shown(header));
  std::size_t count = 1;
  for (const PyValue& d : shape.items) {
    if (d.kind != PyValue::Kind::integer) refuse(path, "malformed header: shape holds a value that is not an integer");
    if (d.number > kMaxValues || (d.number > 0 && count > kMaxValues / d.number))
      refuse(path, "shape holds more than 2^27 values (" + shown(header) + ")");
    a.shape.push_back(static_cast<std::size_t>(d.number));
    count *= static_cast<std::size_t>(d.number);
  }

  const std::size_t item = a.dtype == "<f8" ? 8 : 4;
  const std::uint64_t data_start = 8 + static_cast<std::uint64_t>(length_bytes) + header_bytes;
  const std::uint64_t have = file_size > data_start ? file_size - data_start : 0;
  const std::uint64_t need = static_cast<std::uint64_t>(count) * item;
  if (have < need)
    refuse(path,
           "truncated data: " + std::to_string(have) + " bytes, shape " + npy_shape_text(a.shape) + " of '" + a.dtype +
               "' needs " + std::to_string(need));
  if (have > need)
    refuse(path,
           std::to_string(have - need) + " bytes after the data of shape " + npy_shape_text(a.shape) + " of '" +
               a.dtype + "'");
  std::vector<unsigned char> raw(static_cast<std::size_t>(need));
  in.read(reinterpret_cast<char*>(raw.data()), static_cast<std::streamsize>(raw.size()));
  if (static_cast<std::uint64_t>(in.gcount()) < need) refuse(path, "truncated data: the read ended early");
  a.values.resize(count);
  for (std::size_t i = 0; i < count; ++i) {
    if (item == 8) {
      std::memcpy(&a.values[i], raw.data() + 8 * i, 8);
    } else {
      float f = 0.0f;
      std::memcpy(&f, raw.data() + 4 * i, 4);
      a.values[i] = static_cast<double>(f);
    }
  }
  return a;
}

}  // namespace dsb::mpm
