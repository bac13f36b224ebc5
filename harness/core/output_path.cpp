#include "harness/core/output_path.hpp"

#include <fcntl.h>
#include <stdio.h>
#include <sys/stat.h>
#include <unistd.h>

#include <array>
#include <atomic>
#include <cerrno>
#include <cstdint>
#include <cstring>
#include <filesystem>

#include "common/error.hpp"

namespace dsb {
namespace {

namespace fs = std::filesystem;

// the first bytes of a regular file (fewer when it is shorter or unreadable)
std::string head_of(const std::string& path, std::size_t n) {
  std::string bytes(n, '\0');
  const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC | O_NONBLOCK);
  if (fd < 0) return {};
  const ssize_t got = ::read(fd, bytes.data(), n);
  ::close(fd);
  bytes.resize(got > 0 ? static_cast<std::size_t>(got) : 0);
  return bytes;
}

bool ends_with(const std::string& s, const std::string& tail) {
  return s.size() >= tail.size() && s.compare(s.size() - tail.size(), tail.size(), tail) == 0;
}

// SQLite's own file headers: a database ("SQLite format 3\0"), a write-ahead log (magic
// 0x377f0682 or 0x377f0683, big-endian) and a rollback journal (0xd9d505f920a163d7)
bool has_sqlite_header(const std::string& path) {
  const std::string h = head_of(path, 16);
  if (h.size() == 16 && std::memcmp(h.data(), "SQLite format 3\0", 16) == 0) return true;
  const auto byte = [&](std::size_t i) { return static_cast<unsigned char>(h[i]); };
  if (h.size() >= 4 && byte(0) == 0x37 && byte(1) == 0x7f && byte(2) == 0x06 && (byte(3) == 0x82 || byte(3) == 0x83))
    return true;
  static constexpr std::array<unsigned char, 8> kJournal = {0xd9, 0xd5, 0x05, 0xf9, 0x20, 0xa1, 0x63, 0xd7};
  return h.size() >= 8 && std::memcmp(h.data(), kJournal.data(), 8) == 0;
}

// "-wal", "-shm", "-journal" beside a SQLite database (the -shm file has no header of its own)
bool is_sqlite_sidecar(const std::string& path) {
  for (const char* suffix : {"-wal", "-shm", "-journal"}) {
    if (!ends_with(path, suffix)) continue;
    const std::string base = path.substr(0, path.size() - std::strlen(suffix));
    struct stat st {};
    if (::stat(base.c_str(), &st) == 0 && S_ISREG(st.st_mode) && has_sqlite_header(base)) return true;
  }
  return false;
}

std::string quoted(const std::string& option, const std::string& path) { return option + ": '" + path + "'"; }

std::atomic<unsigned> g_temp_counter{0};

}  // namespace

PathKind path_kind(const std::string& path) {
  struct stat st {};
  if (::stat(path.c_str(), &st) != 0) {
    struct stat link {};
    return ::lstat(path.c_str(), &link) == 0 ? PathKind::other : PathKind::missing;  // a dangling link
  }
  if (S_ISDIR(st.st_mode)) return PathKind::folder;
  if (!S_ISREG(st.st_mode)) return PathKind::stream;
  if (has_sqlite_header(path) || is_sqlite_sidecar(path)) return PathKind::sqlite;
  return PathKind::other;
}

bool same_file(const std::string& a, const std::string& b) {
  struct stat sa {
  }, sb{};
  return ::stat(a.c_str(), &sa) == 0 && ::stat(b.c_str(), &sb) == 0 && sa.st_dev == sb.st_dev && sa.st_ino == sb.st_ino;
}

void check_output_file(const std::string& option, const std::string& path, bool force) {
  if (path.empty()) throw UsageError(option + " must name a file, got ''");
  // SQLite's own names beside a database: a file of such a name may be taken for a database's
  // log or journal (a hot journal is deleted, or rolled into the database, by the next opener)
  for (const char* suffix : {"-journal", "-wal", "-shm"})
    if (ends_with(path, suffix))
      throw UsageError(quoted(option, path) + " ends in '" + suffix +
                       "', a name SQLite gives the files beside a database; name the output otherwise");
  switch (path_kind(path)) {
    case PathKind::sqlite:
      throw UsageError(quoted(option, path) +
                       " is a SQLite database (or one of its files): no command writes over a database, "
                       "even with --force");
    case PathKind::folder: throw UsageError(quoted(option, path) + " is a folder; name a file");
    case PathKind::other:
      if (!force) throw UsageError(quoted(option, path) + " exists; give --force to write over it");
      break;
    case PathKind::missing:
    case PathKind::stream: break;
  }
  const fs::path parent = fs::path(path).parent_path();
  std::error_code ec;
  if (!parent.empty() && !fs::is_directory(parent, ec))
    throw UsageError(quoted(option, path) + ": no folder '" + parent.string() + "'");
}

