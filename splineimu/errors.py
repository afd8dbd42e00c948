"""Exceptions of splineimu.

Every error a user can cause derives from :class:`SplineImuError`; the command line turns
it into a one-line message and exit code 1, without a traceback.
"""

from __future__ import annotations


class SplineImuError(Exception):
    """Base class of every user-facing error of splineimu."""


class InputError(SplineImuError, ValueError):
    """Bad input data: a file, a line and what is wrong with it.

    Parameters
    ----------
    message : str
        What is wrong.
    path : str or os.PathLike, optional
        The file the problem was found in.
    line : int, optional
        1-based line number in that file.
    """

    def __init__(self, message: str, path=None, line: int | None = None):
        self.path = None if path is None else str(path)
        self.line = line
        self.problem = message
        where = ""
        if self.path is not None:
            where = self.path + (f":{line}" if line is not None else "") + ": "
        super().__init__(where + message)


class ConfigError(SplineImuError, ValueError):
    """Bad configuration (IMU yaml, scene file, command-line option)."""


class RangeError(SplineImuError, ValueError):
    """A time query outside the valid range of a motion source."""


class OutputExistsError(SplineImuError):
    """The output location exists and is not empty, and ``--force`` was not given."""
