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
- Kernels found in the cache are loaded without numba's full start-up (:func:`_load_lazily`):
  numba "refreshes" its typing and target contexts before its first cache load in a process,
  importing and installing the registries of all its implementations, which only compiling
  needs (0.1-0.15 s of CPU per process, measured, plus scipy.linalg's import, 0.25 s, which
  ``numba.np.arraymath`` makes when nothing else has).
  The contexts are refreshed as before on the first cache miss, before compiling.
  ``SPLINEIMU_NUMBA_FULL_INIT=1`` restores numba's own path.
"""


from __future__ import annotations

import functools
import os

import numba

CACHE = os.environ.get("SPLINEIMU_NO_CACHE", "0") not in ("1", "true", "yes")
LAZY_INIT = os.environ.get("SPLINEIMU_NUMBA_FULL_INIT", "0") not in ("1", "true", "yes")


def _load_lazily(cache, sig, target_context):
    """``cache.load_overload`` without the context refresh when the kernel is in the cache.

    A cached kernel is machine code; loading it needs numba's runtime (NRT, initialized here)
    and the C helpers and math symbols that numba installs when the target context is made;
    the refresh adds the Python-level implementations that compiling uses. The kernels of
    splineimu are numeric (no strings, dicts or ``parallel=True``), whose code refers to
    nothing else. On a miss (no entry, or a stale one) numba's own ``load_overload`` runs:
    refresh, look again, and the dispatcher compiles.
    """
    from numba.core.runtime import nrt

    nrt.rtsys.initialize(target_context)
    with cache._guard_against_spurious_io_errors():
        cres = cache._load_overload(sig, target_context)
    if cres is None:
        return type(cache).load_overload(cache, sig, target_context)
    return cres


def _lazy_cache(disp):
    cache = getattr(disp, "_cache", None)
    # numba's own FunctionCache (not the NullCache of cache=False); its private methods checked
    if all(hasattr(cache, a) for a in ("_load_overload", "_guard_against_spurious_io_errors", "load_overload")):
        cache.load_overload = functools.partial(_load_lazily, cache)
    return disp


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
        disp = numba.njit(**opts)(f)
        return _lazy_cache(disp) if CACHE and LAZY_INIT else disp

    if fn is None:
        return wrap
    return wrap(fn)


prange = numba.prange
