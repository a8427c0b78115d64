"""`bench tradeoff --packs DIR`: each pack must be what its file name says, and all must come
from one BTF and its teacher; checked before any rendering or output (no GPU work)."""

import shutil
from pathlib import Path

import pytest

from vrneural.bench.packs import PACKS, load_packs, train_packs
from vrneural.cli import main
from vrneural.errors import VrnError
from vrneural.formats.vrnm import read_vrnm, write_vrnm

BUNDLED = Path(__file__).parent.parent / "vrneural" / "data" / "materials"
TINY = dict(preset="leather", res=16, dirs=6, teacher_width=32, teacher_epochs=1, epochs=1, seed=0)


@pytest.fixture(scope="module")
def packs(tmp_path_factory) -> Path:
    """The five packs `bench tradeoff` trains, at a tiny budget (a few seconds on a CPU)."""
    d = tmp_path_factory.mktemp("packs")
    train_packs(d, TINY, progress=False)
    return d


def _dir(tmp_path: Path, packs: Path, **swap: Path) -> Path:
    """A copy of the packs, ``name -> path`` in ``swap`` replacing ``name.vrnm``."""
    d = tmp_path / "swp"
    d.mkdir()
    for k in PACKS:
        shutil.copy(swap.get(k, packs / f"{k}.vrnm"), d / f"{k}.vrnm")
    return d


def _err(capsys, d: Path, out: Path) -> str:
    rc = main(
        ["bench", "tradeoff", "--quick", "--no-progress", "--packs", str(d), "--out", str(out)]
    )
    err = capsys.readouterr().err.strip().splitlines()
    assert rc == 2 and len(err) == 1, err
    assert not out.exists()  # refused before --out was made
    return err[0]


def test_trained_packs_pass_and_keep_their_roles(packs):
    mats = load_packs({k: packs / f"{k}.vrnm" for k in PACKS})
    assert [mats[k].meta["method"] for k in PACKS] == [
        "teacher", "student", "student", "single8", "neumip"
    ]  # fmt: skip


def test_swapped_packs_are_refused_in_one_line_before_any_output(capsys, tmp_path, packs):
    """The user trial: a student named teacher.vrnm (the reference would be a student) and the
    teacher named neumip.vrnm."""
    d = _dir(tmp_path, packs, teacher=packs / "student.vrnm", neumip=packs / "teacher.vrnm")
    msg = _err(capsys, d, tmp_path / "o")
    assert msg == (
        f"vrneural bench tradeoff: error: {d}/teacher.vrnm: is a coarse-to-fine student pack "
        "(8 wide, distilled), but the reference (teacher.vrnm) must be a teacher"
    )
    shutil.copy(packs / "teacher.vrnm", d / "teacher.vrnm")
    msg = _err(capsys, d, tmp_path / "o")
    assert msg == (
        f"vrneural bench tradeoff: error: {d}/neumip.vrnm: is a teacher pack (32 wide), but the "
        "network 'NeuMIP-sized 4x25' (neumip.vrnm) must be a NeuMIP-sized network "
        "(distill --method neumip)"
    )


@pytest.mark.parametrize(
    "name, given, needles",
    [
        ("student", "student_nodistill", ("(8 wide, not distilled)", "must be a distilled")),
        ("student_nodistill", "student", ("(8 wide, distilled)", "without distillation")),
        ("single8", "neumip", ("a single-level neumip pack (25 wide, log1p", "8-wide network")),
        ("neumip", "single8", ("a single-level single8 pack (8 wide", "NeuMIP-sized network")),
        ("student", "teacher", ("is a teacher pack (32 wide)", "the base network (student")),
    ],
)
def test_every_role_is_checked(capsys, tmp_path, packs, name, given, needles):
    d = _dir(tmp_path, packs, **{name: packs / f"{given}.vrnm"})
    msg = _err(capsys, d, tmp_path / "o")
    assert f"error: {d}/{name}.vrnm: is " in msg and f"({name}.vrnm) must be" in msg, msg
    assert all(n in msg for n in needles), msg


def test_packs_of_another_btf_are_refused(capsys, tmp_path, packs):
    """The bundled leather student is a distilled coarse-to-fine student, of another BTF."""
    d = _dir(tmp_path, packs, student=BUNDLED / "leather.vrnm")
    sha = read_vrnm(d / "student.vrnm").meta["provenance"]["btf"]["sha256"]
    msg = _err(capsys, d, tmp_path / "o")
    assert msg.startswith(
        f"vrneural bench tradeoff: error: {d}/student.vrnm: was trained on another BTF ('leather'"
        f" sha256 {sha[:12]}...) than the reference {d}/teacher.vrnm ('leather' sha256 "
    ), msg
    assert msg.endswith("; all packs in --packs must come from one BTF and its teacher"), msg


def test_packs_of_another_teacher_are_refused(capsys, tmp_path, packs):
    """Same BTF, another teacher checkpoint (as a teacher retrained or continued would be)."""
    mat = read_vrnm(packs / "single8.vrnm")
    mat.meta["provenance"]["teacher"] = "ab" * 32
    write_vrnm(tmp_path / "other.vrnm", mat)
    d = _dir(tmp_path, packs, single8=tmp_path / "other.vrnm")
    msg = _err(capsys, d, tmp_path / "o")
    assert msg.startswith(
        f"vrneural bench tradeoff: error: {d}/single8.vrnm: was trained with another teacher "
        "(checkpoint SHA-256 abababababab...) than the reference "
    ), msg


def test_a_pack_that_records_no_method_is_refused(tmp_path, packs):
    mat = read_vrnm(packs / "teacher.vrnm")
    del mat.meta["method"]
    write_vrnm(tmp_path / "teacher.vrnm", mat)
    paths = {k: packs / f"{k}.vrnm" for k in PACKS} | {"teacher": tmp_path / "teacher.vrnm"}
    with pytest.raises(VrnError, match="is a single-level pack \\(32 wide\\) that records no "):
        load_packs(paths)


@pytest.mark.gpu
def test_the_packs_that_pass_are_benchmarked(capsys, tmp_path, packs):
    out = tmp_path / "o"
    argv = ["bench", "tradeoff", "--quick", "--no-progress"]
    assert main([*argv, "--packs", str(packs), "--out", str(out)]) == 0, capsys.readouterr().err
    assert (out / "results.json").is_file()


@pytest.mark.gpu
def test_teacher_and_student_alone_score_without_the_other_networks(capsys, tmp_path, packs):
    """--packs needs the reference and the base network only: a user's own student against
    its teacher. The other networks' rows are left out and the report says so; without
    student.vrnm it is a one-line error naming what is needed."""
    import json

    d = tmp_path / "two"
    d.mkdir()
    for k in ("teacher", "student"):
        shutil.copy(packs / f"{k}.vrnm", d / f"{k}.vrnm")
    out = tmp_path / "o"
    argv = ["bench", "tradeoff", "--quick", "--no-progress"]
    assert main([*argv, "--packs", str(d), "--out", str(out)]) == 0
    doc = json.loads((out / "results.json").read_text())
    assert doc["packs"]["absent"] == ["student_nodistill", "single8", "neumip"]
    variants = [v for r in doc["records"] for v in r["variants"]]
    assert variants and not [v for v in variants if v["knob"] == "network"]
    assert "no student_nodistill, single8, neumip pack there" in (out / "results.md").read_text()
    (d / "student.vrnm").unlink()
    msg = _err(capsys, d, tmp_path / "o2")
    assert "student.vrnm' not found (needs teacher and student .vrnm;" in msg, msg
