"""Atomic outputs: whole folders and single files, never left half-written.

A folder is built in a hidden temporary folder beside its final place and renamed into place
only when everything in it was written (:class:`OutputFolder`); a single file is written to a
temporary file in the same folder and renamed over its target (:func:`atomic_write_bytes`); a
file or folder made by another library is built under a hidden sibling and moved into place
(:func:`staged_path`). A rename inside one filesystem is atomic, so a reader sees either the
old output or the complete new one.

Files are flushed to the disk (``fsync``) before they are renamed into place, so that after
a power loss they are complete too; a batch of many small outputs may defer that to one
:func:`os.sync` at its end (:func:`deferred_sync`).
"""

from __future__ import annotations

import contextvars
import os
import secrets
import shutil
from contextlib import contextmanager
from pathlib import Path

from ..errors import ConfigError, OutputExistsError

__all__ = [
    "OutputFolder",
    "check_output_dir",
    "check_output_file",
    "check_not_input",
    "write_output_file",
    "atomic_write_bytes",
    "atomic_write_text",
    "replace_path",
    "staged_path",
    "sync_to_disk",
    "deferred_sync",
]

_SYNC = contextvars.ContextVar("splineimu_fsync", default=True)


def sync_to_disk(fd: int) -> None:
    """``os.fsync(fd)``, unless inside :func:`deferred_sync` (then nothing)."""
    if _SYNC.get():
        os.fsync(fd)


@contextmanager
def deferred_sync():
    """Within the block (in this thread or task), files are not flushed to the disk one by one.

    Atomicity against a killed process is unchanged (the renames still happen after the
    writes, and the page cache outlives the process); only durability against a power loss
    or an operating-system crash is left to the caller, who calls :func:`os.sync` once for
    the whole lot. Each ``fsync`` waits for the disk (a few ms each on a virtual disk) and
    the waits of parallel writers queue on it, so a batch of many small outputs syncs once.

    Examples
    --------
    >>> import tempfile, pathlib
    >>> with deferred_sync():
    ...     atomic_write_text(pathlib.Path(tempfile.mkdtemp()) / "x.txt", "no fsync").read_text()
    'no fsync'
    """
    token = _SYNC.set(False)
    try:
        yield
    finally:
        _SYNC.reset(token)


def check_output_dir(out_dir, force: bool = False) -> Path:
    """Fail fast if ``out_dir`` holds something that must not be overwritten.

    Call it before a long computation so that the user learns about an occupied output
    folder at once, not after the work. :class:`OutputFolder` calls it again.

    Parameters
    ----------
    out_dir : str or os.PathLike
        The output folder to be created.
    force : bool, default False
        Allow replacing an existing non-empty folder (or a file of that name).

    Returns
    -------
    pathlib.Path
        ``out_dir`` as a path.

    Raises
    ------
    OutputExistsError
        ``out_dir`` is a non-empty folder or a file, and ``force`` is False.

    Examples
    --------
    >>> import tempfile, pathlib
    >>> d = pathlib.Path(tempfile.mkdtemp())
    >>> check_output_dir(d / "new") == d / "new"
    True
    """
    out = Path(out_dir)
    if not str(out_dir):
        raise ConfigError("output folder: empty path", option="-o")
    if _is_link(out):
        raise ConfigError(f"output path '{out}' is a symbolic link; give the folder it points to, or remove the link",
                          option="-o")
    if force:
        return out
    if out.is_dir():
        if any(out.iterdir()):
            raise OutputExistsError(
                f"output folder '{out}' exists and is not empty; use --force to replace it"
            )
    elif out.exists() or out.is_symlink():
        raise OutputExistsError(f"output path '{out}' exists and is not a folder; use --force to replace it")
    return out


def _is_link(path: Path) -> bool:
    return path.is_symlink()


def check_not_input(out, inputs=(), option: str = "-o") -> None:
    """Refuse an output location that is, or (a folder that) contains, one of ``inputs``.

    Paths are compared resolved (symbolic links and ``..`` followed) and, for existing files,
    with :func:`os.path.samefile` (hard links), so no spelling of an input can overwrite it.

    Raises
    ------
    ConfigError
        ``out`` is an input, or a folder that holds one (replacing it would delete the input).

    Examples
    --------
    >>> import tempfile, pathlib
    >>> d = pathlib.Path(tempfile.mkdtemp()); _ = (d / "in.tum").write_text("1 0 0 0 0 0 0 1\\n")
    >>> check_not_input(d / "." / "in.tum", [d / "in.tum"])
    Traceback (most recent call last):
    ...
    splineimu.errors.ConfigError: ... is an input of this command; choose another output
    """
    out = Path(out)
    try:
        out_r = out.resolve()
    except (OSError, RuntimeError):  # a symlink loop: refused elsewhere
        return
    for inp in inputs:
        if inp is None:
            continue
        inp = Path(inp)
        try:
            in_r = inp.resolve()
            same = out_r == in_r or (out.exists() and inp.exists() and os.path.samefile(out, inp))
        except (OSError, RuntimeError):
            continue
        if same:
            raise ConfigError(f"{option} '{out}' is an input of this command; choose another output",
                              option=option)
        if out_r in in_r.parents:
            raise ConfigError(f"{option} '{out}' holds the input '{inp}', which replacing it would delete; "
                              "choose another output", option=option)


