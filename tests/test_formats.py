"""The array container and atomic outputs: round trips and clear errors on bad files."""

import contextlib
import re
import subprocess
import sys

import numpy as np
import pytest

from vrneural.errors import VrnError
from vrneural.formats import (
    ContainerWriter,
    atomic_path,
    check_output,
    read_container,
    write_container,
)

MAGIC = b"VRNTEST"


def _write(tmp_path, rng):
    arrays = {
        "a": rng.standard_normal((3, 5)).astype(np.float32),
        "b": (rng.random(17) * 10).astype(np.float16),
        "empty": np.zeros((0, 4), np.uint32),
    }
    p = write_container(tmp_path / "x.bin", MAGIC, 3, {"name": "t"}, arrays)
    return p, arrays


def test_round_trip(tmp_path, rng):
    p, arrays = _write(tmp_path, rng)
    header, got, version = read_container(p, MAGIC, (3,))
    assert version == 3 and header["name"] == "t"
    for k, v in arrays.items():
        np.testing.assert_array_equal(got[k], v)
        assert got[k].dtype == v.dtype
    for a in header["arrays"].values():
        assert a["offset"] % 64 == 0


@pytest.mark.parametrize(
    ("damage", "message"),
    [
        (lambda b: b"XXXXXXXX" + b[8:], "wrong magic"),
        (lambda b: b[:8] + (9).to_bytes(4, "little") + b[12:], "version 9 is not supported"),
        (lambda b: b[:-10], "truncated"),
        (lambda b: b[:10], "truncated"),
        (lambda b: b[:40] + b"#" + b[41:], "corrupt header"),
        (lambda b: b[:-70] + bytes([b[-70] ^ 0xFF]) + b[-69:], "checksum"),
    ],
    ids=["magic", "version", "truncated-data", "truncated-prefix", "header", "data"],
)
def test_damaged_files_give_clear_errors(tmp_path, rng, damage, message):
    p, _ = _write(tmp_path, rng)
    p.write_bytes(damage(p.read_bytes()))
    with pytest.raises(VrnError, match=message) as e:
        read_container(p, MAGIC, (3,))
    assert str(p) in str(e.value) and "\n" not in str(e.value)


def test_missing_file(tmp_path):
    with pytest.raises(VrnError, match="no such file"):
        read_container(tmp_path / "nope", MAGIC, (1,))


def test_streaming_writer_resume(tmp_path):
    specs = {"v": ((4, 8), "float16")}
    w = ContainerWriter(tmp_path / "s.bin", MAGIC, 1, {"k": 1}, specs)
    w.array("v")[0] = 1.0
    w.array("v").flush()
    assert not (tmp_path / "s.bin").exists()  # nothing visible before finalize
    w2 = ContainerWriter(tmp_path / "s.bin", MAGIC, 1, {"k": 1}, specs, resume=True)
    assert w2.resumed
    w2.array("v")[1:] = 2.0
    w2.finalize()
    _, got, _ = read_container(tmp_path / "s.bin", MAGIC, (1,))
    assert got["v"][0, 0] == 1.0 and got["v"][3, 7] == 2.0
    w3 = ContainerWriter(tmp_path / "t.bin", MAGIC, 1, {"k": 2}, specs, resume=True)
    assert not w3.resumed  # nothing to resume: a fresh write
    before = w3.partial.read_bytes()
    with pytest.raises(VrnError, match="cannot be continued"):  # another header: kept
        ContainerWriter(tmp_path / "t.bin", MAGIC, 1, {"k": 3}, specs, resume=True)
    assert w3.partial.read_bytes() == before


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


def test_atomic_path_leaves_original_on_failure(tmp_path):
    f = tmp_path / "out.txt"
    f.write_text("keep")
    with pytest.raises(RuntimeError), atomic_path(f) as tmp:
        tmp.write_text("half")
        raise RuntimeError("boom")
    assert f.read_text() == "keep"
    assert list(tmp_path.iterdir()) == [f]


def test_force_replaces_only_directories_vrneural_wrote(tmp_path):
    import json

    from vrneural.formats.atomic import (
        OUTPUT_MARK,
        check_output_dir,
        make_output_dir,
        seal_output_dir,
    )

    mine = tmp_path / "mine"
    mine.mkdir()
    (mine / "thesis.tex").write_text("keep")
    # result files that look like ours do not make a folder ours: only the marker does
    (mine / "results.json").write_text(json.dumps({"benchmark": "frames", "records": []}))
    (mine / "summary.json").write_text(json.dumps({"adapter": 1, "resolved": 1, "per_frame": 1}))
    with pytest.raises(VrnError, match="not a vrneural output directory"):
        check_output_dir(mine, True, "run")
    assert (mine / "thesis.tex").read_text() == "keep"
    # our own output: --force replaces it, without --force it is refused
    run = tmp_path / "run"
    check_output_dir(run, False, "run")
    make_output_dir(run, "run")
    (run / "summary.json").write_text("{}")
    (run / "frames").mkdir()
    seal_output_dir(run, "run")
    with pytest.raises(VrnError, match="pass --force"):
        check_output_dir(run, False, "run")
    check_output_dir(run, True, "run")
    make_output_dir(run, "run")
    assert sorted(p.name for p in run.iterdir()) == [OUTPUT_MARK]
    # another command's output is never replaced (a run --force over bench quality checkpoints)
    (run / "summary.json").write_text("{}")
    seal_output_dir(run, "run")
    for command in ("bench quality", "bench frames"):
        with pytest.raises(VrnError, match="holds the output of `vrneural run`, not of"):
            check_output_dir(run, True, command)
    # files added after the command sealed its output: --force refuses and names them
    (run / "notes.md").write_text("mine")
    (run / "sub").mkdir()
    with pytest.raises(VrnError, match=r"2 file\(s\) vrneural did not write there \(notes.md, sub"):
        check_output_dir(run, True, "run")
    with pytest.raises(VrnError, match="did not write there"):
        make_output_dir(run, "run")  # a stale check cannot delete them either
    assert (run / "notes.md").read_text() == "mine" and (run / "summary.json").exists()
    # a marker this release cannot read (an older one) is another command's
    (run / OUTPUT_MARK).write_text("written by vrneural; --force may replace this directory\n")
    with pytest.raises(VrnError, match="output of an older vrneural release"):
        check_output_dir(run, True, "run")
    # an empty directory needs no flag
    empty = tmp_path / "empty"
    empty.mkdir()
    check_output_dir(empty, False, "run")


