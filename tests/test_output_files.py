"""Output folders: written atomically, and never over what amronet did not write (amronet.outputs.files)."""

import json
import os

import pytest

from amronet.cli import main
from amronet.errors import AmronetError
from amronet.outputs.files import MANIFEST, check_output_folder, write_files_atomically

FAST = ["--set", "sim.time_limit=2", "--no-snapshot"]


def tree(folder):
    """Every file under ``folder`` with its bytes, and every folder, relative to it."""
    out = {}
    for root, dirs, files in os.walk(folder):
        for d in dirs:
            out[os.path.relpath(os.path.join(root, d), folder) + "/"] = None
        for f in files:
            path = os.path.join(root, f)
            with open(path, "rb") as fh:
                out[os.path.relpath(path, folder)] = fh.read()
    return out


def run(argv, capsys):
    code = main(argv)
    return code, capsys.readouterr()


def test_a_users_folder_is_refused_and_untouched(tmp_path, capsys):
    out = tmp_path / "out"
    (out / "data").mkdir(parents=True)
    (out / "thesis.tex").write_text("\\chapter{Results}")
    (out / "data" / "raw.csv").write_text("1,2\n")
    before = tree(tmp_path)
    code, cap = run(["run", "--preset", "self-spreading-6x6", "--seed", "1", "--out", str(out), *FAST], capsys)
    assert code == 2
    assert cap.err.count("\n") == 1 and "--out" in cap.err and "thesis.tex" in cap.err and "data/" in cap.err
    assert "Traceback" not in cap.err
    assert tree(tmp_path) == before


def test_a_scenario_inside_the_out_folder_is_not_deleted(tmp_path, capsys):
    out = tmp_path / "exp"
    out.mkdir()
    scenario = out / "scenario.yaml"
    scenario.write_text("map: open-6x6\nbase_stations: [{x: 0, y: 0}]\n")
    code, cap = run(["run", str(scenario), "--seed", "1", "--out", str(out), *FAST], capsys)
    assert code == 2 and "scenario.yaml" in cap.err
    assert scenario.read_text().startswith("map: open-6x6")


@pytest.mark.parametrize("target", [".", "..", "", "   "])
def test_the_current_folder_its_parents_and_empty_paths_are_refused(tmp_path, monkeypatch, capsys, target):
    work = tmp_path / "a" / "b"
    work.mkdir(parents=True)
    monkeypatch.chdir(work)
    before = tree(tmp_path)
    code, cap = run(["run", "--preset", "self-spreading-6x6", "--seed", "1", "--out", target, *FAST], capsys)
    assert code == 2 and cap.err.count("\n") == 1 and "--out" in cap.err and "Traceback" not in cap.err
    assert tree(tmp_path) == before  # no .old- or .tmp- folder left behind


def test_a_folder_amronet_wrote_is_replaced_and_marked(tmp_path, capsys):
    out = tmp_path / "out"
    argv = ["run", "--preset", "self-spreading-6x6", "--seed", "1", "--out", str(out), *FAST]
    assert run(argv, capsys)[0] == 0
    manifest = json.loads((out / MANIFEST).read_text())
    assert sorted(manifest["files"]) == ["network.json", "summary.json", "timeseries.csv"]
    assert run(argv, capsys)[0] == 0  # again: the folder is ours
    assert sorted(p.name for p in out.iterdir()) == sorted([MANIFEST, "network.json", "summary.json",
                                                            "timeseries.csv"])
    assert not [p for p in tmp_path.iterdir() if p.name.startswith(".")]  # no staging left


def test_a_file_added_or_edited_in_amronet_s_folder_is_protected(tmp_path):
    out = tmp_path / "out"
    write_files_atomically(out, {"a.txt": b"x", "b.txt": b"y"})
    check_output_folder(out)
    (out / "notes.md").write_text("mine")
    with pytest.raises(AmronetError, match=r"notes\.md"):
        write_files_atomically(out, {"a.txt": b"z"})
    (out / "notes.md").unlink()
    (out / "b.txt").write_bytes(b"edited by hand")
    with pytest.raises(AmronetError, match=r"b\.txt"):
        check_output_folder(out)
    assert (out / "b.txt").read_bytes() == b"edited by hand"


def test_a_folder_without_a_manifest_or_with_a_broken_one_is_refused(tmp_path):
    out = tmp_path / "old"
    out.mkdir()
    (out / "summary.json").write_text("{}")
    with pytest.raises(AmronetError, match=r"summary\.json"):
        check_output_folder(out)
    (out / MANIFEST).write_text("not json")
    with pytest.raises(AmronetError, match=r"summary\.json"):
        check_output_folder(out)


