"""The store's durable memory: one SQLite database in WAL mode.

SQLite is embedded, crash-safe and on every machine. In WAL mode with
`synchronous=NORMAL` a commit survives `kill -9` of the process (the WAL is in
the OS page cache), which is the failure the issue asks for; `durable=True`
(`tspace serve --fsync`) sets `synchronous=FULL` to survive power loss too.
"""

from __future__ import annotations

import sqlite3
from collections.abc import Iterable, Iterator
from dataclasses import dataclass, field
from pathlib import Path

_SCHEMA = """
CREATE TABLE IF NOT EXISTS triples (
    space TEXT NOT NULL, g TEXT NOT NULL, s TEXT NOT NULL, p TEXT NOT NULL, o TEXT NOT NULL,
    ts TEXT NOT NULL DEFAULT '',
    PRIMARY KEY (space, g, s, p, o)
) WITHOUT ROWID;
CREATE TABLE IF NOT EXISTS log (
    space TEXT NOT NULL, seq INTEGER NOT NULL, payload BLOB NOT NULL,
    PRIMARY KEY (space, seq)
) WITHOUT ROWID;
CREATE TABLE IF NOT EXISTS prefixes (
    space TEXT NOT NULL, name TEXT NOT NULL, ns TEXT NOT NULL,
    PRIMARY KEY (space, name)
) WITHOUT ROWID;
"""

Row = tuple[str, str, str]


@dataclass
class Commit:
    """What one applied changeset does to the database."""

    space: str
    seq: int
    payload: bytes
    removed: list[tuple[str, Row]] = field(default_factory=list)
    added: list[tuple[str, Row, str]] = field(default_factory=list)
    prefixes: dict[str, str] = field(default_factory=dict)


class StoreDB:
    """Open (creating if needed) the database file under `data_dir`.

    Not thread-safe: one owner thread does every call.
    """

    def __init__(self, data_dir: Path, *, durable: bool = False, log_keep: int = 100_000) -> None:
        data_dir.mkdir(parents=True, exist_ok=True)
        self.path = data_dir / "space.sqlite3"
        self.log_keep = log_keep
        self._conn = sqlite3.connect(self.path, isolation_level=None, check_same_thread=False)
        self._conn.execute("PRAGMA journal_mode=WAL")
        self._conn.execute(f"PRAGMA synchronous={'FULL' if durable else 'NORMAL'}")
        self._conn.executescript(_SCHEMA)
        self._commits = 0

    def close(self) -> None:
        """Checkpoint and close the database."""
        self._conn.close()

    def spaces(self) -> list[str]:
        """Return the names of the spaces that have any data."""
        rows = self._conn.execute(
            "SELECT space FROM log UNION SELECT space FROM triples UNION SELECT space FROM prefixes"
        )
        return [r[0] for r in rows]

    def last_seq(self, space: str) -> int:
        """Return the sequence number of the last changeset of a space (0 if none)."""
        row = self._conn.execute("SELECT MAX(seq) FROM log WHERE space=?", (space,)).fetchone()
        return int(row[0] or 0)

    def triples(self, space: str) -> Iterator[tuple[str, str, str, str, str]]:
        """Yield `(g, s, p, o, ts)` of every stored triple of a space."""
        yield from self._conn.execute("SELECT g, s, p, o, ts FROM triples WHERE space=?", (space,))

    def prefixes(self, space: str) -> dict[str, str]:
        """Return the prefix bindings registered in a space."""
        rows = self._conn.execute("SELECT name, ns FROM prefixes WHERE space=?", (space,))
        return dict(rows.fetchall())

    def log(self, space: str, first: int, last: int) -> list[tuple[int, bytes]]:
        """Return the logged changesets `first..last` (inclusive) still kept."""
        rows = self._conn.execute(
            "SELECT seq, payload FROM log WHERE space=? AND seq BETWEEN ? AND ? ORDER BY seq",
            (space, first, last),
        )
        return rows.fetchall()

    def commit(self, commits: Iterable[Commit]) -> None:
        """Write a batch of applied changesets in one transaction."""
        cur = self._conn.cursor()
        cur.execute("BEGIN")
        try:
            for c in commits:
                cur.executemany(
                    "DELETE FROM triples WHERE space=? AND g=? AND s=? AND p=? AND o=?",
                    [(c.space, g, *row) for g, row in c.removed],
                )
                cur.executemany(
                    "INSERT OR REPLACE INTO triples (space, g, s, p, o, ts) VALUES (?,?,?,?,?,?)",
                    [(c.space, g, *row, ts) for g, row, ts in c.added],
                )
                cur.executemany(
                    "INSERT OR IGNORE INTO prefixes (space, name, ns) VALUES (?,?,?)",
                    [(c.space, n, ns) for n, ns in c.prefixes.items()],
                )
                cur.execute(
                    "INSERT INTO log (space, seq, payload) VALUES (?,?,?)",
                    (c.space, c.seq, c.payload),
                )
                self._commits += 1
                if self._commits % 1000 == 0:
                    cur.execute(
                        "DELETE FROM log WHERE space=? AND seq<=?", (c.space, c.seq - self.log_keep)
                    )
            cur.execute("COMMIT")
        except BaseException:
            cur.execute("ROLLBACK")
            raise

    def replace(
        self,
        space: str,
        rows: Iterable[tuple[str, str, str, str, str]],
        prefixes: dict[str, str],
        last: tuple[int, bytes],
    ) -> None:
        """Make a space a copy of another store's, in one transaction.

        `rows` are `(g, s, p, o, ts)` as `triples()` gives them; `last` is the
        `(seq, payload)` of the copy's last changeset, kept as the only log entry
        so that `last_seq()` and later changes continue from it.
        """
        cur = self._conn.cursor()
        cur.execute("BEGIN")
        try:
            for table in ("triples", "log", "prefixes"):
                cur.execute(f"DELETE FROM {table} WHERE space=?", (space,))
            cur.executemany(
                "INSERT INTO triples (space, g, s, p, o, ts) VALUES (?,?,?,?,?,?)",
                [(space, *row) for row in rows],
            )
            cur.executemany(
                "INSERT INTO prefixes (space, name, ns) VALUES (?,?,?)",
                [(space, n, ns) for n, ns in prefixes.items()],
            )
            cur.execute("INSERT INTO log (space, seq, payload) VALUES (?,?,?)", (space, *last))
            cur.execute("COMMIT")
        except BaseException:
            cur.execute("ROLLBACK")
            raise
