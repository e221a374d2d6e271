"""A damaged, foreign, future or read-only result store: every command says so in one line, and leaves it as it was."""

import shutil
import sqlite3

import pytest

from amronet.cli import main
from amronet.sweeps import ResultStore, StoreError
from sweep_helpers import tiny_sweep, write_sweep


@pytest.fixture(scope="module")
def good(tmp_path_factory):
    """A real store of a tiny sweep (6 runs), and the sweep file."""
    folder = tmp_path_factory.mktemp("good")
    sweep = write_sweep(folder / "tiny.yaml", tiny_sweep(seeds=3))
    store = folder / "good.sqlite"
    assert main(["sweep", str(sweep), "--store", str(store), "--workers", "1", "-q"]) == 0
    return store, sweep


def _poke(path, offset, data):
    with path.open("r+b") as fh:
        fh.seek(offset)
        fh.write(data)


def _runs_root_page(path) -> int:
    con = sqlite3.connect(path)
    try:
        return con.execute("SELECT rootpage FROM sqlite_master WHERE name = 'runs'").fetchone()[0]
    finally:
        con.close()


def _garble_runs_page(path):
    """Garbage over the runs table's root page (after its header): its rows cannot be read."""
    _poke(path, (_runs_root_page(path) - 1) * 4096 + 8, b"\xff" * 600)


def _bad_utf8(path):
    """Two bytes inside a stored summary that are not UTF-8; the pages themselves are sound."""
    raw = path.read_bytes()
    _poke(path, raw.index(b'{"algorithm"') + 2, b"\xff\xfe")


def _not_json(path):
    """A stored summary that is UTF-8 but no longer JSON."""
    _poke(path, path.read_bytes().index(b'{"algorithm"'), b"#")


def _future(path):
    con = sqlite3.connect(path)
    con.execute("PRAGMA user_version = 99")
    con.commit()
    con.close()


DAMAGE = {
    "garbled-page": (_garble_runs_page, "is damaged (database disk image is malformed"),
    "not-utf8": (_bad_utf8, "is damaged (Could not decode to UTF-8 column 'summary')"),
    "not-json": (_not_json, "is damaged (summary is not JSON"),
    "truncated": (lambda p: p.write_bytes(p.read_bytes()[:5 * 4096]), "is damaged (database disk image is malformed"),
    "future-schema": (_future, "was written by a newer amronet (schema 99); upgrade amronet"),
    "text-file": (lambda p: p.write_text("hello\n" * 100), "is not a SQLite database"),
}

COMMANDS = {
    "results": lambda s, sweep, out: ["results", str(s)],
    "results-sweep": lambda s, sweep, out: ["results", str(s), "--sweep", "tiny"],
    "export-csv": lambda s, sweep, out: ["results", str(s), "--export", "csv", "--out", str(out / "csv")],
    "plot": lambda s, sweep, out: ["plot", str(s), "--x", "radio.r_c", "--y", "coverage", "--out",
                                   str(out / "p.png")],
    "sweep": lambda s, sweep, out: ["sweep", str(sweep), "--store", str(s), "--workers", "1", "-q"],
}


def _one_error_line(capsys) -> str:
    err = capsys.readouterr().err
    lines = err.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("amronet: error: "), err
    assert "Traceback" not in err
    return lines[0]


@pytest.mark.parametrize("damage", list(DAMAGE))
@pytest.mark.parametrize("command", list(COMMANDS))
def test_a_damaged_store_is_one_line_exit_2_and_left_as_it_was(good, tmp_path, capsys, damage, command):
    store = tmp_path / "r.sqlite"
    shutil.copy(good[0], store)
    spoil, says = DAMAGE[damage]
    spoil(store)
    before = store.read_bytes()
    out = tmp_path / "out"
    out.mkdir()
    assert main(COMMANDS[command](store, good[1], out)) == 2
    line = _one_error_line(capsys)
    assert says in line and "r.sqlite" in line, line
    if damage not in ("future-schema", "text-file"):
        assert "sqlite3 " in line and ".recover" in line, line
    assert store.read_bytes() == before
    assert sorted(p.name for p in tmp_path.iterdir()) == ["out", "r.sqlite"]
    assert list(out.iterdir()) == []


def test_damage_that_reads_without_error_is_found_before_a_sweep_writes(good, tmp_path, capsys):
    """A zeroed page of the runs table reads as rows that break its CHECK: a sweep would have run them again."""
    store = tmp_path / "r.sqlite"
    shutil.copy(good[0], store)
    con = sqlite3.connect(store)
    pages = [p for (p,) in con.execute("SELECT pageno FROM dbstat WHERE name = 'runs' AND pagetype = 'leaf'")] \
        if con.execute("SELECT 1 FROM pragma_compile_options WHERE compile_options = 'ENABLE_DBSTAT_VTAB'"
                       ).fetchone() else []
    con.close()
    if not pages:
        pytest.skip("this SQLite has no dbstat table to find the runs table's pages")
    page = pages[0]
    _poke(store, (page - 1) * 4096 + 4096 // 2, b"\x00" * (4096 // 2))
    before = store.read_bytes()
    assert main(COMMANDS["sweep"](store, good[1], tmp_path)) == 2
    line = _one_error_line(capsys)
    assert "is damaged (database disk image is malformed" in line and ".recover" in line, line
    assert store.read_bytes() == before


def test_a_read_only_store_is_one_line(good, tmp_path, capsys, monkeypatch):
    """A store SQLite may not write to (read-only file or folder; root ignores permissions, so it is simulated)."""
    store = tmp_path / "r.sqlite"
    shutil.copy(good[0], store)
    before = store.read_bytes()
    connect = sqlite3.connect

    def read_only(path, *args, **kwargs):
        return connect(f"file:{path}?mode=ro", *args, uri=True, **kwargs)

    monkeypatch.setattr("amronet.sweeps.store_schema.sqlite3.connect", read_only)
    assert main(COMMANDS["sweep"](store, good[1], tmp_path)) == 2
    line = _one_error_line(capsys)
    assert "--store: " in line and "r.sqlite' is read-only (attempt to write a readonly database" in line, line
    assert store.read_bytes() == before


def test_the_library_raises_store_error_naming_the_file(good, tmp_path):
    store = tmp_path / "r.sqlite"
    shutil.copy(good[0], store)
    _garble_runs_page(store)
    with ResultStore(store, must_exist=True) as st, pytest.raises(StoreError, match=r"r\.sqlite' is damaged"):
        st.runs()
