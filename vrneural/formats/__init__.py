"""File formats shared by the stages: a versioned array container (atomic writes live in
:mod:`vrneural.outputs`)."""

from vrneural.formats.container import ContainerWriter, read_container, write_container

__all__ = ["ContainerWriter", "read_container", "write_container"]
