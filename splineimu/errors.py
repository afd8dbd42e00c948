"""Exceptions of splineimu: one family.

Every error a user can cause derives from :class:`SplineImuError`; the command line turns it
into a short message and exit code 1, without a traceback. Errors caused by bad input are
also :class:`ValueError` subclasses (what numpy and scipy users catch); a refused output
location is also a :class:`FileExistsError`.

Each error may carry where the problem is: ``path`` (a file), ``line`` (1-based) and
``option`` (a command-line flag or a scene-file key). The message then starts with
``path:line:`` as compilers print it, so the same text reads well in a terminal and in a log.

Examples
--------
>>> err = InputError("timestamp is NaN", path="poses.txt", line=12)
>>> str(err)
'poses.txt:12: timestamp is NaN'
>>> isinstance(err, ValueError), err.line
(True, 12)
"""

from __future__ import annotations


class SplineImuError(Exception):
    """Base class of every user-facing error of splineimu.

    Parameters
    ----------
    message : str
        What is wrong (and, where it helps, what to do).
    path : str or os.PathLike, optional
        The file the problem was found in.
    line : int, optional
        1-based line number in that file.
    option : str, optional
        The command-line option or scene-file key at fault.
    """

    def __init__(self, message: str = "", path=None, line: int | None = None, option: str | None = None):
        self.path = None if path is None else str(path)
        self.line = None if line is None else int(line)
        self.option = option
        self.problem = str(message)
        where = ""
        if self.path is not None:
            where = self.path + (f":{self.line}" if self.line is not None else "") + ": "
        super().__init__(where + self.problem)

    def __reduce__(self):  # picklable across processes (Dask workers, multiprocessing)
        return (_rebuild, (type(self), self.problem, self.path, self.line, self.option))


def _rebuild(cls, problem, path, line, option):
    return cls(problem, path=path, line=line, option=option)


class InputError(SplineImuError, ValueError):
    """Bad input data: a file (and line) or an array argument, and what is wrong with it."""


class ConfigError(SplineImuError, ValueError):
    """Bad configuration: an option, a scene-file key, an IMU or extrinsic yaml file."""


class RangeError(SplineImuError, ValueError):
    """A time query outside the valid range of a motion source."""


class OutputExistsError(SplineImuError, FileExistsError):
    """The output location exists (and is not empty), and ``--force`` was not given."""


__all__ = ["SplineImuError", "InputError", "ConfigError", "RangeError", "OutputExistsError"]
