#include "optimizers/ext/ext_optimizer.hpp"

#include <array>
#include <bit>
#include <cmath>
#include <cstring>
#include <limits>
#include <optional>
#include <stdexcept>
#include <vector>

#include "common/error.hpp"
#include "common/number_text.hpp"
#include "optimizers/ext/child_process.hpp"

namespace dsb {
namespace {

using Json = nlohmann::json;
using Clock = ChildProcess::Clock;

// a line as it may appear in an error: at most 80 characters, printable
std::string quote_line(const std::string& line) {
  std::string q;
  for (char c : line.substr(0, 80)) q += (static_cast<unsigned char>(c) < 32) ? '?' : c;
  return "'" + q + (line.size() > 80 ? "...'" : "'");
}

std::string seconds_text(double s) { return Json(s).dump() + " s"; }

// A message as JSON. A binary ask whose "ask" is the first key ({"ask": "BASE64...", ...}, as
// dsb_protocol.py writes it) skips the JSON lexer for its long string (base64 holds no quote or
// backslash): the rest is parsed with an empty string there, then the string is moved in. This
// is 10x faster at 400 doubles a point; anything else goes through the parser whole.
Json parse_message(const std::string& line) {
  auto ws = [&](std::size_t i) {
    while (i < line.size() && (line[i] == ' ' || line[i] == '\t' || line[i] == '\r')) ++i;
    return i;
  };
  std::size_t i = ws(0);
  if (i < line.size() && line[i] == '{') {
    i = ws(i + 1);
    if (line.compare(i, 5, "\"ask\"") == 0) {
      i = ws(i + 5);
      if (i < line.size() && line[i] == ':') {
        i = ws(i + 1);
        if (i < line.size() && line[i] == '"') {
          const std::size_t begin = i + 1, end = line.find('"', begin);
          bool plain = end != std::string::npos && end - begin >= 64;
          for (std::size_t k = begin; plain && k < end; ++k) {
            const char ch = line[k];
            plain = std::isalnum(static_cast<unsigned char>(ch)) || ch == '+' || ch == '/' || ch == '=';
          }
          if (plain) {
            Json m = Json::parse(line.substr(0, begin) + line.substr(end), nullptr, false);
            if (m.is_object() && m.contains("ask") && m["ask"] == "") m["ask"] = line.substr(begin, end - begin);
            return m;
          }
        }
      }
    }
  }
  return Json::parse(line, nullptr, false);
}

constexpr char kBase64[] = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";

// the doubles' little-endian bytes (x86-64's own order) in standard base64 with padding
std::string base64_of_doubles(const std::vector<double>& v) {
  static_assert(std::endian::native == std::endian::little, "the base64 encoding sends little-endian doubles");
  const auto* b = reinterpret_cast<const unsigned char*>(v.data());
  const std::size_t n = v.size() * sizeof(double);
  std::string out;
  out.reserve((n + 2) / 3 * 4);
  for (std::size_t i = 0; i < n; i += 3) {
    const unsigned w = (b[i] << 16) | ((i + 1 < n ? b[i + 1] : 0) << 8) | (i + 2 < n ? b[i + 2] : 0);
    out += kBase64[(w >> 18) & 63];
    out += kBase64[(w >> 12) & 63];
    out += i + 1 < n ? kBase64[(w >> 6) & 63] : '=';
    out += i + 2 < n ? kBase64[w & 63] : '=';
  }
  return out;
}

// false unless text is padded base64 of a whole number of doubles
bool doubles_of_base64(const std::string& text, std::vector<double>& out) {
  static const auto table = [] {
    std::array<int, 256> t;
    t.fill(-1);
    for (int i = 0; i < 64; ++i) t[static_cast<unsigned char>(kBase64[i])] = i;
    return t;
  }();
  if (text.size() % 4 != 0) return false;
  std::string bytes;
  bytes.reserve(text.size() / 4 * 3);
  for (std::size_t i = 0; i < text.size(); i += 4) {
    int q[4];
    int pad = 0;
    for (int j = 0; j < 4; ++j) {
      const char ch = text[i + j];
      if (ch == '=' && i + 4 == text.size() && j >= 2) {
        q[j] = 0;
        ++pad;
        continue;
      }
      if (pad > 0) return false;
      q[j] = table[static_cast<unsigned char>(ch)];
      if (q[j] < 0) return false;
    }
    const unsigned w = (q[0] << 18) | (q[1] << 12) | (q[2] << 6) | q[3];
    bytes += static_cast<char>((w >> 16) & 255);
    if (pad < 2) bytes += static_cast<char>((w >> 8) & 255);
    if (pad < 1) bytes += static_cast<char>(w & 255);
  }
  if (bytes.size() % sizeof(double) != 0) return false;
  out.resize(bytes.size() / sizeof(double));
  std::memcpy(out.data(), bytes.data(), bytes.size());
  return true;
}

// The program's side of one conversation: every wait has the per-reply deadline, every error
// is one line that ends with the program's stderr tail.
class Conversation {
 public:
  Conversation(const ExtOptimizerSpec& spec, const std::string& what)
      : spec_(spec), what_(what), child_(start(spec, what)) {}

