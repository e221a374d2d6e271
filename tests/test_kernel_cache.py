"""amronet's numba cache folder: one per version of the kernels' source, so no stale machine code is loaded."""

import os
import time

import numba
import pytest

from amronet import kernel_cache


@pytest.fixture
def package(tmp_path, monkeypatch):
    pkg = tmp_path / "pkg"
    (pkg / "engine").mkdir(parents=True)
    (pkg / "engine" / "walls.py").write_text("@njit(cache=True)\ndef count(): return 1\n")
    (pkg / "engine" / "hearing.py").write_text("from amronet.engine.robots import State\n"
                                               "@njit(cache=True)\ndef hear(): return count() + State.X\n")
    (pkg / "engine" / "robots.py").write_text("class State:\n    X = 1\n")
    (pkg / "cli.py").write_text("from amronet.engine.hearing import hear\ndef main(): pass\n")
    monkeypatch.setattr(kernel_cache, "_PACKAGE", pkg)
    monkeypatch.setattr(kernel_cache, "_folder", kernel_cache._folder)  # configure() sets it: restored after
    return pkg


def test_folder_changes_with_any_kernel_file_and_only_with_them(package, tmp_path):
    root = tmp_path / "cache"
    first = kernel_cache.cache_folder(root)
    assert first.parent == root and first.name.startswith("numba-")
    assert kernel_cache.cache_folder(root) == first  # deterministic
    (package / "cli.py").write_text("def main(): return 2\n")  # no kernels: the same cache
    assert kernel_cache.cache_folder(root) == first
    # a constant a kernel reads from a module without kernels: compiled into the kernel
    (package / "engine" / "robots.py").write_text("class State:\n    X = 2\n")
    second = kernel_cache.cache_folder(root)
    assert second != first
    # the callee changes, its caller's file does not: numba alone would load the caller's old code
    (package / "engine" / "walls.py").write_text("@njit(cache=True)\ndef count(): return 2\n")
    assert kernel_cache.cache_folder(root) not in (first, second)


def test_the_real_package_hashes_its_kernel_modules():
    sources = {p.name for p in kernel_cache._kernel_sources()}
    assert {"walls.py", "hearing.py", "neighbours.py", "motion.py"} <= sources
    assert {"robots.py", "occupancy.py"} <= sources  # constants the kernels read
    assert "kernel_cache.py" not in sources and "main.py" not in sources and "snapshot.py" not in sources


def _old_version(root, name, age):
    """A cache folder amronet made for an older version of the kernels, last used ``age`` seconds ago."""
    folder = root / name
    (folder / "src_amronet_engine").mkdir(parents=True)
    (folder / kernel_cache.STAMP).write_text(name + "\n")
    (folder / "compiled-all").touch()
    (folder / "src_amronet_engine" / "walls.count-12.py311.nbi").write_bytes(b"index")
    (folder / "src_amronet_engine" / "walls.count-12.py311.1.nbc").write_bytes(b"code")
    stamp = time.time() - age
    os.utime(folder, (stamp, stamp))
    return folder


@pytest.fixture
def cache_home(package, tmp_path, monkeypatch):
    """The cache root ``$XDG_CACHE_HOME/amronet``, with numba's settings restored after the test."""
    monkeypatch.delenv("NUMBA_CACHE_DIR", raising=False)
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path / "xdg"))
    monkeypatch.setattr(numba.config, "CACHE_DIR", numba.config.CACHE_DIR)
    root = tmp_path / "xdg" / "amronet"
    root.mkdir(parents=True)
    return root


def test_configure_uses_the_folder_and_keeps_the_newest_versions(cache_home):
    old = [_old_version(cache_home, f"numba-{k:016x}", 1000 - k) for k in range(kernel_cache.KEEP + 3)]
    (cache_home / "notes.txt").write_text("not ours to remove")
    folder = kernel_cache.configure()
    assert folder == kernel_cache.cache_folder(cache_home) and folder.is_dir()
    assert numba.config.CACHE_DIR == str(folder)
    assert (folder / kernel_cache.STAMP).read_text().strip() == folder.name
    left = sorted(p.name for p in cache_home.glob("numba-*"))
    assert left == sorted([folder.name, *(p.name for p in old[-(kernel_cache.KEEP - 1):])])
    assert (cache_home / "notes.txt").read_text() == "not ours to remove"


