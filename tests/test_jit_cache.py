"""The jit factory's cache loading (splineimu/_jit.py), in fresh processes.

A kernel found in numba's cache is loaded without numba's context refresh (its registries are
not imported), gives the same numbers, and a signature not in the cache still compiles;
``SPLINEIMU_NUMBA_FULL_INIT=1`` restores numba's own path.
"""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import numba
import pytest

from splineimu import _jit

ROOT = Path(__file__).resolve().parents[1]

pytestmark = pytest.mark.skipif(numba.config.DISABLE_JIT or not _jit.CACHE,
                                reason="needs numba's cache (NUMBA_DISABLE_JIT / SPLINEIMU_NO_CACHE set)")

KERNEL = '''
from splineimu._jit import jit


@jit
def scaled_sum(x, a):
    s = 0.0
    for i in range(x.shape[0]):
        s += a * x[i]
    return s
'''

SCRIPT = '''
import sys
import numpy as np
import lazykernel

f = lazykernel.scaled_sum
print(f(np.arange(5.0), 2.0))
print("refreshed" if "numba.np.arraymath" in sys.modules else "lazy")  # imported by numba's refresh
if len(sys.argv) > 1:
    print(f(np.arange(5.0, dtype=np.float32), 3))  # a signature not in the cache: compiled
print(sum(f._cache_hits.values()), sum(f._cache_misses.values()))
'''


def _run(tmp_path, *args, **env):
    e = {k: v for k, v in os.environ.items() if k != "SPLINEIMU_NUMBA_FULL_INIT"}
    e.update(PYTHONPATH=os.pathsep.join([str(tmp_path), str(ROOT)]), **env)
    out = subprocess.run([sys.executable, "-c", SCRIPT, *args], env=e, capture_output=True, text=True, cwd=tmp_path)
    assert out.returncode == 0, out.stderr
    return out.stdout.split()


def test_cached_kernel_loads_without_refresh_and_misses_still_compile(tmp_path):
    (tmp_path / "lazykernel.py").write_text(KERNEL)
    first = _run(tmp_path)  # compiles (numba refreshes) and fills the cache
    assert first == ["20.0", "refreshed", "0", "1"]
    again = _run(tmp_path, "miss")
    assert again[:2] == ["20.0", "lazy"]
    assert float(again[2]) == pytest.approx(30.0, rel=0, abs=0)  # float32 compiled after a refresh
    assert again[3:] == ["1", "1"]  # one hit (float64), one miss (float32)
    full = _run(tmp_path, SPLINEIMU_NUMBA_FULL_INIT="1")
    assert full == ["20.0", "refreshed", "1", "0"]


def test_lazy_loader_only_on_numba_function_caches():
    # the kernels of the package got the lazy loader; a cache-less dispatcher is left alone
    from splineimu._kernels import textfmt

    assert textfmt.format_table._cache.load_overload.func is _jit._load_lazily
    plain = numba.njit(cache=False)(lambda x: x)
    assert _jit._lazy_cache(plain) is plain
    assert not hasattr(plain._cache.load_overload, "func")



LINK_KERNEL = KERNEL + """

@jit
def doubled(x):
    out = np.empty(x.shape[0])
    for i in range(x.shape[0]):
        out[i] = 2.0 * x[i]
    return out
"""

LINK_SCRIPT = """
import sys
import numba
import numpy as np
import linkkernel

f = linkkernel.scaled_sum
x = np.arange(5.0)
print(f(x, 2.0), linkkernel.doubled(x).sum())
cres = f.overloads[f.signatures[0]]
lib = cres.library
print("deferred" if "_shared_bitcode" in lib.__dict__ else "parsed")
print("numba.np.arrayobj" in sys.modules)  # np.empty's environment came without its module
from numba.core.runtime import nrt
print("deferred" if "_shared_bitcode" in nrt.rtsys.library.__dict__ else "parsed")  # numba's runtime: cached
# a kernel compiled after the loads (not cached) calls the loaded ones: their modules are linked in
outer = numba.njit(lambda x: linkkernel.scaled_sum(x, 2.0) + linkkernel.doubled(x)[1] + np.empty(3).size)
print(outer(x))
print("deferred" if "_shared_bitcode" in lib.__dict__ else "parsed")
# names the cached module defines beside the entry point are found (recorded on a miss)
engine = lib.codegen._engine
print(engine.is_symbol_defined(cres.fndesc.llvm_func_name), engine.is_symbol_defined("no_such_symbol"))
print(sum(f._cache_hits.values()), sum(f._cache_misses.values()))
"""


def test_kernel_compiled_after_cache_loads_links_the_loaded_kernels(tmp_path):
    (tmp_path / "linkkernel.py").write_text(LINK_KERNEL.replace("from splineimu", "import numpy as np\nfrom splineimu"))
    e = {k: v for k, v in os.environ.items() if k != "SPLINEIMU_NUMBA_FULL_INIT"}
    e.update(PYTHONPATH=os.pathsep.join([str(tmp_path), str(ROOT)]))

    def run():
        out = subprocess.run([sys.executable, "-c", LINK_SCRIPT], env=e, capture_output=True, text=True,
                             cwd=tmp_path)
        assert out.returncode == 0, out.stderr
        return out.stdout.split("\n")

    first = run()  # compiles (numba's runtime too) and fills the cache
    assert first[1:4] == ["parsed", "True", "parsed"]
    assert list(tmp_path.glob("__pycache__/splineimu-nrt.*.nbo"))
    lines = run()
    assert [float(v) for v in lines[0].split()] == [20.0, 20.0]
    # loaded without parsing bitcode or importing arrayobj, numba's runtime from the cache
    assert lines[1:4] == ["deferred", "False", "deferred"]
    assert float(lines[4]) == pytest.approx(25.0, rel=0, abs=0)  # 20 + 2 + 3
    assert lines[5] == "parsed"  # parsed for linking into the new kernel
    assert lines[6] == "True False"
    assert lines[7] == "1 0"


def test_first_compile_is_announced_once_on_a_terminal_only(monkeypatch):
    import io

    from splineimu import _jit

    class Tty(io.StringIO):
        def isatty(self):
            return True

    for stream, lines in ((io.StringIO(), 0), (Tty(), 1)):
        monkeypatch.setattr(_jit, "_ANNOUNCED", [])
        monkeypatch.setattr("sys.stderr", stream)
        _jit._announce_compiling()
        _jit._announce_compiling()
        assert stream.getvalue().count("compiling numerical kernels") == lines, stream.getvalue()


def test_runtime_cache_key_without_newer_numba_settings(tmp_path):
    """numba 0.61 (the lowest allowed) has no ``config.DEBUG_NRT_STACK_LIMIT``: the cached
    runtime's key read it unconditionally, and every kernel's first call raised AttributeError
    there (found by running the suite at the lowest versions)."""
    (tmp_path / "lazykernel.py").write_text(KERNEL)
    prelude = "import numba.core.config as c; c.__dict__.pop('DEBUG_NRT_STACK_LIMIT', None)\n"
    e = {k: v for k, v in os.environ.items() if k != "SPLINEIMU_NUMBA_FULL_INIT"}
    e.update(PYTHONPATH=os.pathsep.join([str(tmp_path), str(ROOT)]))
    for _ in range(2):  # compiled, then loaded from the cache
        out = subprocess.run([sys.executable, "-c", prelude + SCRIPT], env=e, capture_output=True, text=True,
                             cwd=tmp_path)
        assert out.returncode == 0, out.stderr
        assert out.stdout.split()[0] == "20.0"
