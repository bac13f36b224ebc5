#include "harness/file_lock.hpp"

#include <fcntl.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <string>

#include "harness/sqlite_db.hpp"

namespace dsb {
namespace {

std::string read_all(int fd) {
  std::string text;
  char buf[256];
  ::lseek(fd, 0, SEEK_SET);
  for (ssize_t n; (n = ::read(fd, buf, sizeof buf)) > 0;) text.append(buf, static_cast<std::size_t>(n));
  while (!text.empty() && (text.back() == '\n' || text.back() == ' ')) text.pop_back();
  return text;
}

}  // namespace

FileLock::FileLock(const std::string& database_path) {
  const std::string path = database_path + "-lock";
  struct stat st {};
  if (::stat(database_path.c_str(), &st) == 0 && S_ISDIR(st.st_mode))
    throw StoreError("cannot open database '" + database_path + "': it is a directory");
  fd_ = ::open(path.c_str(), O_RDWR | O_CREAT | O_CLOEXEC, 0644);
  if (fd_ < 0)
    throw StoreError("cannot open the lock file '" + path + "' beside database '" + database_path +
                     "': " + std::strerror(errno));
  if (::flock(fd_, LOCK_EX | LOCK_NB) != 0) {
    const int err = errno;
    const std::string holder = read_all(fd_);
    ::close(fd_);
    fd_ = -1;
    if (err == EWOULDBLOCK)
      throw StoreError("database '" + database_path + "' is in use by another harness (" +
                       (holder.empty() ? std::string("holder unknown") : holder) +
                       "): wait for it to finish or stop it (it resumes later), or use another --db");
    throw StoreError("cannot lock '" + path + "': " + std::strerror(err));
  }
  // who holds it, for the message above
  char host[256] = {0};
  ::gethostname(host, sizeof host - 1);
  const std::string who = "pid " + std::to_string(::getpid()) + " on " + host;
  if (::ftruncate(fd_, 0) == 0) {
    ::lseek(fd_, 0, SEEK_SET);
    [[maybe_unused]] const ssize_t n = ::write(fd_, who.data(), who.size());
  }
}

FileLock::~FileLock() {
  if (fd_ >= 0) ::close(fd_);  // releases the flock
}

}  // namespace dsb
