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


def test_configure_uses_the_folder_and_keeps_the_newest_versions(package, tmp_path, monkeypatch):
    monkeypatch.delenv("NUMBA_CACHE_DIR", raising=False)
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path / "xdg"))
    monkeypatch.setattr(numba.config, "CACHE_DIR", numba.config.CACHE_DIR)  # restored after the test
    root = tmp_path / "xdg" / "amronet"
    root.mkdir(parents=True)
    old = []
    for k in range(kernel_cache.KEEP + 3):  # older versions, the oldest first
        folder = root / f"numba-old{k:02d}"
        folder.mkdir()
        stamp = time.time() - 1000 + k
        os.utime(folder, (stamp, stamp))
        old.append(folder)
    (root / "notes.txt").write_text("not ours to remove")
    folder = kernel_cache.configure()
    assert folder == kernel_cache.cache_folder(root) and folder.is_dir()
    assert numba.config.CACHE_DIR == str(folder)
    left = sorted(p.name for p in root.glob("numba-*"))
    assert left == sorted([folder.name, *(p.name for p in old[-(kernel_cache.KEEP - 1):])])
    assert (root / "notes.txt").read_text() == "not ours to remove"


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
