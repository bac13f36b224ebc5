#pragma once
// Opening a file the user named without ever blocking on it. open(2) of a FIFO for reading waits
// for a writer (and for writing, for a reader), forever when there is none; a device may block or
// never end. So a path is opened with O_NONBLOCK, checked with fstat on the open descriptor (no
// race with a rename between the check and the read), refused unless it is a regular file, and
// only then switched back to blocking reads. Every refusal says what the path is, in the same
// words from every command: "LABEL: 'PATH' is a FIFO (named pipe), not a regular file".
#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <string>
#include <utility>

#include "common/error.hpp"
#include "common/shown_value.hpp"

namespace dsb {

// the kind of a file that is not a regular one, as messages name it ("a FIFO (named pipe)")
inline std::string special_file_kind(mode_t mode) {
  if (S_ISDIR(mode)) return "a directory";
  if (S_ISFIFO(mode)) return "a FIFO (named pipe)";
  if (S_ISCHR(mode)) return "a character device";
  if (S_ISBLK(mode)) return "a block device";
  if (S_ISSOCK(mode)) return "a socket";
  return "not a regular file";
}

// "LABEL: 'PATH'" with the path's control characters escaped
inline std::string labelled_path(const std::string& label, const std::string& path) {
  return (label.empty() ? std::string() : label + ": ") + "'" + shown_value(path) + "'";
}

// "LABEL: 'PATH' is a FIFO (named pipe), not a regular file"
inline std::string not_regular_message(const std::string& label, const std::string& path, mode_t mode) {
  const std::string kind = special_file_kind(mode);
  return labelled_path(label, path) +
      (kind == "not a regular file" ? " is " + kind : " is " + kind + ", not a regular file");
}

// An open descriptor of a regular file, closed when destroyed.
class RegularFile {
 public:
  RegularFile() = default;
  explicit RegularFile(int fd) : fd_(fd) {}
  ~RegularFile() {
    if (fd_ >= 0) ::close(fd_);
  }
  RegularFile(RegularFile&& o) noexcept : fd_(o.fd_) { o.fd_ = -1; }
  RegularFile& operator=(RegularFile&& o) noexcept {
    std::swap(fd_, o.fd_);
    return *this;
  }
  RegularFile(const RegularFile&) = delete;
  RegularFile& operator=(const RegularFile&) = delete;
  int fd() const { return fd_; }

 private:
  int fd_ = -1;
};

// Opens `path` for reading into `file` without blocking; returns "" when it is a regular file, else
// the problem as a phrase that follows the path ("cannot open: No such file or directory", "is a
// FIFO (named pipe), not a regular file"), for callers that word their own messages.
inline std::string open_regular_problem(const std::string& path, RegularFile& file) {
  RegularFile f(::open(path.c_str(), O_RDONLY | O_NONBLOCK | O_CLOEXEC | O_NOCTTY));
  if (f.fd() < 0) return std::string("cannot open: ") + std::strerror(errno);
  struct stat st {};
  if (::fstat(f.fd(), &st) != 0) return std::string("cannot stat: ") + std::strerror(errno);
  if (!S_ISREG(st.st_mode)) {
    const std::string kind = special_file_kind(st.st_mode);
    return kind == "not a regular file" ? "is " + kind : "is " + kind + ", not a regular file";
  }
  const int flags = ::fcntl(f.fd(), F_GETFL);
  if (flags >= 0) ::fcntl(f.fd(), F_SETFL, flags & ~O_NONBLOCK);
  file = std::move(f);
  return {};
}

// Opens `path` for reading. UsageError "LABEL: 'PATH' ..." when it is missing or unreadable ("cannot
// open: No such file or directory") or not a regular file ("is a FIFO (named pipe), not a regular
// file"); never blocks on a FIFO or device.
inline RegularFile open_regular_file(const std::string& label, const std::string& path) {
  if (path.empty()) throw UsageError((label.empty() ? std::string() : label + ": ") + "the path is empty");
  RegularFile f;
  const std::string problem = open_regular_problem(path, f);
  if (!problem.empty())
    throw UsageError(labelled_path(label, path) + (problem.rfind("is ", 0) == 0 ? " " : ": ") + problem);
  return f;
}

// The whole content of a regular file (open_regular_file's refusals; "read error" on failure).
inline std::string read_regular_file(const std::string& label, const std::string& path) {
  const RegularFile f = open_regular_file(label, path);
  std::string bytes;
  char buf[1 << 16];
  for (;;) {
    const ssize_t got = ::read(f.fd(), buf, sizeof buf);
    if (got == 0) break;
    if (got < 0) {
      if (errno == EINTR) continue;
      throw UsageError(labelled_path(label, path) + ": read error: " + std::strerror(errno));
    }
    bytes.append(buf, static_cast<std::size_t>(got));
  }
  return bytes;
}

// UsageError when `path` exists (through links) and is not a regular file; a missing path passes
// (a database to be created). stat(2) opens nothing, so it cannot block.
inline void refuse_special_file(const std::string& label, const std::string& path) {
  struct stat st {};
  if (::stat(path.c_str(), &st) == 0 && !S_ISREG(st.st_mode))
    throw UsageError(not_regular_message(label, path, st.st_mode));
}

// UsageError unless `path` exists (through links) and is a regular file: "LABEL: no file 'PATH'" or
// the kind it is.
inline void require_regular_file(const std::string& label, const std::string& path) {
  struct stat st {};
  if (::stat(path.c_str(), &st) != 0)
    throw UsageError(labelled_path(label, path) + ": no such file" +
                     (errno == ENOENT ? "" : std::string(" (") + std::strerror(errno) + ")"));
  if (!S_ISREG(st.st_mode)) throw UsageError(not_regular_message(label, path, st.st_mode));
}

}  // namespace dsb
