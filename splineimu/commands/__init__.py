"""Subcommands of the ``splineimu`` command line, one module each (see :mod:`splineimu.cli`)."""
