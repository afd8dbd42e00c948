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
  A cached kernel's LLVM bitcode (kept next to its machine code for linking it into kernels
  compiled later) is parsed only when such a kernel needs it, and the symbols it defines are
  recorded when a look-up misses (:class:`_LazyLinking`): parsing and walking it took half of
  each load (~3 ms per kernel, 0.1 s for the 37 kernels of ``from-tum``, measured). numba's
  LLVM-lock events (timers that record nothing during a cache load) are off while loading.
  numba's runtime (NRT), which numba compiles in every process, is compiled once and loaded
  from the same cache folder (:func:`_initialize_nrt`, 0.035-0.045 s of CPU per process).
  A kernel's cache object is made on its first call (:class:`_DeferredCache`).
  ``SPLINEIMU_NUMBA_FULL_INIT=1`` restores numba's own path.
"""


from __future__ import annotations

import contextlib
import functools
import os
import sys
import weakref

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
    with cache._guard_against_spurious_io_errors(), _llvm_lock_events_off():
        _initialize_nrt(cache, target_context)
        cres = _load_cached(cache, sig, target_context)
    if cres is None:
        _announce_compiling()
        return type(cache).load_overload(cache, sig, target_context)
    return cres


_ANNOUNCED = []


def _announce_compiling():
    """One line on a terminal's stderr before the first kernel a process compiles (a first run
    after installing spends 40-50 s there, silent otherwise); nothing when stderr is a file or
    a pipe, whose readers (scripts, tests) expect only the command's own output."""
    if _ANNOUNCED:
        return
    _ANNOUNCED.append(True)
    try:
        if sys.stderr is not None and sys.stderr.isatty():
            print("splineimu: compiling numerical kernels for this machine (once after installing; "
                  "later runs load them from the cache) ...", file=sys.stderr, flush=True)
    except (AttributeError, ValueError, OSError):
        pass


def _initialize_nrt(cache, target_context):
    """``nrt.rtsys.initialize`` with its compiled functions kept next to the kernels' cache.

    numba compiles its runtime's atomic reference counting (a small LLVM module) in every
    process, 0.035-0.045 s of CPU (measured); here the module is compiled as numba compiles it
    once, and its machine code is saved (``splineimu-nrt.*.nbo``, keyed by the numba and
    llvmlite versions and the CPU) and loaded as a cached kernel is. numba's own
    ``initialize`` runs where its runtime does not look as expected.
    """
    from numba.core import config
    from numba.core.compiler_lock import global_compiler_lock
    from numba.core.runtime import _nrt_python, nrt, nrtdynmod

    rtsys = nrt.rtsys
    if getattr(rtsys, "_init", False) is True:
        return
    codegen = target_context.codegen()
    if not (isinstance(getattr(rtsys, "_init", None), bool)
            and isinstance(getattr(type(rtsys), "library", None), property)
            and hasattr(nrtdynmod, "create_nrt_module") and isinstance(getattr(_nrt_python, "c_helpers", None), dict)
            and isinstance(getattr(cache, "_cache_path", None), str) and _lazy_loading_possible(codegen)):
        rtsys.initialize(target_context)
        return
    with global_compiler_lock:
        if rtsys._init:
            return
        import pickle

        import llvmlite
        import llvmlite.binding as ll

        # (DEBUG_NRT_STACK_LIMIT is newer than numba 0.61, the lowest allowed)
        key = (numba.__version__, llvmlite.__version__, codegen.magic_tuple(), config.MACHINE_BITS,
               config.DEBUG_NRT, getattr(config, "DEBUG_NRT_STACK_LIMIT", None))
        path = os.path.join(cache._cache_path, f"splineimu-nrt.{sys.implementation.cache_tag}.nbo")
        try:
            with open(path, "rb") as f:
                saved_key, libdata = pickle.load(f)
        except Exception:  # absent, unreadable or from another layout: compiled below
            saved_key = libdata = None
        # as numba's Runtime.initialize: the C helpers' symbols, then the LLVM-defined functions
        if config.NRT_STATS:
            _nrt_python.memsys_enable_stats()
        for name, address in _nrt_python.c_helpers.items():
            ll.add_symbol(name if name.startswith("_") else "NRT_" + name, address)
        if saved_key == key:
            library = _unserialize_lazily(codegen, None, libdata)
        else:
            ir_module, library = nrtdynmod.create_nrt_module(target_context)
            library.enable_object_caching()
            library.add_ir_module(ir_module)
            library.finalize()
            tmp = f"{path}.{os.getpid()}.tmp"
            try:
                with open(tmp, "wb") as f:
                    pickle.dump((key, library.serialize_using_object_code()), f, protocol=pickle.HIGHEST_PROTOCOL)
                os.replace(tmp, path)
            except OSError:  # a read-only install: compiled in every process, as numba does
                with contextlib.suppress(OSError):
                    os.remove(tmp)
        rtsys._library = library
        rtsys._init = True


