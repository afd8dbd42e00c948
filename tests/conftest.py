"""Shared test set-up: deterministic hypothesis profile, the path to ../shared/data, and a check
that no test writes into the checkout."""

from __future__ import annotations

import ast
import importlib.util
import os
import re
import subprocess
from functools import cache
from pathlib import Path

import pytest
from hypothesis import HealthCheck, settings

settings.register_profile(
    "splineimu",
    derandomize=True,
    database=None,
    deadline=None,  # the first example pays JIT compilation
    max_examples=60,
    suppress_health_check=[HealthCheck.too_slow],
)
settings.load_profile(os.environ.get("HYPOTHESIS_PROFILE", "splineimu"))

REPO = Path(__file__).resolve().parent.parent
SHARED_DATA = Path(os.environ.get("SPLINEIMU_SHARED_DATA", REPO.parent / "shared" / "data"))


@pytest.fixture
def shared_data():
    """Path to ../shared/data; skips the test (naming the path) when it is absent."""
    if not SHARED_DATA.is_dir():
        pytest.skip(f"shared data not found at {SHARED_DATA}")
    return SHARED_DATA


def require_shared(*parts) -> Path:
    """Path to a file in ../shared/data, or skip naming it."""
    p = SHARED_DATA.joinpath(*parts)
    if not p.exists():
        pytest.skip(f"shared data file not found: {p}")
    return p


# ---- no test writes into the checkout -------------------------------------------------------
# Caches that running the code legitimately leaves (numba's cache sits beside the sources).
_ALLOWED = re.compile(r"(^|/)(__pycache__|\.pytest_cache|\.hypothesis|\.benchmarks|\.ruff_cache|\.venv"
                      r"|[^/]*\.egg-info)(/|$)")
_STATUS_KEY = pytest.StashKey[set]()


def _checkout_status() -> set[str] | None:
    """``git status`` lines of the checkout (ignored files too, caches left out), or None outside git."""
    try:
        proc = subprocess.run(["git", "status", "--porcelain", "--ignored", "--untracked-files=normal"],
                              cwd=REPO, capture_output=True, text=True, timeout=60, stdin=subprocess.DEVNULL)
    except (OSError, subprocess.SubprocessError):
        return None
    if proc.returncode != 0:
        return None  # not a git checkout (an unpacked sdist): nothing to compare
    return {line for line in proc.stdout.splitlines() if not _ALLOWED.search(line[3:])}


def pytest_sessionstart(session):
    session.config.stash[_STATUS_KEY] = _checkout_status()


def pytest_sessionfinish(session, exitstatus):
    before = session.config.stash.get(_STATUS_KEY, None)
    if before is None:
        return
    new = sorted((_checkout_status() or set()) - before)
    if new:
        reporter = session.config.pluginmanager.get_plugin("terminalreporter")
        if reporter is not None:
            reporter.write("\n")
            reporter.write_sep("=", "tests changed the checkout (write under tmp_path instead)", red=True, bold=True)
            for line in new:
                reporter.write_line(f"  {line}", red=True)
        session.exitstatus = pytest.ExitCode.TESTS_FAILED


# ---- doctests of features behind an optional extra --------------------------------------------
# A module that imports an extra's package (at module level or lazily, as metrics.py imports evo),
# or imports relatively a module that does (api/compare.py), has its doctests skipped when that
# package is absent, naming the extra; with the test extra installed (as CI does) they all run.
OPTIONAL_PACKAGES = {"evo": "evo", "rdata": "rda"}


@cache
def _imports(path: str) -> tuple[set, list]:
    """(top-level packages imported, paths of the modules imported relatively) of a module."""
    try:
        tree = ast.parse(Path(path).read_text(encoding="utf-8"))
    except (OSError, SyntaxError, UnicodeDecodeError):
        return set(), []
    names, local = set(), []
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            names.update(a.name.split(".")[0] for a in node.names)
        elif isinstance(node, ast.ImportFrom) and node.level == 0 and node.module:
            names.add(node.module.split(".")[0])
        elif isinstance(node, ast.ImportFrom) and node.module:
            base = Path(path).parents[node.level - 1].joinpath(*node.module.split("."))
            local += [str(p) for p in (base.with_suffix(".py"), base / "__init__.py") if p.exists()]
    return names, local


@cache
def _missing_extras(path: str) -> tuple[str, ...]:
    names, local = _imports(path)
    names = names.union(*(_imports(m)[0] for m in local))
    return tuple(sorted(OPTIONAL_PACKAGES[n] for n in names & set(OPTIONAL_PACKAGES)
                        if importlib.util.find_spec(n) is None))


def pytest_collection_modifyitems(config, items):
    for item in items:
        if type(item).__name__ == "DoctestItem":
            missing = _missing_extras(str(item.path))
            if missing:
                extras = ",".join(missing)
                item.add_marker(pytest.mark.skip(reason=f"needs the optional extra: pip install 'splineimu[{extras}]'"))