def check_output_file(path, force: bool = False, inputs=(), option: str = "-o") -> Path:
    """Fail fast if a single-file output may not be written at ``path``.

    Call it before the work; :func:`write_output_file` calls it again before writing.

    Parameters
    ----------
    path : str or os.PathLike
        The file to be written.
    force : bool, default False
        Allow replacing an existing file.
    inputs : sequence of path-like
        Files this command reads: ``path`` may never be one of them.
    option : str
        The option that gave ``path``, for messages.

    Raises
    ------
    OutputExistsError
        ``path`` exists and ``force`` is False.
    ConfigError
        ``path`` is a symbolic link, a folder, or an input.

    Examples
    --------
    >>> import tempfile, pathlib
    >>> d = pathlib.Path(tempfile.mkdtemp()); _ = (d / "t.tum").write_text("x")
    >>> check_output_file(d / "t.tum")
    Traceback (most recent call last):
    ...
    splineimu.errors.OutputExistsError: output file '...t.tum' exists; use --force to replace it
    """
    out = Path(path)
    if not str(path):
        raise ConfigError(f"{option}: empty path", option=option)
    if _is_link(out):
        raise ConfigError(f"{option} '{out}' is a symbolic link; give the path it points to, or remove the link",
                          option=option)
    if out.is_dir():
        raise ConfigError(f"{option} '{out}' is a folder; give a file name", option=option)
    check_not_input(out, inputs, option)
    if out.exists() and not force:
        raise OutputExistsError(f"output file '{out}' exists; use --force to replace it", option=option)
    return out


def write_output_file(path, data, force: bool = False, inputs=(), option: str = "-o") -> Path:
    """Write a single-file output atomically after :func:`check_output_file`.

    ``data`` is bytes, an iterable of bytes, or str (UTF-8). Missing parent folders are
    created. A failure (or an interrupt) leaves what was at ``path`` untouched.

    Examples
    --------
    >>> import tempfile, pathlib
    >>> p = pathlib.Path(tempfile.mkdtemp()) / "sub" / "w.csv"
    >>> write_output_file(p, "a,b\\n").read_text()
    'a,b\\n'
    """
    out = check_output_file(path, force, inputs, option)
    out.parent.mkdir(parents=True, exist_ok=True)
    if isinstance(data, str):
        data = data.encode("utf-8")
    return atomic_write_bytes(out, data)


def _unique_sibling(path: Path, tag: str) -> Path:
    return path.parent / f".{path.name}.{tag}-{secrets.token_hex(4)}"


def replace_path(new: Path, path: Path) -> None:
    """Put ``new`` (file or folder) at ``path``: an existing ``path`` is renamed aside first,
    restored if the rename fails, and deleted only once ``new`` is in place."""
    if not (path.exists() or path.is_symlink()):
        os.rename(new, path)
        return
    old = _unique_sibling(path, "old")
    os.rename(path, old)
    try:
        os.rename(new, path)
    except BaseException:
        os.rename(old, path)
        raise
    _remove(old)


def _remove(path: Path) -> None:
    if path.is_dir() and not path.is_symlink():
        shutil.rmtree(path, ignore_errors=True)
    else:
        try:
            path.unlink()
        except FileNotFoundError:
            pass


