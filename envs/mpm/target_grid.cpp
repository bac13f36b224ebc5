#include "envs/mpm/target_grid.hpp"

#include <charconv>
#include <climits>
#include <cmath>
#include <cstdint>
#include <fstream>
#include <iterator>
#include <limits>
#include <new>
#include <stdexcept>
#include <string_view>

#include "common/error.hpp"
#include "common/gzip_text.hpp"
#include "common/number_text.hpp"
#include "common/regular_file.hpp"

namespace dsb::mpm {

namespace {

constexpr int kMaxAxis = 1 << 16;                        // nodes per axis (distance_to_mass, files)
constexpr std::size_t kMaxNodes = std::size_t{1} << 24;  // nodes in all (files)
constexpr std::size_t kMaxText = std::size_t{1} << 30;   // decompressed bytes (files)

void check_values(const NodeGrid& g, const char* who) {
  for (int a = 0; a < 3; ++a)
    if (g.n[a] < 0) throw std::invalid_argument(std::string(who) + ": negative grid extent");
  if (g.values.size() != g.size())
    throw std::invalid_argument(std::string(who) + ": values.size() does not match the grid shape");
}

// ---- exact squared distance transform --------------------------------------------------------
//
// Along one line of L nodes, with f[p] >= 0 the squared distance (node units, an integer) already
// known at node p and f[p] < 0 for "no target reached yet", the transform is
//   d[q] = min over p with f[p] >= 0 of (q - p)^2 + f[p],
// the lower envelope of the parabolas y = (x - p)^2 + f[p]. With h(p) = f[p] + p^2 the parabolas
// of p < r meet at x(p, r) = (h(r) - h(p)) / (2 (r - p)); left of it p's is lower, right of it r's.
// Scanning p upward, the envelope is a stack v of parabolas whose regions are ordered by these
// meeting points; a new parabola q removes the top a (above c) while x(a, q) <= x(c, a), i.e. a is
// lowest nowhere. Ties remove a, which changes no minimum. The bottom parabola is never removed
// (its region starts at -infinity). Then d[q] reads the parabola whose region holds q.
// Every comparison of meeting points is done on integers, cross-multiplied by the positive
// denominators: with at most 2^16 nodes per axis, |h| < 3 * 2^32 and products stay below 2^51.
// Applied along z, then y, then x (min over a box of sums of per-axis squares separates), the
// result is the exact squared Euclidean distance to the nearest target node.

void envelope_1d(const std::int64_t* f, std::int64_t* d, int len, std::vector<int>& v) {
  auto h = [f](std::int64_t p) { return f[p] + p * p; };
  v.clear();
  for (int q = 0; q < len; ++q) {
    if (f[q] < 0) continue;
    while (v.size() >= 2) {
      const std::int64_t a = v.back(), c = v[v.size() - 2];
      // x(a, q) <= x(c, a)  <=>  (h(q) - h(a)) (a - c) <= (h(a) - h(c)) (q - a)
      if ((h(q) - h(a)) * (a - c) <= (h(a) - h(c)) * (q - a))
        v.pop_back();
      else
        break;
    }
    v.push_back(q);
  }
  if (v.empty()) {
    for (int q = 0; q < len; ++q) d[q] = -1;
    return;
  }
  std::size_t k = 0;
  for (std::int64_t q = 0; q < len; ++q) {
    // advance while the next parabola's region starts left of q: x(v[k], v[k+1]) < q
    while (k + 1 < v.size() && h(v[k + 1]) - h(v[k]) < 2 * q * (v[k + 1] - v[k])) ++k;
    const std::int64_t p = v[k];
    d[q] = (q - p) * (q - p) + f[p];
  }
}

// the 1-D transform along `axis` of every line of g (shape n)
void transform_axis(std::vector<std::int64_t>& g, const std::array<int, 3>& n, int axis) {
  const int len = n[axis];
  if (len == 0) return;
  const std::array<std::size_t, 3> stride{static_cast<std::size_t>(n[1]) * n[2], static_cast<std::size_t>(n[2]), 1};
  std::array<int, 3> lines = n;
  lines[axis] = 1;
  std::vector<std::int64_t> f(len), d(len);
  std::vector<int> v;
  v.reserve(len);
  for (int i = 0; i < lines[0]; ++i)
    for (int j = 0; j < lines[1]; ++j)
      for (int k = 0; k < lines[2]; ++k) {
        const std::size_t base = i * stride[0] + j * stride[1] + k;
        for (int q = 0; q < len; ++q) f[q] = g[base + q * stride[axis]];
        envelope_1d(f.data(), d.data(), len, v);
        for (int q = 0; q < len; ++q) g[base + q * stride[axis]] = d[q];
      }
}

// ---- files -------------------------------------------------------------------------------------

[[noreturn]] void fail(const std::string& path, const std::string& what) {
  throw UsageError("target grid file '" + path + "': " + what);
}

// a field of the file quoted in a message: printable, one line, at most 40 characters
std::string quote(std::string_view s) {
  std::string out = "'";
  for (std::size_t i = 0; i < s.size() && i < 40; ++i) out += (s[i] >= 0x20 && s[i] < 0x7f) ? s[i] : '?';
  if (s.size() > 40) out += "...";
  return out + "'";
}

std::string node_str(long long i, long long j, long long k) {
  std::string s(1, '(');  // appended piece by piece: GCC 12's -Wrestrict misfires on "(" + string
  s += std::to_string(i);
  s += ", ";
  s += std::to_string(j);
  s += ", ";
  s += std::to_string(k);
  s += ')';
  return s;
}

void append_int(std::string& s, long long v) {
  char buf[24];
  s.append(buf, std::to_chars(buf, buf + sizeof buf, v).ptr);
}

bool parse_int(std::string_view s, long long lo, long long hi, long long& out) {
  const auto [p, ec] = std::from_chars(s.data(), s.data() + s.size(), out);
  return ec == std::errc() && p == s.data() + s.size() && out >= lo && out <= hi;
}

bool parse_double(std::string_view s, double& out) {
  const auto [p, ec] = std::from_chars(s.data(), s.data() + s.size(), out, std::chars_format::general);
  return ec == std::errc() && p == s.data() + s.size() && std::isfinite(out);
}

// fields separated by single spaces; false on an empty field (double, leading or trailing space)
bool split(std::string_view line, std::vector<std::string_view>& fields) {
  fields.clear();
  std::size_t start = 0;
  for (;;) {
    const std::size_t sp = line.find(' ', start);
    const std::string_view field = line.substr(start, sp == std::string_view::npos ? sp : sp - start);
    if (field.empty()) return false;
    fields.push_back(field);
    if (sp == std::string_view::npos) return true;
    start = sp + 1;
  }
}

std::string gzip(const std::string& path, const std::string& text) {
  try {
    return dsb::gzip(text);
  } catch (const GzipError& e) {
    fail(path, e.what());
  }
}

std::string gunzip(const std::string& path, const std::string& raw) {
  try {
    return dsb::gunzip(raw, kMaxText);
  } catch (const GzipError& e) {
    fail(path, e.what());
  }
}

}  // namespace

// ---- NodeGrid ----------------------------------------------------------------------------------

NodeGrid NodeGrid::zeros(const std::array<int, 3>& n) {
  for (int a = 0; a < 3; ++a)
    if (n[a] < 0) throw std::invalid_argument("NodeGrid::zeros: negative grid extent");
  NodeGrid g{n, {}};
  g.values.assign(g.size(), 0.0);
  return g;
}

std::size_t NodeGrid::size() const {
  if (n[0] <= 0 || n[1] <= 0 || n[2] <= 0) return 0;
  return static_cast<std::size_t>(n[0]) * n[1] * n[2];
}

double NodeGrid::sum() const {
  double s = 0.0;
  for (double v : values) s += v;
  return s;
}

double NodeGrid::max() const {
  double m = -std::numeric_limits<double>::infinity();
  for (double v : values) m = v > m ? v : m;
  return m;
}

// ---- distance and IoU --------------------------------------------------------------------------

std::vector<double> distance_to_mass(const NodeGrid& target, double threshold, double dx, double empty_value) {
  check_values(target, "distance_to_mass");
  for (int a = 0; a < 3; ++a)
    if (target.n[a] > kMaxAxis) throw std::invalid_argument("distance_to_mass: more than 65536 nodes on an axis");
  std::vector<std::int64_t> sq(target.values.size());
  bool any = false;
  for (std::size_t i = 0; i < sq.size(); ++i) {
    const bool in = target.values[i] > threshold;
    sq[i] = in ? 0 : -1;
    any = any || in;
  }
  std::vector<double> out(sq.size(), empty_value);
  if (!any) return out;
  transform_axis(sq, target.n, 2);
  transform_axis(sq, target.n, 1);
  transform_axis(sq, target.n, 0);
  // sq[i] <= 3 * 65535^2 < 2^53: exact as a double; sqrt is correctly rounded
  for (std::size_t i = 0; i < sq.size(); ++i) out[i] = std::sqrt(static_cast<double>(sq[i])) * dx;
  return out;
}

double soft_iou(const NodeGrid& mass, const NodeGrid& target) {
  check_values(mass, "soft_iou");
  check_values(target, "soft_iou");
  if (mass.n != target.n) throw std::invalid_argument("soft_iou: grids of different shapes");
  const double mm = mass.max(), mt = target.max();
  if (!(mm > 0.0) || !(mt > 0.0)) return 0.0;
  // S = sum (m / max m)(t / max t), A = sum m / max m, B = sum t / max t: the normalised values
  // (no overflow of max m * max t; a binary grid's values normalise to exactly 0 and 1)
  double s = 0.0, a = 0.0, b = 0.0;
  for (std::size_t i = 0; i < mass.values.size(); ++i) {
    const double u = mass.values[i] / mm, w = target.values[i] / mt;
    s += u * w;
    a += u;
    b += w;
  }
  const double den = a + b - s;
  return den > 0.0 ? s / den : 0.0;
}

// ---- files -------------------------------------------------------------------------------------

void write_grid_gz(const std::string& path, const NodeGrid& g) {
  check_values(g, "write_grid_gz");
  std::size_t count = 0;
  for (std::size_t i = 0; i < g.values.size(); ++i) {
    const double v = g.values[i];
    if (!std::isfinite(v)) {
      const auto k = static_cast<long long>(i % g.n[2]), j = static_cast<long long>(i / g.n[2] % g.n[1]),
                 ii = static_cast<long long>(i / g.n[2] / g.n[1]);
      fail(path, "cannot write the non-finite value at node " + node_str(ii, j, k));
    }
    count += (v != 0.0 || std::signbit(v));
  }
  std::string text = "dsb-node-grid 1";
  for (int a = 0; a < 3; ++a) {
    text += ' ';
    append_int(text, g.n[a]);
  }
  text += ' ';
  append_int(text, static_cast<long long>(count));
  text += '\n';
  for (int i = 0; i < g.n[0]; ++i)
    for (int j = 0; j < g.n[1]; ++j)
      for (int k = 0; k < g.n[2]; ++k) {
        const double v = g.at(i, j, k);
        if (v == 0.0 && !std::signbit(v)) continue;
        append_int(text, i);
        text += ' ';
        append_int(text, j);
        text += ' ';
        append_int(text, k);
        text += ' ';
        text += exact_number_text(v);
        text += '\n';
      }
  const std::string bytes = gzip(path, text);
  std::ofstream file(path, std::ios::binary | std::ios::trunc);
  if (!file) fail(path, "cannot open for writing");
  file.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
  file.close();
  if (!file) fail(path, "write failed");
}

NodeGrid read_grid_gz(const std::string& path) {
  // never blocks on a FIFO or device: opened without blocking and checked as a regular file
  const std::string raw = read_regular_file("target grid file", path);
  const std::string text = gunzip(path, raw);

  std::size_t pos = 0;
  long long line_no = 0;
  std::string_view line;
  auto next_line = [&]() {
    if (pos == text.size()) return false;
    ++line_no;
    const std::size_t end = text.find('\n', pos);
    if (end == std::string::npos) fail(path, "line " + std::to_string(line_no) + ": no end of line (truncated)");
    line = std::string_view(text).substr(pos, end - pos);
    pos = end + 1;
    return true;
  };
  auto at_line = [&](const std::string& what) { return "line " + std::to_string(line_no) + ": " + what; };

  std::vector<std::string_view> f;
  if (!next_line()) fail(path, "no header (empty text)");
  const bool fields_ok = split(line, f);
  if (f.empty() || f[0] != "dsb-node-grid") fail(path, "not a dsb-node-grid file (header " + quote(line) + ")");
  if (f.size() < 2 || f[1] != "1")
    fail(path, "unsupported dsb-node-grid version " + (f.size() < 2 ? std::string("(none)") : quote(f[1])));
  long long n[3], count;
  if (!fields_ok || f.size() != 6 || !parse_int(f[2], 0, kMaxAxis, n[0]) || !parse_int(f[3], 0, kMaxAxis, n[1]) ||
      !parse_int(f[4], 0, kMaxAxis, n[2]) || !parse_int(f[5], 0, LLONG_MAX, count))
    fail(path, "bad header " + quote(line) + ", expected 'dsb-node-grid 1 n0 n1 n2 count' (n0..n2 <= 65536)");
  NodeGrid g{{static_cast<int>(n[0]), static_cast<int>(n[1]), static_cast<int>(n[2])}, {}};
  if (g.size() > kMaxNodes) fail(path, "grid of " + std::to_string(g.size()) + " nodes exceeds 2^24 nodes");
  if (static_cast<unsigned long long>(count) > g.size())
    fail(path, "header count " + std::to_string(count) + " exceeds the " + std::to_string(g.size()) + " nodes");
  g.values.assign(g.size(), 0.0);
  std::vector<bool> seen(g.size(), false);

  for (long long e = 0; e < count; ++e) {
    if (!next_line())
      fail(path, "ends after " + std::to_string(e) + " of the " + std::to_string(count) + " entries of the header");
    if (!split(line, f) || f.size() != 4) fail(path, at_line("expected 'i j k value', got " + quote(line)));
    long long idx[3];
    for (int a = 0; a < 3; ++a)
      if (!parse_int(f[a], LLONG_MIN, LLONG_MAX, idx[a])) fail(path, at_line("bad node index " + quote(f[a])));
    for (int a = 0; a < 3; ++a)
      if (idx[a] < 0 || idx[a] >= n[a])
        fail(path,
             at_line("node " + node_str(idx[0], idx[1], idx[2]) + " outside the " + std::to_string(n[0]) + " x " +
                     std::to_string(n[1]) + " x " + std::to_string(n[2]) + " grid"));
    double v;
    if (!parse_double(f[3], v)) fail(path, at_line("bad number " + quote(f[3])));
    const std::size_t i = g.index(static_cast<int>(idx[0]), static_cast<int>(idx[1]), static_cast<int>(idx[2]));
    if (seen[i]) fail(path, at_line("duplicate node " + node_str(idx[0], idx[1], idx[2])));
    seen[i] = true;
    g.values[i] = v;
  }
  if (next_line()) fail(path, at_line("more entries than the header's count " + std::to_string(count)));
  return g;
}

}  // namespace dsb::mpm
