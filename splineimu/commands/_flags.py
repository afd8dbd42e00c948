"""Flags shared by the commands that read a recording, and errors that name the flag a user typed.

The library functions a command calls name their arguments in errors ("`t_offset` must be
finite"); :func:`flag_names` turns those names into the flags the user typed ("`--t-offset`"),
as the synthesis commands' options do (:data:`splineimu.api.options.FLAGS`).
"""

from __future__ import annotations

import argparse
import contextlib


def add_clock_args(p: argparse.ArgumentParser, folder: str = "the folder's "):
    """--time-offset and --clock-drift-ppm of the commands that read a recording against its ground
    truth (integrate, preintegrate; :func:`splineimu.api.clock.stamp_clock`)."""
    p.add_argument("--time-offset", type=float, default=None, metavar="S",
                   help=f"the IMU clock reads true time + S (default: as recorded in {folder}report.json, "
                        "else 0; 0 turns the correction off)")
    p.add_argument("--clock-drift-ppm", type=float, default=None, metavar="PPM",
                   help="the IMU clock runs fast by PPM parts per million (default: as recorded, else 0)")


#: Library argument -> flag of integrate and preintegrate.
RECORDING_FLAGS = {"gravity": "--gravity", "time_offset_s": "--time-offset", "clock_drift_ppm": "--clock-drift-ppm"}


@contextlib.contextmanager
def flag_names(flags: dict):
    """Re-raise an error that names a library argument of ``flags`` (name -> flag) with the flag.

    Errors that point into a file (``path`` set, e.g. a ``report.json`` key of the same name)
    are left as they are.

    Examples
    --------
    >>> from splineimu.errors import ConfigError
    >>> with flag_names({"t_offset": "--t-offset"}):
    ...     raise ConfigError("`t_offset` must be finite, got nan", option="t_offset")
    Traceback (most recent call last):
    ...
    splineimu.errors.ConfigError: `--t-offset` must be finite, got nan
    """
    from ..errors import SplineImuError

    try:
        yield
    except SplineImuError as exc:
        named = [k for k in flags if f"`{k}`" in exc.problem]
        if exc.path is not None or not named:
            raise
        problem = exc.problem
        for k in named:
            problem = problem.replace(f"`{k}`", f"`{flags[k]}`")
        option = flags.get(exc.option, flags[named[0]])
        raise type(exc)(problem, option=option) from None
