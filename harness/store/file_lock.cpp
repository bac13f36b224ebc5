#include "harness/store/file_lock.hpp"

#include <fcntl.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <sys/sysmacros.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <sstream>
#include <string>

#include "common/error.hpp"
#include "common/regular_file.hpp"
#include "harness/store/sqlite_db.hpp"

namespace dsb {
namespace {

std::string host_name() {
  char host[256] = {0};
  ::gethostname(host, sizeof host - 1);
  return host;
}

// "pid N on HOST" of the process holding a flock on the file open at fd, from /proc/locks
// (lines "1: FLOCK  ADVISORY  WRITE PID MAJ:MIN:INODE 0 EOF", device numbers in hex); the inode
// alone matches when the device differs (an overlay filesystem reports another device)
std::string flock_holder(int fd) {
  struct stat st {};
  if (::fstat(fd, &st) != 0) return {};
  std::ifstream locks("/proc/locks");
  std::string line, by_inode;
  while (std::getline(locks, line)) {
    if (line.find("->") != std::string::npos) continue;  // a waiter, not a holder
    std::istringstream words(line);
    std::string id, type, mode, access, pid, where;
    if (!(words >> id >> type >> mode >> access >> pid >> where) || type != "FLOCK") continue;
    unsigned maj = 0, min = 0;
    unsigned long long ino = 0;
    if (std::sscanf(where.c_str(), "%x:%x:%llu", &maj, &min, &ino) != 3 || ino != st.st_ino) continue;
    const std::string who = "pid " + pid + " on " + host_name();
    if (maj == ::major(st.st_dev) && min == ::minor(st.st_dev)) return who;
    if (by_inode.empty()) by_inode = who;
  }
  return by_inode;
}

}  // namespace

FileLock::FileLock(const std::string& database_path) {
  // never blocks: a FIFO or device is refused by its kind, like every path a command is given
  refuse_special_file("database", database_path);
  fd_ = ::open(database_path.c_str(), O_RDWR | O_CREAT | O_NONBLOCK | O_CLOEXEC | O_NOCTTY, 0644);
  if (fd_ < 0) {
    const int err = errno;
    if (err == EISDIR) throw UsageError(not_regular_message("database", database_path, S_IFDIR));
    throw StoreError("cannot open database '" + shown_value(database_path) + "' for writing: " + std::strerror(err));
  }
  struct stat st {};
  if (::fstat(fd_, &st) != 0 || !S_ISREG(st.st_mode)) {
    const mode_t mode = st.st_mode;
    ::close(fd_);
    fd_ = -1;
    throw UsageError(not_regular_message("database", database_path, mode));
  }
  device_ = st.st_dev;
  inode_ = st.st_ino;
  if (::flock(fd_, LOCK_EX | LOCK_NB) != 0) {
    const int err = errno;
    const std::string holder = err == EWOULDBLOCK ? flock_holder(fd_) : std::string();
    ::close(fd_);
    fd_ = -1;
    if (err == EWOULDBLOCK)
      throw StoreError("database '" + database_path + "' is in use by another harness (" +
                       (holder.empty() ? std::string("holder unknown") : holder) +
                       "): wait for it to finish or stop it (it resumes later), or use another --db");
    throw StoreError("cannot lock database '" + database_path + "': " + std::strerror(err));
  }
}

bool FileLock::names_locked_file(const std::string& path) const {
  struct stat st {};
  return ::stat(path.c_str(), &st) == 0 && st.st_dev == device_ && st.st_ino == inode_;
}

std::string FileLock::current_path() const {
  char target[4096];
  const std::string link = "/proc/self/fd/" + std::to_string(fd_);
  const ssize_t n = ::readlink(link.c_str(), target, sizeof target - 1);
  if (n <= 0) return {};
  std::string p(target, static_cast<std::size_t>(n));
  static const std::string deleted = " (deleted)";
  if (p.size() >= deleted.size() && p.compare(p.size() - deleted.size(), deleted.size(), deleted) == 0) return {};
  return p;
}

FileLock::~FileLock() {
  if (fd_ >= 0) ::close(fd_);  // releases the flock
}

}  // namespace dsb
