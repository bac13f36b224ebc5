#include "harness/commands/slurm_dir.hpp"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <optional>
#include <regex>
#include <string_view>
#include <vector>

#include "common/error.hpp"
#include "common/shown_value.hpp"
#include "harness/core/output_path.hpp"

namespace dsb {
namespace {

namespace fs = std::filesystem;

std::string quoted(const fs::path& p) { return "'" + shown_value(p.string()) + "'"; }

// the entry itself, links not followed
std::optional<struct stat> lstat_of(const fs::path& p) {
  struct stat st {};
  if (::lstat(p.c_str(), &st) != 0) return std::nullopt;
  return st;
}

bool is_real_file(const fs::path& p) {
  const auto st = lstat_of(p);
  return st && S_ISREG(st->st_mode);
}

bool is_real_folder(const fs::path& p) {
  const auto st = lstat_of(p);
  return st && S_ISDIR(st->st_mode);
}

// the content of a regular file that is not a link (never blocks: O_NONBLOCK, checked with fstat);
// nullopt when it is anything else or unreadable
std::optional<std::string> read_real_file(const fs::path& p) {
  const int fd = ::open(p.c_str(), O_RDONLY | O_NONBLOCK | O_NOFOLLOW | O_CLOEXEC | O_NOCTTY);
  if (fd < 0) return std::nullopt;
  struct stat st {};
  std::optional<std::string> text;
  if (::fstat(fd, &st) == 0 && S_ISREG(st.st_mode)) {
    text.emplace();
    char buf[1 << 14];
    for (;;) {
      const ssize_t got = ::read(fd, buf, sizeof buf);
      if (got < 0 && errno == EINTR) continue;
      if (got <= 0) break;
      text->append(buf, static_cast<std::size_t>(got));
    }
  }
  ::close(fd);
  return text;
}

bool is_our_script(const fs::path& p) {
  const auto text = read_real_file(p);
  return text && text->find(kSlurmScriptMarker) != std::string::npos;
}

// the names in a folder, sorted (so that a refusal names the same entry every time)
std::vector<std::string> names_in(const fs::path& dir) {
  std::vector<std::string> names;
  std::error_code ec;
  for (fs::directory_iterator it(dir, ec), end; !ec && it != end; it.increment(ec))
    names.push_back(it->path().filename().string());
  if (ec) throw UsageError("--dir: cannot list folder " + quoted(dir) + ": " + ec.message());
  std::sort(names.begin(), names.end());
  return names;
}

// the names the scripts write (slurm_command.cpp's templates)
const std::regex kLogName(R"((shard-[0-9]+-job-[0-9]+|merge-job-[0-9]+)\.out)");
const std::regex kShardName(
    R"(shard-[0-9]+\.sqlite(-journal|-wal|-shm)?|\.shard-[0-9]+\.[A-Za-z0-9]+\.tmp(-journal)?)");
const std::regex kMergeTempName(R"(\.results\.[A-Za-z0-9]+\.sqlite(-journal)?)");
const char* const kScripts[] = {"array.sbatch", "merge.sbatch", "submit.sh"};

struct Foreign {
  fs::path path;
  enum class Kind { database, script, other } kind;
};

Foreign foreign(const fs::path& p, bool script = false) {
  if (path_kind(p.string()) == PathKind::sqlite) return {p, Foreign::Kind::database};
  return {p, script ? Foreign::Kind::script : Foreign::Kind::other};
}

// a missing DIR: the nearest existing folder above it must be one we may create folders in
void check_creatable(const fs::path& dir) {
  fs::path up = dir.parent_path();
  struct stat st {};
  while (::stat(up.c_str(), &st) != 0) {
    if ((errno != ENOENT && errno != ENOTDIR) || up == up.parent_path())
      throw UsageError("--dir " + quoted(dir) + ": cannot create it: " + quoted(up) + ": " + std::strerror(errno));
    up = up.parent_path();
  }
  if (!S_ISDIR(st.st_mode))
    throw UsageError("--dir " + quoted(dir) + ": cannot create it: " + quoted(up) + " is not a folder");
  if (::access(up.c_str(), W_OK | X_OK) != 0)
    throw UsageError("--dir " + quoted(dir) + ": cannot create it: folder " + quoted(up) + " is not writable");
}

}  // namespace

fs::path slurm_dir_path(const std::string& dir) {
  if (dir.empty()) throw UsageError("--dir must not be empty");
  fs::path abs = fs::absolute(dir).lexically_normal();
  if (!abs.has_filename() && abs.has_parent_path() && abs != abs.root_path()) abs = abs.parent_path();  // "D/" -> "D"
  const std::string text = abs.string();
  const bool control = std::any_of(text.begin(), text.end(), [](char c) {
    return static_cast<unsigned char>(c) < 0x20 || static_cast<unsigned char>(c) == 0x7f;
  });
  if (control || text.find_first_of("'\"\\ ") != std::string::npos)
    throw UsageError("--dir must not contain spaces, quotes, backslashes or control characters, got '" +
                     shown_value(dir) + "'");
  return abs;
}

void check_slurm_dir(const fs::path& dir, const std::string& array_text) {
  struct stat st {};
  if (::stat(dir.c_str(), &st) != 0) {
    if (errno != ENOENT && errno != ENOTDIR) throw UsageError("--dir " + quoted(dir) + ": " + std::strerror(errno));
    check_creatable(dir);
    return;
  }
  if (!S_ISDIR(st.st_mode)) throw UsageError("--dir " + quoted(dir) + " is not a folder");
  if (::access(dir.c_str(), W_OK | X_OK) != 0) throw UsageError("--dir: folder " + quoted(dir) + " is not writable");

  const bool ours = is_our_script(dir / "array.sbatch");
  std::vector<Foreign> found;
  for (const std::string& name : names_in(dir)) {
    const fs::path p = dir / name;
    if (std::find(std::begin(kScripts), std::end(kScripts), name) != std::end(kScripts)) {
      if (!is_our_script(p)) found.push_back(foreign(p, true));
    } else if (name == "logs" || name == "shards") {
      if (!is_real_folder(p)) {
        found.push_back(foreign(p));
        continue;
      }
      const std::regex& allowed = name == "logs" ? kLogName : kShardName;
      for (const std::string& inner : names_in(p))
        if (!ours || !is_real_file(p / inner) || !std::regex_match(inner, allowed)) found.push_back(foreign(p / inner));
      if (::access(p.c_str(), W_OK | X_OK) != 0) throw UsageError("--dir: folder " + quoted(p) + " is not writable");
    } else if (!(ours && is_real_file(p) && std::regex_match(name, kMergeTempName))) {
      found.push_back(foreign(p));
    }
  }
  // a database first, then a script of the user's, then anything else
  const auto first =
      std::min_element(found.begin(), found.end(), [](const Foreign& a, const Foreign& b) { return a.kind < b.kind; });
  if (first != found.end()) {
    switch (first->kind) {
      case Foreign::Kind::database:
        throw UsageError("--dir " + quoted(dir) + " holds a SQLite database, " + quoted(first->path) +
                         ": `harness slurm` never writes beside a database, not even an earlier merge's "
                         "results.sqlite; use a new or empty folder");
      case Foreign::Kind::script:
        throw UsageError("--dir: " + quoted(first->path) +
                         " exists and was not written by `harness slurm`; use a new or empty folder");
      case Foreign::Kind::other:
        throw UsageError("--dir " + quoted(dir) + " holds " + quoted(first->path) +
                         ", which `harness slurm` did not write; use a new or empty folder");
    }
  }

  // shards of an earlier grid must not be mixed with this one's
  if (!ours || read_real_file(dir / "array.sbatch") == array_text || !is_real_folder(dir / "shards")) return;
  for (const std::string& name : names_in(dir / "shards"))
    if (name.rfind("shard-", 0) == 0)
      throw UsageError("--dir " + quoted(dir) + " holds shards of a different grid or binary (" +
                       quoted(dir / "shards" / name) + "); use another --dir");
}

void create_slurm_dir(const fs::path& dir) {
  for (const fs::path& p : {dir, dir / "logs", dir / "shards"}) {
    std::error_code ec;
    fs::create_directories(p, ec);
    if (ec || (p == dir ? !fs::is_directory(p, ec) : !is_real_folder(p)))
      throw UsageError("--dir: cannot create folder " + quoted(p) + (ec ? ": " + ec.message() : ""));
  }
}

std::string slurm_pattern_literal(const std::string& path) {
  std::string out;
  for (const char c : path) out += c == '%' ? std::string("%%") : std::string(1, c);
  return out;
}

}  // namespace dsb
