"""Opening a harness database to read it, leaving its folder as it was found (standard library only,
so the scripts that need nothing else can use it too). The rules are the harness's own
(harness/store/sqlite_db.hpp):

- SQLite's read-only connection to a WAL database makes the -wal and -shm files beside it and, being
  read-only, cannot remove them when it closes. Where no connection has the database open (no -wal,
  -shm or -journal beside it) the read opens read-write under PRAGMA query_only, so that SQLite's
  own close removes what it made; where they exist (a grid writing, a writer that was killed), it
  opens read-only and leaves them as found. A file the user may not write, with none of them beside
  it, opens as immutable: SQLite would open it read-only whatever the mode says and, its folder
  writable, make the files it could not remove.
- A WAL database whose -shm file cannot be made (a read-only folder or mount, a file the user may not
  write) and that has no -wal frames is the file alone: opened as immutable.
"""
from __future__ import annotations

import os
import sqlite3

SIDECARS = ("-wal", "-shm", "-journal")


def uri(path, query: str) -> str:
    """file:ABSOLUTE?query, with the characters a URI gives meaning to escaped."""
    escaped = os.path.abspath(os.fspath(path)).replace("%", "%25").replace("?", "%3f").replace("#", "%23")
    return f"file:{escaped}?{query}"


def has_sidecar_files(path) -> bool:
    return any(os.path.lexists(os.fspath(path) + s) for s in SIDECARS)


def wal_has_frames(path) -> bool:
    try:
        return os.path.getsize(os.fspath(path) + "-wal") > 0
    except OSError:
        return False


def connect(path) -> sqlite3.Connection:
    """A connection that reads `path` (str or path-like) and writes nothing; sqlite3.Error when it
    cannot be read."""
    untouched = not has_sidecar_files(path)
    if untouched and os.access(path, os.R_OK) and not os.access(path, os.W_OK):
        return immutable(path)
    con = sqlite3.connect(uri(path, "mode=rw" if untouched else "mode=ro"), uri=True)
    try:
        if untouched:
            con.execute("PRAGMA query_only = ON")
        con.execute("SELECT count(*) FROM sqlite_master").fetchone()
        return con
    except sqlite3.OperationalError as e:
        con.close()
        text = str(e)
        if wal_has_frames(path) or ("readonly" not in text and "unable to open" not in text):
            raise
    return immutable(path)


def immutable(path) -> sqlite3.Connection:
    """The file alone as the whole database: no -shm, no locks."""
    con = sqlite3.connect(uri(path, "immutable=1"), uri=True)
    try:
        con.execute("SELECT count(*) FROM sqlite_master").fetchone()
    except sqlite3.Error:
        con.close()
        raise
    return con