def test_empty_folders_symlinks_and_files(tmp_path):
    (tmp_path / "empty").mkdir()
    write_files_atomically(tmp_path / "empty", {"a.txt": b"x"})
    assert (tmp_path / "empty" / "a.txt").read_bytes() == b"x"
    (tmp_path / "target").mkdir()
    (tmp_path / "link").symlink_to(tmp_path / "target")
    (tmp_path / "dangling").symlink_to(tmp_path / "nowhere")
    for link in ("link", "dangling"):  # refused, in words that say why: amronet writes only into a real folder
        with pytest.raises(AmronetError, match="is a symbolic link; amronet writes only into a real folder"):
            check_output_folder(tmp_path / link)
    (tmp_path / "file").write_text("x")
    with pytest.raises(AmronetError, match="exists and is not a folder"):
        check_output_folder(tmp_path / "file")


def test_run_out_a_link_to_a_folder_is_refused_as_a_link(tmp_path, capsys):
    (tmp_path / "target").mkdir()
    (tmp_path / "link").symlink_to(tmp_path / "target")
    code, cap = run(["run", "--preset", "self-spreading-6x6", "--out", str(tmp_path / "link"), *FAST, "-q"], capsys)
    assert code == 2 and cap.err.count("\n") == 1 and "is a symbolic link" in cap.err, cap.err
    assert "not a folder" not in cap.err and not any((tmp_path / "target").iterdir())


def test_kept_store_files_survive_and_count_as_amronet_s(tmp_path):
    out = tmp_path / "fig"
    out.mkdir()
    (out / "results.sqlite").write_bytes(b"store")
    (out / "results.sqlite-wal").write_bytes(b"wal")
    write_files_atomically(out, {"fig.csv": b"1"}, keep=("results.sqlite",))
    assert (out / "results.sqlite").read_bytes() == b"store" and (out / "results.sqlite-wal").read_bytes() == b"wal"
    write_files_atomically(out, {"fig.csv": b"2"}, keep=("results.sqlite",))
    with pytest.raises(AmronetError, match=r"results\.sqlite"):
        write_files_atomically(out, {"fig.csv": b"3"})  # not kept by this command: not ours to delete


def test_reproduce_refuses_a_users_folder_before_running(tmp_path, capsys):
    out = tmp_path / "fig5"
    out.mkdir()
    (out / "draft.txt").write_text("mine")
    code, cap = run(["reproduce", "fig5", "--quick", "--out", str(out), "--quiet"], capsys)
    assert code == 2 and "draft.txt" in cap.err
    assert sorted(p.name for p in out.iterdir()) == ["draft.txt"]  # no result store was created in it


def test_plan_and_export_refuse_a_users_folder(tmp_path, capsys):
    out = tmp_path / "mine"
    out.mkdir()
    (out / "keep.me").write_text("mine")
    code, cap = run(["plan", "--map", "open-6x6", "--base", "0.5,0.5", "--rc", "1", "--runs", "1",
                     "--out", str(out), "--quiet"], capsys)
    assert code == 2 and "keep.me" in cap.err
    store = tmp_path / "s.sqlite"
    from amronet.sweeps import ResultStore

    with ResultStore(store):
        pass
    code, cap = run(["results", str(store), "--export", "csv", "--out", str(out)], capsys)
    assert code == 2 and "keep.me" in cap.err
    assert sorted(p.name for p in out.iterdir()) == ["keep.me"]


def test_the_longest_name_the_file_system_takes_can_be_written(tmp_path, capsys):
    """Issue #45 (5c): staging names are amronet's own, not the output's name with a prefix (which overflowed)."""
    longest = os.pathconf(tmp_path, "PC_NAME_MAX")
    out = tmp_path / ("r" * longest)
    write_files_atomically(out, {"a.txt": b"y"})
    assert sorted(p.name for p in out.iterdir()) == [MANIFEST, "a.txt"]
    code, cap = run(["run", "--preset", "self-spreading-6x6", "--seed", "1", "--out", str(out), *FAST, "-q"], capsys)
    assert code == 0, cap.err  # replaced: the previous content is moved aside under a short name too
    assert sorted(p.name for p in out.iterdir()) == [MANIFEST, "network.json", "summary.json", "timeseries.csv"]
    picture = tmp_path / ("m" * (longest - 4) + ".png")
    code, cap = run(["maps", "show", "open-6x6", "--out", str(picture)], capsys)
    assert code == 0 and picture.stat().st_size > 0, cap.err
    assert sorted(p.name for p in tmp_path.iterdir()) == sorted([out.name, picture.name])  # nothing staged is left