  [[noreturn]] void fail(const std::string& reason) {
    child_->kill();
    std::string msg = what_ + reason;
    const std::string tail = child_->stderr_tail();
    if (!tail.empty()) msg += "; stderr: " + tail;
    throw std::runtime_error(msg);
  }

  // the program's CPU so far, its group's descendants included (ChildProcess::cpu_seconds)
  double cpu_seconds() const { return child_->cpu_seconds(); }
  // the program is killed if still there, and reaped
  void end() { child_->kill(); }

  Clock::time_point deadline() const {
    return Clock::now() + std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(spec_.timeout_s));
  }

  // false when the program no longer reads its stdin
  bool send(const Json& message) {
    const std::string line = message.dump() + "\n";
    switch (child_->write(line, deadline())) {
      case ChildProcess::Io::ok: return true;
      case ChildProcess::Io::closed: return false;
      case ChildProcess::Io::timeout:
        fail("did not read its input within the timeout of " + seconds_text(spec_.timeout_s));
    }
    return false;
  }

  // the next line, or nullopt at the end of its stdout
  std::optional<std::string> receive_line(const std::string& waiting_for) {
    std::string line;
    switch (child_->read_line(line, deadline())) {
      case ChildProcess::Io::ok: return line;
      case ChildProcess::Io::timeout:
        fail("no reply within the timeout of " + seconds_text(spec_.timeout_s) + " (waiting for " + waiting_for + ")");
      case ChildProcess::Io::closed:
        if (child_->too_long()) fail("a line longer than " + std::to_string(ChildProcess::kMaxLine) + " bytes");
        return std::nullopt;
    }
    return std::nullopt;
  }

  // one JSON object; a malformed line or the end of stdout fails
  Json receive(const std::string& waiting_for) {
    const auto line = receive_line(waiting_for);
    if (!line) fail(ended_text() + " (waiting for " + waiting_for + ")");
    Json m = Json::parse(*line, nullptr, false);
    if (m.is_discarded() || !m.is_object()) fail("malformed line " + quote_line(*line) + " (not a JSON object)");
    return m;
  }

  // what ended its stdout: its exit (waited for up to the timeout)
  std::string ended_text() {
    const auto status = child_->wait_exit(deadline());
    if (!status) return "closed its stdout but did not exit";
    return "closed its stdout and " + describe_exit(*status);
  }

  // after the last message: no more input, no more output, exit 0 within the timeout
  void expect_clean_exit(const std::string& after) {
    child_->close_stdin();
    for (;;) {
      const auto line = receive_line("its exit " + after);
      if (!line) break;
      if (line->find_first_not_of(" \t\r") == std::string::npos) continue;
      const Json m = Json::parse(*line, nullptr, false);
      if (m.is_object() && m.contains("ask")) fail("asked for points " + after);
      fail("wrote " + quote_line(*line) + " " + after);
    }
    const auto status = child_->wait_exit(deadline());
    if (!status) fail("did not exit within " + seconds_text(spec_.timeout_s) + " " + after);
    if (*status != 0) fail(describe_exit(*status) + " " + after);
  }

  // its hello: {"hello": 1, "name": "...", "version": "..."}
  std::pair<std::string, std::string> receive_hello() {
    const Json h = receive("its hello");
    if (!h.contains("hello")) fail("first line is not a hello: " + quote_line(h.dump()));
    if (!h["hello"].is_number_integer() || h["hello"].get<std::int64_t>() != kExtProtocol)
      fail("speaks protocol " + h["hello"].dump() + ", the harness " + std::to_string(kExtProtocol));
    for (const char* key : {"name", "version"})
      if (!h.contains(key) || !h[key].is_string() || h[key].get<std::string>().empty() ||
          h[key].get<std::string>().size() > 200)
        fail(std::string("hello without a '") + key + "' (a non-empty string of at most 200 characters)");
    return {h["name"].get<std::string>(), h["version"].get<std::string>()};
  }

 private:
  static std::unique_ptr<ChildProcess> start(const ExtOptimizerSpec& spec, const std::string& what) {
    try {
      return std::make_unique<ChildProcess>(spec.command);
    } catch (const std::exception& e) {
      throw std::runtime_error(what + "could not start: " + e.what());
    }
  }

  const ExtOptimizerSpec& spec_;
  std::string what_;
  std::unique_ptr<ChildProcess> child_;
};

class ExtOptimizer : public Optimizer {
 public:
  ExtOptimizer(ExtOptimizerSpec spec, std::string env, std::uint64_t seed)
      : spec_(std::move(spec)), env_(std::move(env)), seed_(seed), name_("ext:" + spec_.name) {}