def test_folders_the_user_made_are_never_pruned_whatever_their_names(cache_home):
    """12 folders named like amronet's, each holding a file of the user's, all survive (the data-loss report)."""
    mine = []
    for k in range(12):
        name = f"numba-{k:016x}" if k % 2 else f"numba-mine{k}"
        folder = cache_home / name
        folder.mkdir()
        (folder / "thesis.tex").write_text(f"chapter {k}")
        stamp = time.time() - 5000 + k
        os.utime(folder, (stamp, stamp))
        mine.append(folder)
    # amronet's own old folders, but one with a user's file put inside and one whose stamp names another folder
    touched = _old_version(cache_home, "numba-00000000000000aa", 9000)
    (touched / "src_amronet_engine" / "results.csv").write_text("x,y\n")
    forged = _old_version(cache_home, "numba-00000000000000bb", 9000)
    (forged / kernel_cache.STAMP).write_text("numba-00000000000000cc\n")
    link = cache_home / "numba-00000000000000dd"
    link.symlink_to(mine[0], target_is_directory=True)
    for k in range(kernel_cache.KEEP + 2):  # enough amronet folders that every older one would go
        _old_version(cache_home, f"numba-{0xf00 + k:016x}", 100 + k)
    in_use = kernel_cache.configure()
    for k, folder in enumerate(mine):
        assert (folder / "thesis.tex").read_text() == f"chapter {k}"
    assert (touched / "src_amronet_engine" / "results.csv").is_file()
    assert forged.is_dir() and link.is_symlink() and (mine[0] / "thesis.tex").is_file()
    ours = [p for p in cache_home.iterdir() if p != in_use and kernel_cache._removable(p)]
    assert len(ours) == kernel_cache.KEEP - 1  # the newest of amronet's own, besides the one in use


def test_a_relative_xdg_cache_home_is_ignored(package, tmp_path, monkeypatch):
    monkeypatch.setenv("XDG_CACHE_HOME", "relative/cache")
    monkeypatch.setenv("HOME", str(tmp_path / "home"))
    assert kernel_cache.cache_folder().parent == tmp_path / "home" / ".cache" / "amronet"


def test_the_users_numba_cache_dir_wins(package, tmp_path, monkeypatch):
    monkeypatch.setenv("NUMBA_CACHE_DIR", str(tmp_path / "mine"))
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path / "xdg"))
    assert kernel_cache.configure() is None
    assert not (tmp_path / "xdg").exists()


def test_an_unwritable_cache_home_falls_back_to_numbas_default(package, tmp_path, monkeypatch):
    monkeypatch.delenv("NUMBA_CACHE_DIR", raising=False)
    blocker = tmp_path / "file"
    blocker.write_text("a file where the cache folder would go")
    monkeypatch.setenv("XDG_CACHE_HOME", str(blocker))
    monkeypatch.setattr(numba.config, "CACHE_DIR", "unchanged")
    assert kernel_cache.configure() is None
    assert numba.config.CACHE_DIR == "unchanged"


def test_warm_ups_are_noted_in_the_folder_of_the_kernels_version(package, tmp_path, monkeypatch):
    monkeypatch.delenv("NUMBA_CACHE_DIR", raising=False)
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path / "xdg"))
    monkeypatch.setattr(numba.config, "CACHE_DIR", numba.config.CACHE_DIR)
    folder = kernel_cache.configure()
    assert kernel_cache.compiled("all", "common") is False
    kernel_cache.mark_compiled("common")
    assert kernel_cache.compiled("common") is True and kernel_cache.compiled("all", "common") is True
    assert kernel_cache.compiled("all") is False
    assert (folder / "compiled-common").is_file()
    (package / "engine" / "walls.py").write_text("@njit(cache=True)\ndef count(): return 2\n")
    assert kernel_cache.configure() != folder  # a new version of the kernels: compiled by nobody yet
    assert kernel_cache.compiled("all", "common") is False


def test_nothing_is_noted_in_a_folder_amronet_does_not_manage(package, tmp_path, monkeypatch):
    monkeypatch.setenv("NUMBA_CACHE_DIR", str(tmp_path / "mine"))
    assert kernel_cache.configure() is None
    kernel_cache.mark_compiled("all")
    assert kernel_cache.compiled("all") is None  # unknown: warm_up_if_cold leaves the runs to compile
    assert not (tmp_path / "mine").exists()
