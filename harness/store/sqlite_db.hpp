#pragma once
// Thin RAII layer over the SQLite C API: a connection, prepared statements, transactions.
// Every failure throws StoreError carrying SQLite's message.
#include <cstdint>
#include <optional>
#include <stdexcept>
#include <string>

struct sqlite3;
struct sqlite3_stmt;

namespace dsb {

struct StoreError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

class Statement {
 public:
  Statement(sqlite3* db, const std::string& sql);
  ~Statement();
  Statement(const Statement&) = delete;
  Statement& operator=(const Statement&) = delete;

  Statement& bind(int index, std::int64_t v);
  Statement& bind(int index, double v);  // NaN binds as NULL (SQLite has no NaN)
  Statement& bind(int index, const std::string& v);
  Statement& bind_null(int index);
  Statement& bind_blob(int index, const std::string& bytes);
  bool step();  // true while a row is available
  void run();   // step to completion
  void reset();
  std::int64_t column_int(int col) const;
  double column_double(int col) const;  // NULL reads as NaN
  std::string column_text(int col) const;
  std::string column_blob(int col) const;
  bool column_is_null(int col) const;
  int column_type(int col) const;  // SQLite's type code: 1 integer, 2 real, 3 text, 4 blob, 5 NULL

 private:
  sqlite3* db_;
  sqlite3_stmt* stmt_ = nullptr;
};

// UsageError naming the option when `path` cannot be a database file: it exists and is not a
// regular file ("--db: 'PATH' is a FIFO (named pipe), not a regular file": the same words from every
// command), or it is missing and must_exist ("--db: 'PATH': no such file"). Looks at the path
// without opening it, so a FIFO or a device never blocks the command. Database refuses such a path
// too; commands check first so that the message names their option.
void check_database_path(const std::string& option, const std::string& path, bool must_exist);

class Database {
 public:
  enum class Mode { write_create, write, read_only };
  // Opens a database file (write_create: creating it if needed); throws StoreError naming the
  // path when it cannot be opened in that mode. read_only also reads a WAL database that SQLite
  // cannot open read-only because its -shm file cannot be made (a read-only folder or mount):
  // when it has no -wal frames, the file is opened as immutable. A read_only open of a database
  // that no connection has open (no -wal, -shm or -journal beside it) leaves none behind either.
  explicit Database(const std::string& path, Mode mode = Mode::write_create);
  ~Database();
  Database(const Database&) = delete;
  Database& operator=(const Database&) = delete;

  void exec(const std::string& sql);
  sqlite3* handle() const { return db_; }
  const std::string& path() const { return path_; }

 private:
  void open(const std::string& name, int flags);
  void open_immutable();  // closes what is open, then opens path_ as immutable, read-only
  bool readable();        // false when a first read fails for want of write access (READONLY, CANTOPEN)
  static bool wal_has_frames(const std::string& path);
  static bool has_sidecar_files(const std::string& path);  // a -wal, -shm or -journal beside it
  static std::string immutable_uri(const std::string& path);

  sqlite3* db_ = nullptr;
  std::string path_;
};

// BEGIN IMMEDIATE ... COMMIT, rolled back when destroyed without commit()
class Transaction {
 public:
  explicit Transaction(Database& db);
  ~Transaction();
  void commit();

 private:
  Database& db_;
  bool done_ = false;
};

}  // namespace dsb