  const std::string& name() const override { return name_; }
  // it is told in the hello whether gradients exist; it may run on any env
  bool needs_gradient() const override { return false; }
  Json config() const override {
    return {{"protocol", kExtProtocol},
            {"command", spec_.command},
            {"name", spec_.reported_name},
            {"version", spec_.version}};
  }
  Json diagnostics() const override { return diag_; }
  double process_cpu_s() const override { return conversation_ ? conversation_->cpu_seconds() : 0.0; }

  void minimize(Objective& f, Rng& /*rng: the program seeds itself from the hello*/) override {
    diag_ = {{"name", spec_.reported_name},
             {"version", spec_.version},
             {"asks", 0},
             {"grad_asks", 0},
             {"points", 0},
             {"largest_ask", 0},
             {"end", "failed"}};
    conversation_.emplace(spec_, name_ + ": ");
    Conversation& c = *conversation_;
    // the program ends with minimize(), however minimize() ends (a stop's exception included):
    // killed if still there and reaped, its CPU kept for process_cpu_s()
    struct EndProgram {
      Conversation& c;
      ~EndProgram() { c.end(); }
    } end_program{c};
    const int d = f.dim();
    c.send({{"protocol", kExtProtocol},
            {"env", env_},
            {"dim", d},
            {"lower", std::vector<double>(d, -1.0)},
            {"upper", std::vector<double>(d, 1.0)},
            {"budget", f.budget()},
            {"gradient", f.has_gradient()},
            {"seed", seed_}});
    const auto [name, version] = c.receive_hello();
    if (name != spec_.reported_name || version != spec_.version)
      c.fail("reports itself as " + name + " " + version + ", but the plan's probe saw " + spec_.reported_name + " " +
             spec_.version + " (results of two versions would mix)");

    std::vector<double> xs, losses, grads;
    for (;;) {
      const auto line = c.receive_line("an ask");
      if (!line) {
        // it stopped before the budget: a normal end when it exits 0 (the run is done, shorter)
        const std::string ended = c.ended_text();
        if (ended != "closed its stdout and exited with status 0") c.fail(ended + " before the budget end");
        diag_["end"] = "optimizer";
        return;
      }
      const Json m = parse_message(*line);
      if (m.is_discarded() || !m.is_object()) c.fail("malformed line " + quote_line(*line) + " (not a JSON object)");
      if (!m.contains("ask")) c.fail("unexpected message " + quote_line(*line) + " (expected an ask)");
      const bool binary = m.contains("ask") && m["ask"].is_string();
      const bool want_grad = read_ask(c, m, d, xs);
      const std::size_t asked = xs.size() / static_cast<std::size_t>(d);
      if (want_grad && !f.has_gradient())
        c.fail("asked for gradients, but env '" + env_ + "' has none (the hello said gradient: false)");
      diag_["asks"] = diag_["asks"].get<std::int64_t>() + 1;
      if (want_grad) diag_["grad_asks"] = diag_["grad_asks"].get<std::int64_t>() + 1;
      diag_["largest_ask"] = std::max<std::int64_t>(diag_["largest_ask"].get<std::int64_t>(), asked);

      // the points that fit in the budget, in order; the reply says how many were evaluated
      const std::size_t n = std::min<std::size_t>(asked, static_cast<std::size_t>(f.remaining()));
      losses.resize(n);
      grads.resize(want_grad ? n * static_cast<std::size_t>(d) : 0);
      if (want_grad) {
        for (std::size_t k = 0; k < n; ++k)
          losses[k] = f.value_and_grad(std::span<const double>(xs).subspan(k * d, d),
                                       std::span<double>(grads).subspan(k * d, d));
      } else {
        f.values(std::span<const double>(xs).first(n * d), losses);
      }
      diag_["points"] = diag_["points"].get<std::int64_t>() + static_cast<std::int64_t>(n);
      // a failed episode (+inf from the objective): null in JSON, NaN in base64
      Json reply = {{"used", f.used()}, {"remaining", f.remaining()}};
      if (binary) {
        for (std::size_t k = 0; k < n; ++k) {
          if (std::isfinite(losses[k])) continue;
          losses[k] = std::numeric_limits<double>::quiet_NaN();
          if (want_grad) std::fill_n(grads.begin() + k * d, d, std::numeric_limits<double>::quiet_NaN());
        }
        reply["losses"] = base64_of_doubles(losses);
        if (want_grad) reply["grads"] = base64_of_doubles(grads);
      } else {
        Json reply_losses = Json::array(), reply_grads = Json::array();
        for (std::size_t k = 0; k < n; ++k) {
          const bool ok = std::isfinite(losses[k]);
          reply_losses.push_back(ok ? Json(losses[k]) : Json(nullptr));
          if (want_grad)
            reply_grads.push_back(ok ? Json(std::vector<double>(grads.begin() + k * d, grads.begin() + (k + 1) * d))
                                     : Json(nullptr));
        }
        reply["losses"] = std::move(reply_losses);
        if (want_grad) reply["grads"] = std::move(reply_grads);
      }
      c.send(reply);
      if (f.remaining() == 0) {
        // the end: tell it, then it must exit 0 without asking again
        c.send({{"end", "budget"}});
        c.expect_clean_exit("after the budget end");
        diag_["end"] = "budget";
        throw BudgetExhausted{};
      }
    }
  }