def _lazy_loading_possible(codegen) -> bool:
    """Whether numba's code generator has the parts :func:`_unserialize_lazily` uses."""
    engine = getattr(codegen, "_engine", None)
    return (all(hasattr(engine, a) for a in ("_defined_symbols", "_load_defined_symbols", "is_symbol_defined"))
            and hasattr(getattr(codegen, "_library_class", None), "_unserialize"))


def _load_cached(cache, sig, target_context):
    """``cache._load_overload`` with :func:`_unserialize_lazily` for the kernel's library."""
    from numba.core.funcdesc import FunctionDescriptor

    codegen = target_context.codegen()
    if not (all(hasattr(cache, a) for a in ("_index_key", "_cache_file", "_impl", "_enabled"))
            and _lazy_loading_possible(codegen)):
        return cache._load_overload(sig, target_context)
    if not cache._enabled:
        return None
    with _numba_environments_unimported():
        data = cache._cache_file.load(cache._index_key(sig, codegen))
    if data is None:
        return None
    # CompileResult._reduce's payload: (library, fndesc, environment, ...)
    fndesc = data[1] if isinstance(data, tuple) and len(data) > 1 else None
    if not isinstance(fndesc, FunctionDescriptor):
        return cache._impl.rebuild(target_context, data)
    codegen.unserialize_library = functools.partial(_unserialize_lazily, codegen, fndesc.llvm_cpython_wrapper_name)
    try:
        return cache._impl.rebuild(target_context, data)
    finally:
        del codegen.unserialize_library


class _LazyLinking:
    """Mixin of a cached code library whose linking module is parsed from its bitcode on first use."""

    @property
    def _shared_module(self):
        bitcode = self.__dict__.pop("_shared_bitcode", None)
        if bitcode is not None:
            import llvmlite.binding as ll

            self.__dict__["_shared"] = ll.parse_bitcode(bitcode)
        return self.__dict__.get("_shared")

    @_shared_module.setter
    def _shared_module(self, module):
        self.__dict__.pop("_shared_bitcode", None)
        self.__dict__["_shared"] = module


@functools.cache
def _lazy_class(cls):
    return type("Lazy" + cls.__name__, (_LazyLinking, cls), {})


def _unserialize_lazily(codegen, entry_name, state):
    """numba's ``CPUCodeLibrary._unserialize`` of an object-code entry, the linking module deferred.

    The execution engine answers "is this symbol defined?" from the set of names it has seen
    defined; the library's entry point ``entry_name`` (the one name that loading looks up) goes
    there now, the rest when a look-up misses (:func:`_deferred_symbols`), so that every answer
    is the one numba's own path gives.
    """
    name, kind, data = state
    cls = codegen._library_class
    if kind != "object":
        return cls._unserialize(codegen, state)
    object_code, shared_bitcode = data
    lib = _lazy_class(cls)(codegen, name)
    lib.enable_object_caching()
    lib._set_compiled_object(object_code)
    lib.__dict__["_shared_bitcode"] = shared_bitcode
    lib._finalize_final_module()
    engine = codegen._engine
    pending = _deferred_symbols(engine)
    if entry_name is not None:
        engine._defined_symbols.add(entry_name)
    pending.append(lib)
    return lib


