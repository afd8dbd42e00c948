"""The ``splineimu`` command line: parse, call the library, print.

Each subcommand lives in :mod:`splineimu.commands` as a module with ``NAME``, ``HELP``,
``add_arguments(parser)`` and ``run(args) -> int``. Heavy imports stay inside ``run`` so that
``--help`` is instant.
"""

from __future__ import annotations

import os

# Small banded solves and vector maths: BLAS threads only contend (and spin) on a busy machine.
# Set before numpy is imported; a user's explicit setting wins.
for _var in ("OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS", "OMP_NUM_THREADS"):
    os.environ.setdefault(_var, "1")

import argparse  # noqa: E402
import importlib  # noqa: E402
import pkgutil  # noqa: E402
import sys  # noqa: E402

from . import __version__  # noqa: E402
from .errors import SplineImuError  # noqa: E402


def _commands():
    from . import commands

    mods = []
    for info in pkgutil.iter_modules(commands.__path__):
        if info.name.startswith("_"):
            continue
        mods.append(importlib.import_module(f"{commands.__name__}.{info.name}"))
    return sorted(mods, key=lambda m: (getattr(m, "ORDER", 100), m.NAME))


def build_parser(command: str | None = None) -> argparse.ArgumentParser:
    """The parser of every command; with ``command`` (a command's name, or ``""`` for none),
    only that command's flags are added (every command is listed with its help line), so that
    a run, ``--help`` or ``--version`` does not import what the other commands' flags need."""
    parser = argparse.ArgumentParser(
        prog="splineimu",
        description=(
            "Turn a recorded or designed trajectory into realistic IMU data with exact ground truth.\n"
            "Typical use:  splineimu from-tum poses.txt -o out --imu imu.yaml"
        ),
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    parser.add_argument("--version", action="version", version=f"splineimu {__version__}")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")
    for mod in _commands():
        p = sub.add_parser(
            mod.NAME,
            help=mod.HELP,
            description=getattr(mod, "DESCRIPTION", mod.HELP),
            formatter_class=argparse.RawDescriptionHelpFormatter,
        )
        if command is None or command == mod.NAME:
            mod.add_arguments(p)
        p.set_defaults(_run=mod.run)
    return parser


class Terminated(KeyboardInterrupt):
    """SIGTERM (or SIGHUP) arrived: unwinds like Ctrl-C, so that temporary outputs are removed."""

    def __init__(self, signum: int):
        super().__init__(signum)
        self.signum = signum


def _raise_terminated(signum, frame):
    raise Terminated(signum)


def _install_signal_handlers() -> dict:
    """SIGTERM and SIGHUP raise :class:`Terminated` (a KeyboardInterrupt, as SIGINT raises);
    the ``with`` blocks of the atomic outputs then remove their temporaries. Returns the
    handlers replaced, for :func:`_restore_signal_handlers`."""
    import signal

    old = {}
    for name in ("SIGTERM", "SIGHUP"):
        sig = getattr(signal, name, None)
        if sig is not None and signal.getsignal(sig) in (signal.SIG_DFL, None):
            try:
                old[sig] = signal.signal(sig, _raise_terminated)
            except ValueError:  # not the main thread (main() called from a library user's thread)
                break
    return old


def _restore_signal_handlers(old: dict) -> None:
    import signal

    for sig, handler in old.items():
        signal.signal(sig, handler)


def _os_error_text(exc: OSError) -> str:
    """One line for an OSError: the path(s) and the system's words, and what to do."""
    import errno

    what = exc.strerror or type(exc).__name__
    paths = [p for p in (exc.filename, exc.filename2) if p is not None]
    where = " -> ".join(f"'{os.fsdecode(p)}'" for p in paths)
    hint = {
        errno.EACCES: "check the permissions of that folder or choose another -o",
        errno.EPERM: "check the permissions of that folder or choose another -o",
        errno.EROFS: "the filesystem is read-only; choose another -o",
        errno.ENOSPC: "the disk is full; free space or choose another -o",
        errno.EDQUOT: "the disk quota is exceeded; free space or choose another -o",
        errno.ENAMETOOLONG: "use a shorter name",
        errno.ENOTDIR: "a part of the path is a file, not a folder",
        errno.ENOENT: "check the path",
        errno.EISDIR: "that is a folder; give a file",
    }.get(exc.errno)
    return f"{where + ': ' if where else ''}{what}" + (f" ({hint})" if hint else "")


def main(argv=None) -> int:
    """Run the command line; returns the exit code.

    Every error a user can cause ends as one line on stderr and exit code 1 (errors of the
    splineimu family, OS errors on inputs and outputs, memory and nesting limits); Ctrl-C
    exits with 130. Run as the program (``argv`` None), SIGTERM and SIGHUP unwind like Ctrl-C,
    so temporary outputs are removed, and exit with 128 + the signal number.

    Parameters
    ----------
    argv : list of str, optional
        The arguments (default: ``sys.argv[1:]``).
    """
    program = argv is None
    argv = sys.argv[1:] if program else list(argv)
    command = argv[0] if argv and not argv[0].startswith("-") else ""
    parser = build_parser(command)
    args = parser.parse_args(argv)
    if not getattr(args, "_run", None):
        parser.print_help()
        return 2
    # the program itself (not main() called in-process, e.g. by tests): SIGTERM cleans up like Ctrl-C
    old_handlers = _install_signal_handlers() if program else {}
    try:
        return _run(args)
    finally:
        _restore_signal_handlers(old_handlers)


def _run(args) -> int:
    prog = f"splineimu {args.command}"
    try:
        return int(args._run(args) or 0)
    except SplineImuError as exc:
        print(f"{prog}: error: {exc}", file=sys.stderr)
        return 1
    except Terminated as exc:
        print(f"{prog}: terminated (signal {exc.signum}); nothing partial was left", file=sys.stderr)
        return 128 + exc.signum
    except KeyboardInterrupt:
        print(f"{prog}: interrupted; nothing partial was left", file=sys.stderr)
        return 130
    except BrokenPipeError:  # e.g. `splineimu allan ... | head`
        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, sys.stdout.fileno())
        return 1
    except OSError as exc:
        print(f"{prog}: error: {_os_error_text(exc)}", file=sys.stderr)
        return 1
    except MemoryError:
        print(f"{prog}: error: out of memory; try a shorter span, a lower --rate, or fewer outputs "
              "(--plot and --bag hold the whole record)", file=sys.stderr)
        return 1
    except RecursionError:
        print(f"{prog}: error: an input is nested too deeply to be read", file=sys.stderr)
        return 1


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
