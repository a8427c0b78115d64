"""The output layer, through which every command writes: :class:`OutputDir` (an ``--out``
directory for a ``with`` block), :func:`output_lock` (files being trained, ``-o x.pt``), checks
before any work (:func:`check_output`, ...) and atomic writes (:func:`atomic_path`)."""

from vrneural.outputs.files import (
    atomic_path,
    check_free_space,
    check_not_input,
    check_output,
    check_outputs,
    check_resume_force,
    check_suffix,
    check_writable,
    file_sha256,
    json_safe,
    make_parent,
    same_file,
    write_json,
)
from vrneural.outputs.lock import OutputLock, lock_path, output_lock
from vrneural.outputs.outdir import (
    OUTPUT_MARK,
    OutputDir,
    read_mark,
    seal_output_dir,
    write_mark,
)

__all__ = [
    "OUTPUT_MARK",
    "OutputDir",
    "OutputLock",
    "atomic_path",
    "check_free_space",
    "check_not_input",
    "check_output",
    "check_outputs",
    "check_resume_force",
    "check_suffix",
    "check_writable",
    "file_sha256",
    "json_safe",
    "lock_path",
    "make_parent",
    "output_lock",
    "read_mark",
    "same_file",
    "seal_output_dir",
    "write_json",
    "write_mark",
]
