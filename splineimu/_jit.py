"""The one jit factory of splineimu.

Every numba kernel is built through :func:`jit` so that caching and the pure-Python
fallback are controlled in one place:

- ``cache=True`` always, unless ``SPLINEIMU_NO_CACHE=1`` is set in the environment.
- ``NUMBA_DISABLE_JIT=1`` (numba's own switch) turns every kernel into plain Python; the
  test-suite is run once that way to check that both paths agree.
- No ``fastmath``: it breaks the small-angle branches of the Lie kernels.
"""

from __future__ import annotations

import os

import numba

CACHE = os.environ.get("SPLINEIMU_NO_CACHE", "0") not in ("1", "true", "yes")


def jit(fn=None, *, parallel: bool = False, inline: str = "never"):
    """Compile ``fn`` in nopython mode with the project's options.

    Use as ``@jit`` or ``@jit(parallel=True)``. ``inline="always"`` is for small helpers
    called inside hot loops.
    """

    def wrap(f):
        return numba.njit(cache=CACHE, parallel=parallel, inline=inline, error_model="numpy")(f)

    if fn is None:
        return wrap
    return wrap(fn)


prange = numba.prange
