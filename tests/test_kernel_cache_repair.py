"""A damaged entry of the kernel cache is recompiled with one line of notice, never fatal (issue #45, point 2).

Each case compiles two tiny kernels of its own (not amronet's) into a cache folder under a temporary
``XDG_CACHE_HOME``, damages both entries the same way, and runs them again in a fresh process.
"""

from __future__ import annotations

import json
import os
import pickle
import shutil
import subprocess
import sys
from collections.abc import Callable
from pathlib import Path

import numba
import pytest

from amronet import kernel_cache
from amronet.cli.main import main

_KERNELS = """\
import numba

@numba.njit(cache=True)
def add(a, b):
    return a + b

@numba.njit(cache=True)
def twice(a):
    return 2 * a
"""

_RUN = """\
import json, sys
import amronet  # configures the kernel cache
from amronet import kernel_cache
sys.path.insert(0, sys.argv[1])
import tiny_kernels as k
assert k.add(1, 2) == 3 and k.twice(2.5) == 5.0
print(json.dumps({"folder": str(kernel_cache._folder), "hits": [len(k.add.stats.cache_hits),
                  len(k.twice.stats.cache_hits)]}))
"""


def _run(env: dict[str, str], source: Path) -> tuple[dict, str]:
    """Run the two kernels in a fresh process: what it printed on stdout (JSON) and its stderr."""
    done = subprocess.run([sys.executable, "-c", _RUN, str(source)], env=env, capture_output=True, text=True,
                          timeout=300)
    assert done.returncode == 0 and "Traceback" not in done.stderr, done.stderr
    return json.loads(done.stdout), done.stderr


@pytest.fixture(scope="module")
def compiled(tmp_path_factory: pytest.TempPathFactory) -> tuple[dict[str, str], Path, Path, Path]:
    """The environment, the kernels' folder, the cache folder in use and a pristine copy of it."""
    tmp = tmp_path_factory.mktemp("repair")
    source = tmp / "src"
    source.mkdir()
    (source / "tiny_kernels.py").write_text(_KERNELS)
    env = {k: v for k, v in os.environ.items() if not k.startswith("NUMBA_")}
    env["XDG_CACHE_HOME"] = str(tmp / "xdg")
    found, err = _run(env, source)
    assert found["hits"] == [0, 0] and err == ""
    folder = Path(found["folder"])
    assert len(list(folder.rglob("tiny_kernels.*.nbi"))) == 2
    pristine = tmp / "pristine"
    shutil.copytree(folder, pristine)
    return env, source, folder, pristine


def _empty(path: Path) -> None:
    path.write_bytes(b"")


def _garbled_index(path: Path) -> None:
    # numba's version pickle intact (so numba reads on), then junk where the source stamp and the index should be
    path.write_bytes(pickle.dumps(numba.__version__, protocol=-1) + b"\x80\x05garbled\xff\x00 index")