def test_an_unfinished_output_is_refused_and_every_ending_seals(tmp_path):
    """A command that was killed never sealed its output: --force cannot tell its files from
    ones added since, so it refuses. Any other ending seals (``seal_marked``, run by the CLI
    whatever the command's outcome), after which added files are told apart."""
    from vrneural.formats.atomic import (
        OUTPUT_MARK,
        check_output_dir,
        mark_output_dir,
        read_mark,
        seal_marked,
    )

    out = tmp_path / "o"
    mark_output_dir(out, "run")
    (out / "frame0000_eye0.png").write_bytes(b"png")
    with pytest.raises(VrnError, match="an unfinished `vrneural run` output"):
        check_output_dir(out, True, "run")
    assert read_mark(out)["entries"] is None
    seal_marked()
    assert read_mark(out)["entries"] == ["frame0000_eye0.png"]
    (out / "notes.md").write_text("mine")
    with pytest.raises(VrnError, match=r"did not write there \(notes.md\)"):
        check_output_dir(out, True, "run")
    # a caller that deletes nothing (bench quality) is not refused for either reason
    check_output_dir(out, True, "run", deletes=False)
    assert sorted(p.name for p in out.iterdir()) == [OUTPUT_MARK, "frame0000_eye0.png", "notes.md"]


@contextlib.contextmanager
def _lock_held_by_another_process(d):
    """An exclusive flock on directory ``d`` held by a child process, as a running command
    holds its output's."""
    holder = subprocess.Popen(
        [
            sys.executable,
            "-c",
            "import fcntl, os, sys, time; fd = os.open(sys.argv[1], os.O_RDONLY); "
            "fcntl.flock(fd, fcntl.LOCK_EX); print('locked', flush=True); time.sleep(60)",
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

    from vrneural.formats.atomic import make_output_dir, seal_output_dir

    d = make_output_dir(tmp_path / "o", "run")
    seal_output_dir(d, "run")  # a finished output: --force may replace it
    with _lock_held_by_another_process(d):
        with pytest.raises(VrnError, match="another vrneural process is writing this output"):
            make_output_dir(d, "run")
    make_output_dir(d, "run")  # the holder is gone: its lock went with it
    seal_output_dir(d, "run")


def test_an_unfinished_output_says_whether_its_writer_still_runs(tmp_path):
    """A second `--force` while the first command still writes its (unsealed) output was told
    "killed, or still running elsewhere"; the lock tells which."""
    import json

    from vrneural.formats.atomic import OUTPUT_MARK, check_output_dir

    d = tmp_path / "o"
    d.mkdir()
    (d / OUTPUT_MARK).write_text(json.dumps({"command": "run", "entries": None}))
    (d / "frame.png").write_bytes(b"x")
    with pytest.raises(
        VrnError, match=r"unfinished `vrneural run` output \(its process was killed"
    ):
        check_output_dir(d, True, "run")
    with _lock_held_by_another_process(d):
        for force in (True, False):  # without --force too: "pass --force" would not help
            with pytest.raises(VrnError, match="another vrneural process is writing this"):
                check_output_dir(d, force, "run")
    assert sorted(p.name for p in d.iterdir()) == [OUTPUT_MARK, "frame.png"]


def test_an_old_output_that_cannot_be_removed_is_one_line(tmp_path, monkeypatch):
    import pathlib

    from vrneural.formats.atomic import make_output_dir, seal_output_dir

    d = make_output_dir(tmp_path / "o", "run")
    (d / "frame.png").write_bytes(b"x")
    seal_output_dir(d, "run")

    def read_only(self, *a, **k):
        raise OSError(30, "Read-only file system")

    monkeypatch.setattr(pathlib.Path, "unlink", read_only)
    with pytest.raises(VrnError, match=r"frame\.png: cannot remove the old output to replace it"):
        make_output_dir(d, "run")


def test_a_file_system_without_locks_still_takes_outputs(tmp_path, monkeypatch):
    """flock can fail for reasons other than a holder (ENOLCK on some network mounts): then
    the output is written without the lock, not refused as busy."""
    import errno
    import fcntl

    from vrneural.formats.atomic import make_output_dir, seal_output_dir

    def no_locks(fd, op):
        raise OSError(errno.ENOLCK, "No locks available")

    monkeypatch.setattr(fcntl, "flock", no_locks)
    d = make_output_dir(tmp_path / "o", "run")
    seal_output_dir(d, "run")
    make_output_dir(d, "run")


def test_output_names_are_checked_in_one_place():
    from vrneural.formats.atomic import check_suffix

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
    folder, which held nothing else (it was sealed with a sub-folder that was gone)."""
    from vrneural.formats.atomic import (
        mark_output_dir,
        remove_empty_created_dirs,
        seal_marked,
    )

    ba = tmp_path / "new" / "ba"
    mark_output_dir(ba, "bench all")
    mark_output_dir(ba / "frames", "bench frames")
    seal_marked(failed=True)
    remove_empty_created_dirs()
    assert list(tmp_path.iterdir()) == []
