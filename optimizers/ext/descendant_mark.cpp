#include "optimizers/ext/descendant_mark.hpp"

#include <dirent.h>
#include <fcntl.h>
#include <signal.h>
#include <sys/syscall.h>
#include <time.h>
#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <cstddef>
#include <cstdint>

namespace dsb {
namespace {

std::atomic<std::uint64_t> g_serial{0};

// the layout getdents64(2) fills in
struct LinuxDirent64 {
  std::uint64_t d_ino;
  std::int64_t d_off;
  unsigned short d_reclen;
  unsigned char d_type;
  char d_name[1];
};

// "/proc/<digits>/environ" into out (at least 40 bytes); false when name is not a process id
bool environ_path(const char* name, char* out, pid_t& pid) {
  static const char head[] = "/proc/";
  static const char tail[] = "/environ";
  std::size_t n = 0;
  for (const char* p = head; *p; ++p) out[n++] = *p;
  std::int64_t value = 0;
  std::size_t digits = 0;
  for (const char* p = name; *p; ++p, ++digits) {
    if (*p < '0' || *p > '9' || digits >= 19) return false;
    value = value * 10 + (*p - '0');
    out[n++] = *p;
  }
  if (digits == 0 || value <= 0 || value > INT32_MAX) return false;
  for (const char* p = tail; *p; ++p) out[n++] = *p;
  out[n] = '\0';
  pid = static_cast<pid_t>(value);
  return true;
}

// whether the environment read from fd (entries "KEY=VALUE", each ended by a zero byte) holds
// the entry `mark` of `length` bytes: one pass, entry by entry, no buffer beyond one block
bool environ_holds(int fd, const char* mark, std::size_t length) {
  char block[4096];
  std::size_t matched = 0;  // bytes of the current entry equal to mark's so far
  bool mismatch = false;    // the current entry is not the mark
  for (;;) {
    const ssize_t got = ::read(fd, block, sizeof block);
    if (got < 0 && errno == EINTR) continue;
    if (got <= 0) return !mismatch && matched == length;  // a last entry without its zero byte
    for (ssize_t i = 0; i < got; ++i) {
      const char c = block[i];
      if (c == '\0') {
        if (!mismatch && matched == length) return true;
        matched = 0;
        mismatch = false;
      } else if (!mismatch) {
        if (matched < length && mark[matched] == c)
          ++matched;
        else
          mismatch = true;
      }
    }
  }
}

// one scan of /proc: SIGKILL to each marked process; the number killed
int kill_marked_once(const char* mark, std::size_t length) {
  const int dir = ::open("/proc", O_RDONLY | O_DIRECTORY | O_CLOEXEC);
  if (dir < 0) return 0;
  const pid_t self = ::getpid();
  int killed = 0;
  alignas(8) char entries[8192];
  for (;;) {
    const long got = ::syscall(SYS_getdents64, dir, entries, sizeof entries);
    if (got < 0 && errno == EINTR) continue;
    if (got <= 0) break;
    for (long at = 0; at < got;) {
      const auto* e = reinterpret_cast<const LinuxDirent64*>(entries + at);
      at += e->d_reclen;
      char path[48];
      pid_t pid = 0;
      if (!environ_path(e->d_name, path, pid) || pid == self) continue;
      const int fd = ::open(path, O_RDONLY | O_CLOEXEC);
      if (fd < 0) continue;  // gone, or not ours to read
      const bool marked = environ_holds(fd, mark, length);
      ::close(fd);
      if (marked && ::kill(pid, SIGKILL) == 0) ++killed;
    }
  }
  ::close(dir);
  return killed;
}

}  // namespace

std::string new_descendant_mark() {
  return "DSB_EXT_RUN=" + std::to_string(::getpid()) + "." + std::to_string(g_serial.fetch_add(1));
}

int kill_marked_processes(const char* mark) {
  std::size_t length = 0;
  while (mark[length] != '\0') ++length;
  if (length == 0) return 0;
  int killed = 0;
  for (int scan = 0; scan < 64; ++scan) {
    const int now = kill_marked_once(mark, length);
    if (now == 0) break;
    killed += now;
    // let the killed ones exit (a dying process may still show its environment for a moment)
    const timespec pause{0, 2'000'000};
    ::nanosleep(&pause, nullptr);
  }
  return killed;
}

}  // namespace dsb
