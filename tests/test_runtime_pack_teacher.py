"""`vrneural run --pack student.vrnm --mode reference` finds the student's own teacher pack, by
the checkpoint the pack records, and passes over packs of other teachers (hash mismatch) and
unverifiable ones at a path resolved against the wrong directory."""

from __future__ import annotations

import copy
import shutil

from distill_helpers import trained  # noqa: F401 (fixture)

from vrneural.formats.vrnm import read_vrnm, write_vrnm
from vrneural.material import random_material
from vrneural.outputs import file_sha256
from vrneural.runtime.pack_teacher import teacher_beside


def _other_teacher(path, sha=None):
    t = random_material(5, arch="single", width=16)
    t.meta["method"] = "teacher"
    if sha:
        t.meta["provenance"] = {"checkpoint_sha256": sha}
    write_vrnm(path, t)


def test_the_recorded_teacher_is_found_and_other_teachers_are_passed_over(
    trained,  # noqa: F811
    tmp_path,
    monkeypatch,
):
    student = read_vrnm(trained["student"].with_suffix(".vrnm"))
    teacher_pack = trained["teacher"].with_suffix(".vrnm")
    prov = student.meta["provenance"]
    assert prov["teacher"] == file_sha256(trained["teacher"])  # what the student records
    assert read_vrnm(teacher_pack).meta["provenance"]["checkpoint_sha256"] == prov["teacher"]
    d = tmp_path / "moved"
    d.mkdir()
    pack = d / "student.vrnm"
    shutil.copy(trained["student"].with_suffix(".vrnm"), pack)
    found, _, _ = teacher_beside(pack, student)  # by the absolute path it records
    assert found.resolve() == teacher_pack.resolve()

    lost = copy.deepcopy(student)  # the teacher moved away; the typed path is relative
    lost.meta["provenance"]["teacher_path"] = str(tmp_path / "gone" / "teacher.pt")
    lost.meta["provenance"]["config"]["teacher"] = "teacher.pt"
    monkeypatch.chdir(tmp_path)
    _other_teacher(tmp_path / "teacher.vrnm")  # resolved against the wrong directory, no hash
    _other_teacher(d / "student.teacher.vrnm", sha="0" * 64)  # another teacher by its hash
    found, teacher, tried = teacher_beside(pack, lost)
    assert found is None and teacher is None
    text = " | ".join(tried)
    assert "cannot tell it is the recorded teacher" in text
    assert "another teacher: its checkpoint hash differs" in text
    shutil.copy(teacher_pack, d / "teacher.vrnm")  # the real one, under the plain name
    found, teacher, _ = teacher_beside(pack, lost)
    assert found == d / "teacher.vrnm" and teacher.meta["method"] == "teacher"
