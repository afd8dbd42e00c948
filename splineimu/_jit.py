"""The one jit factory of splineimu.

Every numba kernel is built through :func:`jit` so that caching and the pure-Python
fallback are controlled in one place:

- ``cache=True`` always, unless ``SPLINEIMU_NO_CACHE=1`` is set in the environment.
- ``NUMBA_DISABLE_JIT=1`` (numba's own switch) turns every kernel into plain Python; the
  test-suite is run once that way to check that both paths agree.
- No ``fastmath``: it breaks the small-angle branches of the Lie kernels.
- ``nrt=False`` compiles a kernel without numba's reference-counted runtime. Every array
  that a jitted function passes to another is otherwise incref'd and decref'd atomically at
  each call (and at each aliasing assignment of an inlined call), which costs ~5 ns per
  array per call and dominates tight per-element loops that call helpers (measured:
  the text formatter spent 30 of its 44 ns per ``0`` there). Such a kernel may not allocate
  arrays: the caller passes in scratch and output buffers.
- ``nogil=True`` releases the GIL, so that plain Python threads run a kernel in parallel
  without the start-up cost of numba's parallel backend (~0.5 s on the first call in a
  process, measured), which matters for one-shot command-line runs.
"""

from __future__ import annotations

import os

import numba

CACHE = os.environ.get("SPLINEIMU_NO_CACHE", "0") not in ("1", "true", "yes")


def jit(fn=None, *, parallel: bool = False, inline: str = "never", nrt: bool = True, nogil: bool = False):
    """Compile ``fn`` in nopython mode with the project's options.

    Use as ``@jit`` or ``@jit(parallel=True)``. ``inline="always"`` is for small helpers
    called inside hot loops; ``nrt=False`` for allocation-free kernels whose helpers take
    arrays; ``nogil=True`` for kernels run from Python threads.
    """

    def wrap(f):
        opts = dict(cache=CACHE, parallel=parallel, inline=inline, error_model="numpy", nogil=nogil)
        if not nrt:
            opts["_nrt"] = False
        return numba.njit(**opts)(f)

    if fn is None:
        return wrap
    return wrap(fn)


prange = numba.prange
