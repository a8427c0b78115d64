"""The output layer (:mod:`vrneural.outputs`): output files checked before any work, atomic
writes, output directories that --force replaces only when vrneural wrote them, locks, and
sealing however a block ends, from the CLI or the Python API."""

import contextlib
import json
import re
import subprocess
import sys

import pytest

from vrneural.errors import VrnError
from vrneural.outputs import (
    OUTPUT_MARK,
    OutputDir,
    atomic_path,
    check_output,
    check_suffix,
    mark_output,
    read_mark,
)


def _written(path, command, files=("summary.json",)):
    """An output directory ``command`` wrote and sealed, holding ``files``."""
    with OutputDir(path, command, force=True) as out:
        out.open()
        for f in files:
            (out / f).write_text("{}")
    return path


def test_check_output_refuses_overwrite(tmp_path):
    f = tmp_path / "out.txt"
    f.write_text("keep")
    with pytest.raises(VrnError, match="--force"):
        check_output(f, force=False)
    assert check_output(f, force=True) == f
    assert f.read_text() == "keep"
    d = tmp_path / "somedir.pt"  # a directory where a file goes: said at once, --force or not
    d.mkdir()
    for force in (False, True):
        with pytest.raises(VrnError, match=r"somedir\.pt: output path is a directory"):
            check_output(d, force=force)


def test_checks_create_no_folder_and_writes_make_theirs(tmp_path):
    """A check makes nothing (a command that fails after it leaves no folder behind); the
    write makes the folders its file goes into; a file in the way is named at the check."""
    deep = tmp_path / "a" / "b" / "x.json"
    check_output(deep, force=False)
    assert list(tmp_path.iterdir()) == []
    with atomic_path(deep) as tmp:
        tmp.write_text("{}")
    assert deep.read_text() == "{}"
    (tmp_path / "f").write_text("")
    with pytest.raises(VrnError, match=r"cannot create output directory \(.*f is a file"):
        check_output(tmp_path / "f" / "g" / "x.json", force=False)


def test_atomic_path_leaves_original_on_failure(tmp_path):
    f = tmp_path / "out.txt"
    f.write_text("keep")
    with pytest.raises(RuntimeError), atomic_path(f) as tmp:
        tmp.write_text("half")
        raise RuntimeError("boom")
    assert f.read_text() == "keep"
    assert list(tmp_path.iterdir()) == [f]


def test_force_replaces_only_directories_vrneural_wrote(tmp_path):
    mine = tmp_path / "mine"
    mine.mkdir()
    (mine / "thesis.tex").write_text("keep")
    # result files that look like ours do not make a folder ours: only the marker does
    (mine / "results.json").write_text(json.dumps({"benchmark": "frames", "records": []}))
    (mine / "summary.json").write_text(json.dumps({"adapter": 1, "resolved": 1, "per_frame": 1}))
    with pytest.raises(VrnError, match="not a vrneural output directory"):
        OutputDir(mine, "run", force=True).check()
    assert (mine / "thesis.tex").read_text() == "keep"
    # our own output: --force replaces it, without --force it is refused
    run = tmp_path / "run"
    with OutputDir(run, "run") as out:
        out.check()
        out.open()
        (run / "summary.json").write_text("{}")
        (run / "frames").mkdir()
    with pytest.raises(VrnError, match="pass --force"):
        OutputDir(run, "run").check()
    with OutputDir(run, "run", force=True) as out:
        out.check()
        out.open()
        assert sorted(p.name for p in run.iterdir()) == [OUTPUT_MARK]
        # another command's output is never replaced (a run --force over bench quality's)
        (run / "summary.json").write_text("{}")
    for command in ("bench quality", "bench frames"):
        with pytest.raises(VrnError, match="holds the output of `vrneural run`, not of"):
            OutputDir(run, command, force=True).check()
    # files added after the command sealed its output: --force refuses and names them
    (run / "notes.md").write_text("mine")
    (run / "sub").mkdir()
    with pytest.raises(VrnError, match=r"2 file\(s\) vrneural did not write there \(notes.md, sub"):
        OutputDir(run, "run", force=True).check()
    stale = OutputDir(run, "run", force=True)
    stale.checked = True  # a stale check cannot delete them either: open() checks again
    with pytest.raises(VrnError, match="did not write there"), stale:
        stale.open()
    assert (run / "notes.md").read_text() == "mine" and (run / "summary.json").exists()
    # a marker this release cannot read (an older one) is another command's
    (run / OUTPUT_MARK).write_text("written by vrneural; --force may replace this directory\n")
    with pytest.raises(VrnError, match="output of an older vrneural release"):
        OutputDir(run, "run", force=True).check()
    # an empty directory needs no flag
    empty = tmp_path / "empty"
    empty.mkdir()
    OutputDir(empty, "run").check()