def _deferred_symbols(engine):
    """The libraries whose defined symbols ``engine`` has yet to record (made on first use)."""
    pending = engine.__dict__.get("_splineimu_pending")
    if pending is None:
        pending = engine.__dict__["_splineimu_pending"] = []
        own = engine.is_symbol_defined

        def is_symbol_defined(name):
            if name not in engine._defined_symbols:
                while pending:
                    engine._load_defined_symbols(pending.pop()._shared_module)
            return own(name)

        engine.is_symbol_defined = is_symbol_defined
    return pending


@contextlib.contextmanager
def _numba_environments_unimported():
    """Unpickle the environments of numba's own implementations without importing their modules.

    A cached kernel refers to the environment (globals and constants) of every function in its
    code, among them numba's ``np.empty`` and ``np.zeros`` from ``numba.np.arrayobj``, whose import
    (0.04-0.06 s of CPU, measured) numba's unpickling makes only to hand the module's dict to the
    environment. Compiled nopython code reads an environment's constants, never its globals (only
    object-mode code looks names up there), so a module of numba not imported yet gets a dict
    that holds its name; anything else (an imported module, any other package) goes through numba.
    """
    from numba.core import environment

    own = getattr(environment, "_rebuild_env", None)
    if not (callable(own) and hasattr(environment, "lookup_environment")
            and isinstance(getattr(environment.Environment, "_memo", None), weakref.WeakValueDictionary)):
        yield
        return

    def _rebuild_env(modname, consts, env_name):
        if not (isinstance(modname, str) and modname.startswith("numba.")) or modname in sys.modules:
            return own(modname, consts, env_name)
        env = environment.lookup_environment(env_name)
        if env is None:
            env = environment.Environment({"__name__": modname})
            env.consts[:] = consts
            env.env_name = env_name
            environment.Environment._memo[env_name] = env
        return env

    # pickled by reference as numba's own, should anything pickle an environment meanwhile
    _rebuild_env.__module__, _rebuild_env.__qualname__ = own.__module__, own.__qualname__
    environment._rebuild_env = _rebuild_env
    try:
        yield
    finally:
        environment._rebuild_env = own


@contextlib.contextmanager
def _llvm_lock_events_off():
    """numba broadcasts an event at every acquire and release of llvmlite's lock (thousands
    per cache load); the timers listening during a load record nothing (no result yet)."""
    from llvmlite.binding import ffi

    lock = getattr(getattr(ffi, "lib", None), "_lock", None)
    callbacks = getattr(lock, "_cblist", None)
    if not isinstance(callbacks, list):
        yield
        return
    lock._cblist = []
    try:
        yield
    finally:
        lock._cblist = callbacks


class _DeferredCache:
    """A kernel's numba cache (``cache=True``), made when the dispatcher first uses it.

    Making numba's ``FunctionCache`` checks that the cache folder is writable by creating a file
    in it, ~0.1 ms per kernel at import; a command runs a third of the kernels it imports.
    """

    def __init__(self, disp):
        self._disp = disp

    def __getattr__(self, name):
        from numba.core.caching import FunctionCache

        disp = self._disp
        if disp._cache is self:
            disp._cache = FunctionCache(disp.py_func)
            _lazy_cache(disp)
        return getattr(disp._cache, name)


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
        lazy = CACHE and LAZY_INIT
        opts = dict(cache=CACHE and not lazy, parallel=parallel, inline=inline, error_model="numpy", nogil=nogil)
        if not nrt:
            opts["_nrt"] = False
        disp = numba.njit(**opts)(f)
        if lazy and hasattr(disp, "_cache"):  # (not under NUMBA_DISABLE_JIT: the function itself)
            disp._cache = _DeferredCache(disp)
        return disp

    if fn is None:
        return wrap
    return wrap(fn)


prange = numba.prange
