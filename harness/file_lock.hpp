#pragma once
// One harness per results file: an exclusive, non-blocking flock on the sidecar PATH-lock, which
// records who holds it (pid, host, start time) for the message a second harness gets. The kernel
// releases the lock when the holder exits, however it exits, so a crash leaves no stale lock.
#include <string>

namespace dsb {

class FileLock {
 public:
  // Throws StoreError naming the file and the holder when another process holds the lock, or
  // naming the lock file when it cannot be created.
  explicit FileLock(const std::string& database_path);
  ~FileLock();
  FileLock(const FileLock&) = delete;
  FileLock& operator=(const FileLock&) = delete;

 private:
  int fd_ = -1;
};

}  // namespace dsb