 private:
  // {"ask": [[x...], ...], "grad": bool}: points of dim numbers in [-1, 1], row after row into xs
  bool read_ask(Conversation& c, const Json& m, int d, std::vector<double>& xs) const {
    const Json& ask = m["ask"];
    if (!(ask.is_array() && !ask.empty()) && !ask.is_string())
      c.fail("malformed ask (wants a non-empty list of points, or a base64 string)");
    bool grad = false;
    if (m.contains("grad")) {
      if (!m["grad"].is_boolean()) c.fail("malformed ask ('grad' must be true or false)");
      grad = m["grad"].get<bool>();
    }
    xs.clear();
    if (ask.is_string()) {
      // base64 of little-endian IEEE doubles, point after point
      if (!doubles_of_base64(ask.get_ref<const std::string&>(), xs))
        c.fail("malformed ask (the base64 string does not decode to doubles)");
      if (xs.empty() || xs.size() % static_cast<std::size_t>(d) != 0)
        c.fail("malformed ask (" + std::to_string(xs.size()) + " doubles in base64, not a multiple of dim " +
               std::to_string(d) + ")");
      for (std::size_t j = 0; j < xs.size(); ++j)
        if (!(xs[j] >= -1.0 && xs[j] <= 1.0))
          c.fail("point " + std::to_string(j / d) + " of the ask has x[" + std::to_string(j % d) +
                 "] = " + number_text(xs[j]) + ", outside the box [-1, 1]");
      return grad;
    }
    xs.reserve(ask.size() * static_cast<std::size_t>(d));
    for (std::size_t k = 0; k < ask.size(); ++k) {
      const Json& p = ask[k];
      if (!p.is_array() || p.size() != static_cast<std::size_t>(d))
        c.fail("point " + std::to_string(k) + " of the ask is not a list of " + std::to_string(d) + " numbers");
      for (std::size_t i = 0; i < p.size(); ++i) {
        if (!p[i].is_number())
          c.fail("point " + std::to_string(k) + " of the ask has a non-number x[" + std::to_string(i) + "]");
        const double v = p[i].get<double>();
        if (!(v >= -1.0 && v <= 1.0))
          c.fail("point " + std::to_string(k) + " of the ask has x[" + std::to_string(i) + "] = " + number_text(v) +
                 ", outside the box [-1, 1]");
        xs.push_back(v);
      }
    }
    return grad;
  }

  ExtOptimizerSpec spec_;
  std::string env_;
  std::uint64_t seed_;
  std::string name_;
  Json diag_ = Json::object();
  std::optional<Conversation> conversation_;  // the current or last minimize()'s program
};

}  // namespace

std::string ext_name_of(const std::string& optimizer) {
  return optimizer.rfind("ext:", 0) == 0 ? optimizer.substr(4) : std::string();
}

void check_ext_name(const std::string& name) {
  bool ok = !name.empty() && name.size() <= 64;
  for (char c : name) ok = ok && (std::isalnum(static_cast<unsigned char>(c)) || c == '_' || c == '-' || c == '.');
  if (!ok)
    throw UsageError("external optimizer name '" + name +
                     "' must be 1 to 64 letters, digits, '_', '-' or '.' (as in ext:my-opt)");
}

ExtOptimizerSpec ext_probe(ExtOptimizerSpec spec) {
  try {
    Conversation c(spec, "ext:" + spec.name + ": probe of '" + spec.command + "' failed: ");
    c.send({{"protocol", kExtProtocol}, {"probe", true}});  // a program that exits at once: its exit says why
    std::tie(spec.reported_name, spec.version) = c.receive_hello();
    c.send({{"end", "probe"}});
    c.expect_clean_exit("after the probe's end");
  } catch (const UsageError&) {
    throw;
  } catch (const std::exception& e) {
    throw UsageError(e.what());
  }
  return spec;
}

std::unique_ptr<Optimizer> make_ext_optimizer(const ExtOptimizerSpec& spec, const std::string& env,
                                              std::uint64_t seed) {
  return std::make_unique<ExtOptimizer>(spec, env, seed);
}

}  // namespace dsb