def _truncated(path: Path) -> None:
    data = path.read_bytes()
    path.write_bytes(data[: len(data) // 2])


def _garbled(path: Path) -> None:
    path.write_bytes(b"\x80\x04not a pickle at all \xde\xad\xbe\xef" * 3)


DAMAGE: dict[str, tuple[str, Callable[[Path], None]]] = {
    "empty .nbi": ("nbi", _empty),
    "garbled .nbi": ("nbi", _garbled_index),
    "truncated .nbc": ("nbc", _truncated),
    "garbled .nbc": ("nbc", _garbled),
}


@pytest.mark.parametrize("kind", list(DAMAGE))
def test_a_damaged_entry_is_recompiled_with_one_line_of_notice(compiled, kind):
    env, source, folder, pristine = compiled
    shutil.rmtree(folder)
    shutil.copytree(pristine, folder)
    suffix, damage = DAMAGE[kind]
    damaged = sorted(folder.rglob(f"tiny_kernels.*.{suffix}"))
    assert len(damaged) == 2  # both kernels' entries: still one notice
    for path in damaged:
        damage(path)
    found, err = _run(env, source)
    assert found["hits"] == [0, 0]  # recompiled, not loaded
    lines = err.splitlines()
    assert len(lines) == 1, err
    assert lines[0].startswith("amronet: discarded damaged entries of the kernel cache in ")
    assert str(folder) in lines[0] and "recompiling" in lines[0]
    # numba saved the recompiled kernels: sound files, loaded by the next process without a word
    found, err = _run(env, source)
    assert found["hits"] == [1, 1] and err == ""
    assert (folder / kernel_cache.STAMP).is_file()  # nothing but the damaged files went


def test_a_damaged_entry_in_the_users_numba_cache_dir_is_overwritten_not_removed(compiled, tmp_path):
    env, source, _, _ = compiled
    env = {**env, "NUMBA_CACHE_DIR": str(tmp_path / "mine")}
    _run(env, source)
    index = sorted((tmp_path / "mine").rglob("tiny_kernels.*.nbi"))
    data = sorted((tmp_path / "mine").rglob("tiny_kernels.*.nbc"))
    assert len(index) == len(data) == 2
    _empty(index[0])
    _garbled(data[1])
    found, err = _run(env, source)
    assert found["hits"] == [0, 0] and found["folder"] == "None"
    assert len(err.splitlines()) == 1 and "recompiling them, numba overwrites them" in err
    found, err = _run(env, source)  # numba wrote them again when it saved the recompiled kernels
    assert found["hits"] == [1, 1] and err == ""


@pytest.fixture
def managed_folder(tmp_path, monkeypatch) -> Path:
    monkeypatch.delenv("NUMBA_CACHE_DIR", raising=False)
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path / "xdg"))
    monkeypatch.setattr(numba.config, "CACHE_DIR", numba.config.CACHE_DIR)
    monkeypatch.setattr(kernel_cache, "_folder", kernel_cache._folder)  # configure() sets it: restored after
    return kernel_cache.configure()


def test_clear_removes_only_the_compiled_kernels_and_notes(managed_folder):
    folder = managed_folder
    sub = folder / "src_amronet_engine"
    sub.mkdir()
    ours = [folder / "compiled-all", sub / "walls.count-12.py311.nbi", sub / "walls.count-12.py311.1.nbc"]
    for path in ours:
        path.write_bytes(b"x")
    writing = sub / "walls.count-12.py311.nbi.tmp.0123abcd"  # another process is writing it: left alone
    writing.write_bytes(b"x")
    (sub / "notes.txt").write_text("mine")
    elsewhere = folder.parent / "other.nbi"
    elsewhere.write_bytes(b"x")
    (sub / "link.nbi").symlink_to(elsewhere)
    assert kernel_cache.clear() == 3
    assert not any(p.exists() for p in ours)
    assert writing.is_file() and (sub / "notes.txt").is_file() and elsewhere.is_file()
    assert (sub / "link.nbi").is_symlink() and (folder / kernel_cache.STAMP).is_file()


def test_compile_fresh_empties_the_cache_then_compiles(managed_folder, monkeypatch, capsys):
    import amronet.sim.warmup as warmup

    (managed_folder / "compiled-all").touch()
    seen = []
    monkeypatch.setattr(warmup, "warm_up", lambda **kw: seen.append(kernel_cache.compiled("all")) or 0.5)
    assert main(["compile", "--fresh", "--jobs", "1"]) == 0
    assert seen == [False]  # emptied before compiling
    out = capsys.readouterr().out
    assert f"emptied the kernel cache {managed_folder} (1 file removed)" in out


def test_compile_fresh_refuses_the_users_numba_cache_dir(monkeypatch, tmp_path, capsys):
    monkeypatch.setenv("NUMBA_CACHE_DIR", str(tmp_path / "mine"))
    monkeypatch.setattr(kernel_cache, "_folder", None)
    assert main(["compile", "--fresh"]) == 2
    err = capsys.readouterr().err
    assert len(err.splitlines()) == 1
    assert err.startswith("amronet: error: --fresh: the kernel cache is your NUMBA_CACHE_DIR")


def test_compile_help_names_fresh(capsys):
    with pytest.raises(SystemExit):
        main(["compile", "--help"])
    assert "--fresh" in capsys.readouterr().out