class OutputFolder:
    """Build an output folder atomically.

    ``with OutputFolder(out_dir, force) as tmp:`` yields a new hidden folder beside
    ``out_dir`` (``.<name>.tmp-<random>``, on the same filesystem). Write everything into
    ``tmp``. On a clean exit the folder is renamed to ``out_dir``; with ``force`` an
    existing ``out_dir`` is first renamed aside, the new folder renamed in, and only then
    is the old one deleted. If the block raises (including ``KeyboardInterrupt``), the
    temporary folder is deleted and ``out_dir`` is left exactly as it was.

    Parameters
    ----------
    out_dir : str or os.PathLike
        Final location. Missing parent folders are created (and removed again if the
        block fails).
    force : bool, default False
        Replace an existing non-empty ``out_dir``.

    Attributes
    ----------
    path : pathlib.Path
        The final location.
    tmp : pathlib.Path or None
        The temporary folder while the block runs.

    Raises
    ------
    OutputExistsError
        At construction (before any work) and again on entry and on commit, if
        ``out_dir`` is a non-empty folder or a file and ``force`` is False.

    Examples
    --------
    >>> import tempfile, pathlib
    >>> out = pathlib.Path(tempfile.mkdtemp()) / "out"
    >>> with OutputFolder(out) as tmp:
    ...     _ = (tmp / "a.txt").write_text("hello")
    >>> sorted(p.name for p in out.iterdir())
    ['a.txt']
    """

    def __init__(self, out_dir, force: bool = False):
        path = Path(out_dir)
        # "." and ".." have no name of their own: the temporary sibling would land inside them
        self.path = Path(os.path.abspath(path)) if path.name in ("", "..") and str(out_dir) else path
        self.force = bool(force)
        self.tmp: Path | None = None
        self._made_parents: list[Path] = []
        check_output_dir(self.path, self.force)

    def __enter__(self) -> Path:
        check_output_dir(self.path, self.force)
        self._made_parents = [a for a in self.path.parents if not a.exists()]
        self.path.parent.mkdir(parents=True, exist_ok=True)
        while True:
            tmp = _unique_sibling(self.path, "tmp")
            try:
                os.mkdir(tmp)  # default mode (0o777 & ~umask), unlike tempfile.mkdtemp
                break
            except FileExistsError:  # pragma: no cover - 32 random bits
                continue
        self.tmp = tmp
        return tmp

    def __exit__(self, exc_type, exc, tb):
        tmp, self.tmp = self.tmp, None
        if exc_type is not None:
            self._discard(tmp)
            return False
        try:
            self._commit(tmp)
        except BaseException:
            self._discard(tmp)
            raise
        return False

    def _discard(self, tmp: Path) -> None:
        _remove(tmp)
        for parent in self._made_parents:  # innermost first; only folders we created
            try:
                os.rmdir(parent)
            except OSError:
                break

    def _commit(self, tmp: Path) -> None:
        out = self.path
        if out.is_dir() and not out.is_symlink() and not any(out.iterdir()):
            os.rmdir(out)
            os.rename(tmp, out)
            return
        if not self.force:
            check_output_dir(out, False)  # raises: something appeared while we worked
        replace_path(tmp, out)


def atomic_write_bytes(path, data) -> Path:
    """Write ``data`` to ``path`` atomically (temporary file in the same folder, fsync unless
    :func:`deferred_sync`, ``os.replace``).

    Parameters
    ----------
    path : str or os.PathLike
        Target file; it is replaced if it exists. Its folder must exist.
    data : bytes-like, or an iterable of bytes-like
        The content; an iterable (list, generator) is written piece by piece as it comes
        (no concatenated copy).

    Returns
    -------
    pathlib.Path
        ``path``.

    Examples
    --------
    >>> import tempfile, pathlib
    >>> p = pathlib.Path(tempfile.mkdtemp()) / "x.bin"
    >>> _ = atomic_write_bytes(p, b"abc"); p.read_bytes()
    b'abc'
    """
    path = Path(path)
    while True:
        tmp = _unique_sibling(path, "tmp")
        try:
            fd = os.open(tmp, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o666)
            break
        except FileExistsError:  # pragma: no cover
            continue
    try:
        with os.fdopen(fd, "wb") as f:
            for chunk in (data,) if isinstance(data, (bytes, bytearray, memoryview)) else data:
                f.write(chunk)
            f.flush()
            sync_to_disk(f.fileno())
        os.replace(tmp, path)
    except BaseException:
        _remove(tmp)
        raise
    return path


def atomic_write_text(path, text: str, encoding: str = "utf-8") -> Path:
    """Write ``text`` to ``path`` atomically; see :func:`atomic_write_bytes`.

    Examples
    --------
    >>> import tempfile, pathlib
    >>> p = pathlib.Path(tempfile.mkdtemp()) / "x.txt"
    >>> _ = atomic_write_text(p, "abc\\n"); p.read_text()
    'abc\\n'
    """
    return atomic_write_bytes(path, text.encode(encoding))


@contextmanager
def staged_path(path):
    """Build ``path`` (a file or a folder that another library writes) out of sight, then
    put it in place.

    Yields a path with the same name as ``path`` inside a new hidden sibling folder (some
    writers name their inner files after it, as rosbag2 does); when the block ends without
    an error, it replaces ``path`` (:func:`replace_path`). The hidden folder is removed
    either way.

    Examples
    --------
    >>> import tempfile, pathlib
    >>> target = pathlib.Path(tempfile.mkdtemp()) / "run.log"
    >>> with staged_path(target) as tmp:
    ...     _ = tmp.write_text("done")
    ...     target.exists(), tmp.name
    (False, 'run.log')
    >>> target.read_text()
    'done'
    """
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp_parent = _unique_sibling(path, "tmp")
    os.mkdir(tmp_parent)
    try:
        tmp = tmp_parent / path.name
        yield tmp
        replace_path(tmp, path)
    finally:
        _remove(tmp_parent)
