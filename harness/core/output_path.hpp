#pragma once
// Where a command may write. No command writes over a SQLite database (a harness database above
// all) or one of its -wal, -shm and -journal files, whatever path names it and even with --force:
// the file is recognised by its content, so `./x`, a symbolic link and a hard link are the same
// file. Any other existing file is written over only with --force. A file is written under a
// temporary name beside its destination and moved into place once complete, so a command that
// fails or is stopped half-way leaves no partial file; without --force the move itself refuses a
// path that appeared meanwhile (renameat2 RENAME_NOREPLACE, or link() where that is missing).
// A folder of outputs (a report, an IOHprofiler export) must be new, empty, or one the command
// made before; --force lets it write into another folder, over files of its own names only.
#include <fstream>
#include <functional>
#include <string>

namespace dsb {

// What is at `path`, read through symbolic links: nothing, a SQLite database or one of its
// sidecar files, a folder, a device or pipe (written as it goes: /dev/null, /dev/stdout), or
// another file (a dangling link included).
enum class PathKind { missing, sqlite, folder, stream, other };
PathKind path_kind(const std::string& path);

// True when a and b name the same existing file (device and inode, links resolved).
bool same_file(const std::string& a, const std::string& b);

// UsageError "OPTION: 'PATH' ..." when a file may not be written at `path`: a folder, a SQLite
// database or its sidecar (even with force), an existing file or link without force, or a
// missing parent folder.
void check_output_file(const std::string& option, const std::string& path, bool force);

// A file written whole or not at all: check_output_file, then a temporary file beside `path`
// (created exclusively), which commit() moves to `path`. Destroyed without commit(), the
// temporary file is removed and `path` is untouched.
class OutputFile {
 public:
  OutputFile(std::string option, std::string path, bool force);
  ~OutputFile();
  OutputFile(const OutputFile&) = delete;
  OutputFile& operator=(const OutputFile&) = delete;

  std::ofstream& stream() { return out_; }
  // closes the stream and moves the file into place; UsageError naming the path when writing
  // failed or (without force) the path exists by now
  void commit();

 private:
  std::string option_, path_, temp_;
  bool force_;
  bool committed_ = false;
  std::ofstream out_;
};

// UsageError "OPTION: 'PATH' ..." when outputs may not go into the folder `path`: a file is
// there, or a folder that is neither empty nor ours (is_ours(path)) and force is not given (the
// message names force_flag when the command has one). A missing folder is fine (the command
// creates it).
void check_output_folder(const std::string& option, const std::string& path, bool force,
                         const std::function<bool(const std::string&)>& is_ours,
                         const std::string& force_flag = "--force");

}  // namespace dsb