def test_an_unfinished_output_is_refused_and_every_ending_seals(tmp_path):
    """A command that was killed never sealed its output: --force cannot tell its files from
    ones added since, so it refuses. Any other ending of the block seals it, an error too,
    after which added files are told apart."""
    out = tmp_path / "o"
    out.mkdir()
    mark_output(out, "run", sealed=False)  # as a killed process leaves it
    (out / "frame0000_eye0.png").write_bytes(b"png")
    with pytest.raises(VrnError, match="an unfinished `vrneural run` output"):
        OutputDir(out, "run", force=True).check()
    assert read_mark(out)["entries"] is None
    with pytest.raises(RuntimeError, match="boom"), OutputDir(out, "run", resume=True) as o:
        o.open()
        raise RuntimeError("boom")
    assert read_mark(out)["entries"] == ["frame0000_eye0.png"]
    (out / "notes.md").write_text("mine")
    with pytest.raises(VrnError, match=r"did not write there \(notes.md\)"):
        OutputDir(out, "run", force=True).check()
    # a caller that deletes nothing (bench quality) is not refused for either reason
    OutputDir(out, "run", resume=True).check()
    assert sorted(p.name for p in out.iterdir()) == [OUTPUT_MARK, "frame0000_eye0.png", "notes.md"]


def test_the_python_api_seals_its_outputs_too(tmp_path):
    """The issue's example: a folder marked and written by a caller that is not the CLI, which
    returns; the next --force (of the CLI) replaces it instead of calling it unfinished."""
    from distill_helpers import run_cli

    def write_from_python(path):
        with OutputDir(path, "bench tradeoff") as out:
            out.open()
            (out / "results.json").write_text("{}")
            return "done"  # returned mid-block: sealed all the same

    o = tmp_path / "o"
    assert write_from_python(o) == "done"
    assert read_mark(o)["entries"] == ["results.json"]
    code, err = run_cli("bench", "tradeoff", "--quick", "--out", o)
    assert code == 2 and "output exists; pass --force to overwrite" in err
    # --force passes the output's checks and empties it (then this bench stops on free space)
    argv = ["bench", "tradeoff", "--quick", "--btf-dirs", 100000, "--force", "--out", o]
    code, err = run_cli(*argv)
    assert code == 2 and "needs" in err and "free" in err and "killed" not in err, err
    assert not (o / "results.json").exists()
    with OutputDir(o, "bench tradeoff", force=True) as out:  # and from Python, as before
        out.open()
    assert sorted(p.name for p in o.iterdir()) == [OUTPUT_MARK]


@contextlib.contextmanager
def _lock_held_by_another_process(d):
    """The lock of output ``d`` held by a child process, as a running command holds it."""
    holder = subprocess.Popen(
        [
            sys.executable,
            "-c",
            "import sys, time; from vrneural.outputs import output_lock\n"
            "with output_lock(sys.argv[1]): print('locked', flush=True); time.sleep(60)",
            str(d),
        ],
        stdout=subprocess.PIPE,
        text=True,
    )
    try:
        assert holder.stdout.readline().strip() == "locked"
        yield
    finally:
        holder.kill()
        holder.wait()


def test_an_output_directory_another_process_writes_is_refused(tmp_path):
    """Two commands given one --out: the second is a one-line error, not a race that empties
    the folder under the first (the lock is a flock, released however its holder ends)."""
    d = _written(tmp_path / "o", "run")  # a finished output: --force may replace it
    with _lock_held_by_another_process(d):
        with pytest.raises(VrnError, match="another vrneural process is writing this output"):
            with OutputDir(d, "run", force=True) as out:
                out.open()
    _written(d, "run")  # the holder is gone: its lock went with it