OutputFile::OutputFile(std::string option, std::string path, bool force)
    : option_(std::move(option)), path_(std::move(path)), force_(force) {
  check_output_file(option_, path_, force_);
  if (path_kind(path_) == PathKind::stream) {  // a device or a pipe: written as it goes
    // opened without blocking first: a FIFO nobody reads would hold open(2) forever (ENXIO now)
    const int fd = ::open(path_.c_str(), O_WRONLY | O_NONBLOCK | O_CLOEXEC | O_NOCTTY);
    if (fd < 0) {
      const int err = errno;
      if (err == ENXIO) throw UsageError(quoted(option_, path_) + " is a FIFO (named pipe) that nobody reads");
      throw UsageError(quoted(option_, path_) + ": cannot write: " + std::strerror(err));
    }
    struct stat st {};
    if (::fstat(fd, &st) != 0 || S_ISDIR(st.st_mode) || S_ISREG(st.st_mode)) {
      ::close(fd);
      throw UsageError(quoted(option_, path_) + " changed while it was opened; try again");
    }
    // the same file again, blocking, while our descriptor keeps the pipe's write side open
    out_.open("/proc/self/fd/" + std::to_string(fd), std::ios::binary);
    ::close(fd);
    if (!out_) throw UsageError(quoted(option_, path_) + ": cannot write: " + std::strerror(errno));
    return;
  }
  const fs::path p(path_);
  const fs::path dir = p.has_parent_path() ? p.parent_path() : fs::path(".");
  for (int attempt = 0;; ++attempt) {
    std::string name = ".";  // .NAME.tmp-PID-N (appended: GCC 12 warns falsely on "." + std::string)
    name.append(p.filename().string()).append(".tmp-").append(std::to_string(::getpid()));
    name.append("-").append(std::to_string(g_temp_counter.fetch_add(1)));
    temp_ = (dir / name).string();
    const int fd = ::open(temp_.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0666);
    if (fd >= 0) {
      ::close(fd);
      break;
    }
    if (errno != EEXIST || attempt > 100) {
      const int err = errno;
      temp_.clear();
      throw UsageError(quoted(option_, path_) + ": cannot write in folder '" + dir.string() +
                       "': " + std::strerror(err));
    }
  }
  out_.open(temp_, std::ios::binary | std::ios::trunc);
  if (!out_) throw UsageError(quoted(option_, path_) + ": cannot write '" + temp_ + "'");
}

OutputFile::~OutputFile() {
  if (out_.is_open()) out_.close();
  if (!committed_ && !temp_.empty()) ::unlink(temp_.c_str());
}

void OutputFile::commit() {
  out_.close();
  if (!out_) throw UsageError(quoted(option_, path_) + ": writing failed");
  if (temp_.empty()) {
    committed_ = true;
    return;
  }
  // the same refusals as at the start: the path may have changed while the output was computed
  check_output_file(option_, path_, force_);
  if (force_) {
    if (::rename(temp_.c_str(), path_.c_str()) != 0)
      throw UsageError(quoted(option_, path_) + ": cannot move the output into place: " + std::strerror(errno));
  } else if (::renameat2(AT_FDCWD, temp_.c_str(), AT_FDCWD, path_.c_str(), RENAME_NOREPLACE) != 0) {
    int err = errno;
    if (err == EINVAL || err == ENOSYS) {  // a filesystem without RENAME_NOREPLACE: link() refuses too
      err = ::link(temp_.c_str(), path_.c_str()) == 0 ? 0 : errno;
      if (err == 0) ::unlink(temp_.c_str());
    }
    if (err == EEXIST)
      throw UsageError(quoted(option_, path_) +
                       " appeared while the output was written; give --force to write over it");
    if (err != 0)
      throw UsageError(quoted(option_, path_) + ": cannot move the output into place: " + std::strerror(err));
  }
  committed_ = true;
}

void check_output_folder(const std::string& option, const std::string& path, bool force,
                         const std::function<bool(const std::string&)>& is_ours, const std::string& force_flag) {
  if (path.empty()) throw UsageError(option + " must name a folder, got ''");
  switch (path_kind(path)) {
    case PathKind::missing: return;
    case PathKind::sqlite: throw UsageError(quoted(option, path) + " is a SQLite database, not a folder");
    case PathKind::other:
    case PathKind::stream: throw UsageError(quoted(option, path) + " is a file, not a folder");
    case PathKind::folder: break;
  }
  std::error_code ec;
  if (fs::is_empty(path, ec) || is_ours(path) || force) return;
  throw UsageError(quoted(option, path) + " is a folder with other files in it; use a new or empty folder" +
                   (force_flag.empty() ? std::string() : ", or give " + force_flag + " to write into it"));
}

}  // namespace dsb
