"""File formats shared by the stages: a versioned array container, atomic writes."""

from vrneural.formats.atomic import (
    atomic_path,
    check_output,
    check_output_dir,
    make_output_dir,
    write_json,
)
from vrneural.formats.container import ContainerWriter, read_container, write_container

__all__ = [
    "ContainerWriter",
    "atomic_path",
    "check_output",
    "check_output_dir",
    "make_output_dir",
    "read_container",
    "write_container",
    "write_json",
]
