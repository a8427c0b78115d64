"""The teacher pack beside a student pack (``run --pack``'s ``--mode reference``): the
candidates it records or that sit beside it, and the checks that one is this student's
teacher."""

from __future__ import annotations

from pathlib import Path

from vrneural.errors import VrnError
from vrneural.formats.vrnm import read_vrnm
from vrneural.outputs import file_sha256, same_file


def teacher_beside(pack: Path, mat) -> tuple[Path | None, object, list[str]]:
    """The teacher pack of the student ``pack`` (its path and material, or None, None) and the
    paths tried before it (each with why it was passed over). Candidates, in order: the
    ``.vrnm`` of the teacher checkpoint the pack records (beside the pack, at its absolute
    path, at the path as typed then), ``<stem>.teacher.vrnm``
    (the bundled packs' naming) and ``teacher.vrnm`` beside the pack. A candidate must be a
    teacher pack, and where the student records its teacher's checkpoint hash, the candidate
    must not belong to another checkpoint: its own recorded hash (or that of the ``.pt`` beside
    it) must match. The typed path is resolved against the current directory, not the one
    `distill` ran in, so it counts only when that hash confirms it."""
    prov = mat.meta.get("provenance") or {}
    want = prov.get("teacher") if isinstance(prov.get("teacher"), str) else None
    typed = (prov.get("config") or {}).get("teacher")
    typed = Path(typed).with_suffix(".vrnm") if isinstance(typed, str) and typed else None
    absolute = prov.get("teacher_path")
    cands: list[tuple[Path, bool]] = []  # (path, must the hash confirm it)
    if typed:
        cands.append((pack.with_name(typed.name), False))
    if isinstance(absolute, str) and absolute:
        cands.append((Path(absolute).with_suffix(".vrnm"), False))
    if typed:
        cands.append((typed, True))
    cands += [(pack.with_name(f"{pack.stem}.teacher.vrnm"), False)]
    cands += [(pack.with_name("teacher.vrnm"), False)]
    tried, seen = [], set()
    for t, strict in cands:
        key = str(t.resolve())
        if key in seen:
            continue
        seen.add(key)
        teacher, why = _read_teacher(t, pack, want, strict)
        if teacher is not None:
            return t, teacher, tried
        tried.append(f"{t}{'' if why == 'not found' else f' ({why})'}")
    return None, None, tried


def _read_teacher(t: Path, pack: Path, want: str | None, strict: bool) -> tuple[object, str]:
    """``(material, "")`` when ``t`` is the teacher of ``pack``, else ``(None, why not)``."""
    if not t.is_file():
        return None, "not found"
    if same_file(t, pack):
        return None, "the pack itself"
    try:
        mat = read_vrnm(t)
    except VrnError:
        return None, "not a readable pack"
    if mat.meta.get("method") != "teacher":
        return None, f"a {mat.meta.get('method') or 'non-teacher'} pack, not a teacher"
    if want is None:
        return mat, ""
    have = (mat.meta.get("provenance") or {}).get("checkpoint_sha256")
    if have is None and t.with_suffix(".pt").is_file():
        have = file_sha256(t.with_suffix(".pt"))
    if have is None:
        return (None, "cannot tell it is the recorded teacher") if strict else (mat, "")
    return (mat, "") if have == want else (None, "another teacher: its checkpoint hash differs")
