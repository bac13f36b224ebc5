#pragma once
// One harness per results file, whatever path names it: an exclusive, non-blocking flock on the
// database file itself (created empty when missing, which SQLite takes as a new database). `./x`,
// a symbolic link and a hard link all open the same inode and so meet the same lock, and no
// sidecar file is left beside the database. The kernel releases the lock when the holder exits,
// however it exits, so a crash leaves no stale lock. A second harness is told who holds it (pid
// and host, read from /proc/locks; "holder unknown" on a filesystem that does not show it).
//
// The descriptor is close-on-exec, and must outlive every SQLite connection of this process to
// the file (Store declares the lock before its Database): closing any descriptor of a file drops
// the POSIX locks SQLite holds on it.
#include <string>

namespace dsb {

class FileLock {
 public:
  // Throws StoreError naming the file and the holder when another process holds the lock, or
  // naming the file when it cannot be opened for writing (a folder, no permission).
  explicit FileLock(const std::string& database_path);
  ~FileLock();
  FileLock(const FileLock&) = delete;
  FileLock& operator=(const FileLock&) = delete;

  // Whether `path` names the locked file now (same device and inode): false once the file was
  // moved, replaced or removed.
  bool names_locked_file(const std::string& path) const;
  // Where the locked file is now, as /proc/self/fd shows it; empty when it was deleted.
  std::string current_path() const;

 private:
  int fd_ = -1;
  unsigned long long device_ = 0, inode_ = 0;
};

}  // namespace dsb