def test_an_unfinished_output_says_whether_its_writer_still_runs(tmp_path):
    """A second `--force` while the first command still writes its (unsealed) output was told
    "killed, or still running elsewhere"; the lock tells which."""
    d = tmp_path / "o"
    d.mkdir()
    (d / OUTPUT_MARK).write_text(json.dumps({"command": "run", "entries": None}))
    (d / "frame.png").write_bytes(b"x")
    with pytest.raises(
        VrnError, match=r"unfinished `vrneural run` output \(its process was killed"
    ):
        OutputDir(d, "run", force=True).check()
    with _lock_held_by_another_process(d):
        for force in (True, False):  # without --force too: "pass --force" would not help
            with pytest.raises(VrnError, match="another vrneural process is writing this"):
                OutputDir(d, "run", force=force).check()
    assert sorted(p.name for p in d.iterdir()) == [OUTPUT_MARK, "frame.png"]


def test_an_old_output_that_cannot_be_removed_is_one_line(tmp_path, monkeypatch):
    import pathlib

    d = _written(tmp_path / "o", "run", ["frame.png"])

    def read_only(self, *a, **k):
        raise OSError(30, "Read-only file system")

    monkeypatch.setattr(pathlib.Path, "unlink", read_only)
    with pytest.raises(VrnError, match=r"frame\.png: cannot remove the old output to replace it"):
        with OutputDir(d, "run", force=True) as out:
            out.open()


def test_a_file_system_without_locks_still_takes_outputs(tmp_path, monkeypatch):
    """flock can fail for reasons other than a holder (ENOLCK on some network mounts): then
    the output is written without the lock, not refused as busy."""
    import errno
    import fcntl

    def no_locks(fd, op):
        raise OSError(errno.ENOLCK, "No locks available")

    monkeypatch.setattr(fcntl, "flock", no_locks)
    d = _written(tmp_path / "o", "run")
    _written(d, "run")


def test_output_names_are_checked_in_one_place():
    check_suffix("a/b.pt", ".pt", "checkpoint", "run.pt")
    check_suffix("a/b.PNG", ".png", "image", "sheet.png", ignore_case=True)
    with pytest.raises(VrnError, match=re.escape("a/b.PT: output checkpoint must end in .pt")):
        check_suffix("a/b.PT", ".pt", "checkpoint", "run.pt")  # the pack would be a/b.vrnm
    for path, msg in (
        ("", "-o is empty; name the output checkpoint (e.g. -o run.pt)"),
        ("  ", "-o is empty"),
        ("x/.pt", "x/.pt: the output checkpoint needs a name before .pt (run.pt)"),
        ("x.pt/", "x.pt/: output checkpoint must end in .pt"),
        ("x.vrnm", "x.vrnm: output checkpoint must end in .pt"),
    ):
        with pytest.raises(VrnError, match=re.escape(msg)):
            check_suffix(path, ".pt", "checkpoint", "run.pt")


def test_a_failed_bench_all_takes_back_its_folders_deepest_first(tmp_path):
    """`bench all` stopped before any bench wrote: its sub-folder goes first, then its own
    folder, which held nothing else, then the folder made for it."""
    ba = tmp_path / "new" / "ba"
    with pytest.raises(KeyboardInterrupt), OutputDir(ba, "bench all", keep=True) as out:
        out.open()
        with OutputDir(ba / "frames", "bench frames") as sub:
            sub.open()
            raise KeyboardInterrupt
    assert list(tmp_path.iterdir()) == []


def test_seal_records_what_a_command_wrote(tmp_path):
    d = tmp_path / "o"
    d.mkdir()
    (d / "a.png").write_bytes(b"")
    mark_output(d, "run")
    assert read_mark(d) == {
        "written_by": "vrneural run",
        "command": "run",
        "entries": ["a.png"],
        "note": "--force of the same command may replace the entries listed here",
    }
