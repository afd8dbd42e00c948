"""Former home of the atomic outputs and the table formatter, kept so that old imports work.

Atomic folders and files now live in :mod:`splineimu.io.files`, text tables in
:mod:`splineimu.io.tables` and the digit kernels in :mod:`splineimu._kernels.textfmt`.
Import from those; this module only re-exports their names.
"""

from __future__ import annotations

from .files import (  # noqa: F401 - re-exported
    OutputFolder,
    _remove,
    _unique_sibling,
    atomic_write_bytes,
    atomic_write_text,
    check_output_dir,
    replace_path,
)
from .tables import CHUNK_ROWS, MAX_AHEAD, TableWriter, format_table, format_table_chunks  # noqa: F401

__all__ = [
    "OutputFolder",
    "TableWriter",
    "check_output_dir",
    "atomic_write_bytes",
    "atomic_write_text",
    "format_table",
]
