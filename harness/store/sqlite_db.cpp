#include "harness/store/sqlite_db.hpp"

#include <sys/stat.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <limits>

#include <fmt/format.h>

#include <sqlite3.h>

#include "common/error.hpp"
#include "common/regular_file.hpp"

namespace dsb {

namespace {

// "database 'FILE': MESSAGE": what SQLite said, naming the file it said it about
std::string error_of(sqlite3* db) {
  const char* file = sqlite3_db_filename(db, "main");
  return std::string("database '") + (file && *file ? file : "(temporary)") + "': " + sqlite3_errmsg(db);
}

}  // namespace

Statement::Statement(sqlite3* db, const std::string& sql) : db_(db) {
  if (sqlite3_prepare_v2(db, sql.c_str(), -1, &stmt_, nullptr) != SQLITE_OK) throw StoreError(error_of(db));
}

Statement::~Statement() { sqlite3_finalize(stmt_); }

Statement& Statement::bind(int index, std::int64_t v) {
  sqlite3_bind_int64(stmt_, index, v);
  return *this;
}

Statement& Statement::bind(int index, double v) {
  if (std::isnan(v))
    sqlite3_bind_null(stmt_, index);
  else
    sqlite3_bind_double(stmt_, index, v);
  return *this;
}

Statement& Statement::bind(int index, const std::string& v) {
  sqlite3_bind_text(stmt_, index, v.data(), static_cast<int>(v.size()), SQLITE_TRANSIENT);
  return *this;
}

Statement& Statement::bind_blob(int index, const std::string& bytes) {
  sqlite3_bind_blob(stmt_, index, bytes.data(), static_cast<int>(bytes.size()), SQLITE_TRANSIENT);
  return *this;
}

Statement& Statement::bind_null(int index) {
  sqlite3_bind_null(stmt_, index);
  return *this;
}

bool Statement::step() {
  const int rc = sqlite3_step(stmt_);
  if (rc == SQLITE_ROW) return true;
  if (rc == SQLITE_DONE) return false;
  throw StoreError(error_of(db_));
}

void Statement::run() {
  while (step()) {}
  reset();
}

void Statement::reset() {
  sqlite3_reset(stmt_);
  sqlite3_clear_bindings(stmt_);
}

std::int64_t Statement::column_int(int col) const { return sqlite3_column_int64(stmt_, col); }

double Statement::column_double(int col) const {
  if (sqlite3_column_type(stmt_, col) == SQLITE_NULL) return std::numeric_limits<double>::quiet_NaN();
  return sqlite3_column_double(stmt_, col);
}

std::string Statement::column_text(int col) const {
  const auto* p = sqlite3_column_text(stmt_, col);
  return p ? std::string(reinterpret_cast<const char*>(p)) : std::string();
}

std::string Statement::column_blob(int col) const {
  const auto* p = static_cast<const char*>(sqlite3_column_blob(stmt_, col));
  return p ? std::string(p, static_cast<std::size_t>(sqlite3_column_bytes(stmt_, col))) : std::string();
}

int Statement::column_type(int col) const { return sqlite3_column_type(stmt_, col); }

bool Statement::column_is_null(int col) const { return sqlite3_column_type(stmt_, col) == SQLITE_NULL; }

void check_database_path(const std::string& option, const std::string& path, bool must_exist) {
  if (path.empty()) throw UsageError(option + " must name a file, got ''");
  if (must_exist)
    require_regular_file(option, path);
  else
    refuse_special_file(option, path);
}

Database::Database(const std::string& path, Mode mode) : path_(path) {
  // SQLite's open(2) of a FIFO for reading waits for a writer forever: refused before it
  refuse_special_file("database", path);
  // A read-only connection to a WAL database makes its -wal and -shm files and, read-only, cannot
  // delete them when it closes. Where no connection has them open (neither exists, nor a rollback
  // journal), a read opens read-write under query_only instead, so that SQLite's own close removes
  // what it made; where they exist (a grid writing, a writer that was killed) they are left as found
  const bool untouched = mode == Mode::read_only && !has_sidecar_files(path);
  // ... but a file the user may not write opens read-only whatever the flags say, and its folder
  // may still let SQLite make the files: with no connection on it, the file alone is the whole
  // database, read as immutable (no -shm, no locks)
  if (untouched && ::access(path.c_str(), W_OK) != 0 && ::access(path.c_str(), R_OK) == 0) {
    open_immutable();
  } else {
    const bool read_write = mode != Mode::read_only || untouched;
    const int flags = (read_write ? SQLITE_OPEN_READWRITE : SQLITE_OPEN_READONLY) |
        (mode == Mode::write_create ? SQLITE_OPEN_CREATE : 0) | SQLITE_OPEN_FULLMUTEX;
    open(path, flags);
    if (untouched && sqlite3_exec(db_, "PRAGMA query_only = ON", nullptr, nullptr, nullptr) != SQLITE_OK) {
      sqlite3_close(db_);
      db_ = nullptr;
      throw StoreError("cannot open database '" + path + "' for reading: PRAGMA query_only failed");
    }
    // A WAL database read where its -shm file cannot be made (a read-only folder or mount, a file
    // the user may not write): with no -wal frames the file alone is the whole database, which
    // SQLite then reads as immutable (no -shm, no locks)
    if (mode == Mode::read_only && !readable() && !wal_has_frames(path)) open_immutable();
    if (mode != Mode::read_only && sqlite3_db_readonly(db_, "main") == 1) {
      sqlite3_close(db_);
      db_ = nullptr;
      throw StoreError("cannot open database '" + path + "' for writing");
    }
  }
  sqlite3_busy_timeout(db_, 10000);
}

void Database::open(const std::string& name, int flags) {
  const int rc = sqlite3_open_v2(name.c_str(), &db_, flags, nullptr);
  if (rc != SQLITE_OK) {
    const std::string msg = db_ ? sqlite3_errmsg(db_) : "out of memory";
    sqlite3_close(db_);
    db_ = nullptr;
    throw StoreError("cannot open database '" + path_ + "': " + msg);
  }
}

void Database::open_immutable() {
  sqlite3_close(db_);  // a no-op on nullptr
  db_ = nullptr;
  open(immutable_uri(path_), SQLITE_OPEN_READONLY | SQLITE_OPEN_URI | SQLITE_OPEN_FULLMUTEX);
}

bool Database::readable() {
  const int rc = sqlite3_exec(db_, "SELECT count(*) FROM sqlite_master", nullptr, nullptr, nullptr);
  const int primary = rc & 0xff;
  return !(primary == SQLITE_READONLY || primary == SQLITE_CANTOPEN);
}

bool Database::has_sidecar_files(const std::string& path) {
  std::error_code ec;
  for (const char* suffix : {"-wal", "-shm", "-journal"})
    if (std::filesystem::exists(path + suffix, ec) || ec) return true;
  return false;
}

bool Database::wal_has_frames(const std::string& path) {
  struct stat st {};
  return ::stat((path + "-wal").c_str(), &st) == 0 && st.st_size > 0;
}

std::string Database::immutable_uri(const std::string& path) {
  // file:ABSOLUTE?immutable=1, with the characters a URI gives meaning to escaped
  std::string uri = "file:";
  for (const char c : std::filesystem::absolute(path).string()) {
    if (c == '%' || c == '?' || c == '#')
      uri += fmt::format("%{:02X}", static_cast<unsigned char>(c));
    else
      uri += c;
  }
  return uri + "?immutable=1";
}

Database::~Database() { sqlite3_close(db_); }

void Database::exec(const std::string& sql) {
  char* err = nullptr;
  if (sqlite3_exec(db_, sql.c_str(), nullptr, nullptr, &err) != SQLITE_OK) {
    std::string msg = err ? err : "unknown error";
    sqlite3_free(err);
    throw StoreError("sqlite: " + msg + " (database '" + path_ + "')");
  }
}

Transaction::Transaction(Database& db) : db_(db) { db_.exec("BEGIN IMMEDIATE"); }

Transaction::~Transaction() {
  if (!done_) {
    try {
      db_.exec("ROLLBACK");
    } catch (...) {}
  }
}

void Transaction::commit() {
  db_.exec("COMMIT");
  done_ = true;
}

}  // namespace dsb
