"""Audit: run about a hundred cases through every command as a new user would.

Malformed inputs to every reader and command, resource limits under a 3 GB address-space cap,
output-path faults and signals during long writes, and semantic traps (wrong units, wrong
format, NaN, null keys). Each case runs the command line in a subprocess in a fresh folder and
is *held* when:

- ``error`` cases: the exit code is non-zero (not a signal death), stderr has no traceback and
  at most a few lines, it matches the expected words, and nothing in the folder changed;
- ``ok`` cases: exit code 0, no traceback, and the case's own check passed;
- every case: no temporary (``.name.tmp-*`` / ``.name.old-*``) left behind, files that
  existed before unchanged unless the case replaces them, finished within its time limit.

Not part of the test suite (it takes minutes). Run from the repository root::

    python tools/audit_inputs.py [--jobs 2] [--only REGEX] [--verbose]
"""

from __future__ import annotations

import argparse
import concurrent.futures as cf
import hashlib
import os
import re
import resource
import shutil
import signal
import subprocess
import sys
import tempfile
import time
from dataclasses import dataclass, field
from pathlib import Path

REPO = Path(__file__).resolve().parent.parent
SHARED = REPO.parent / "shared" / "data"
MEM_CAP = 3 * 1024**3
CATEGORIES = {"input": "malformed inputs and options", "resource": "resource limits (3 GB cap)",
              "output": "output faults and signals", "semantic": "semantic traps"}


@dataclass
class Case:
    cat: str
    name: str
    argv: list
    expect: str = "error"  # error | ok | any
    setup: object = None  # setup(d: Path)
    check: object = None  # check(d: Path, proc) -> str or None (what is wrong)
    words: tuple = ()  # regexes that must occur in stderr (error cases)
    timeout: float = 180.0
    may_change: tuple = ()  # pre-existing files the case may replace
    sig: tuple | None = None  # (signal, wait_for_glob, delay_s)
    user: str | None = None  # run as this user (root only)


@dataclass
class Outcome:
    case: Case
    held: bool
    why: str = ""
    rc: int | None = None
    seconds: float = 0.0
    stderr: str = ""
    extra: list = field(default_factory=list)


# ------------------------------------------------------------------ input files


def _w(d: Path, name: str, text) -> Path:
    p = d / name
    p.parent.mkdir(parents=True, exist_ok=True)
    if isinstance(text, bytes):
        p.write_bytes(text)
    else:
        p.write_text(text)
    return p


def tum_text(n=300, dt=0.01, t0=1700000000.0, scale=1.0, fmt="{:.9f}"):
    import math

    lines = ["# timestamp tx ty tz qx qy qz qw"]
    for i in range(n):
        t = t0 + i * dt
        a = 0.3 * i * dt
        lines.append(f"{fmt.format(t * scale)} {2 * math.cos(a):.6f} {math.sin(a):.6f} 1.0 0 0 "
                     f"{math.sin(a / 2):.9f} {math.cos(a / 2):.9f}")
    return "\n".join(lines) + "\n"


def euroc_gt_text(n=300, dt_ns=10_000_000, t0=1_400_000_000_000_000_000, stamp=None):
    import math

    lines = ["#timestamp, p_RS_R_x [m], p_RS_R_y [m], p_RS_R_z [m], q_RS_w [], q_RS_x [], q_RS_y [], q_RS_z []"]
    for i in range(n):
        t = t0 + i * dt_ns
        a = 0.3 * i * dt_ns / 1e9
        st = stamp(i) if stamp else str(t)
        lines.append(f"{st},{2 * math.cos(a):.6f},{math.sin(a):.6f},1.0,{math.cos(a / 2):.9f},0,0,"
                     f"{math.sin(a / 2):.9f}")
    return "\n".join(lines) + "\n"


def imu_csv_text(n=400, dt_ns=5_000_000, t0=1_000_000_000, stamp=None):
    lines = ["#timestamp [ns],w_RS_S_x [rad s^-1],w_RS_S_y [rad s^-1],w_RS_S_z [rad s^-1],"
             "a_RS_S_x [m s^-2],a_RS_S_y [m s^-2],a_RS_S_z [m s^-2]"]
    for i in range(n):
        st = stamp(i) if stamp else str(t0 + i * dt_ns)
        lines.append(f"{st},0.001,-0.002,0.0005,0.01,-0.02,9.81")
    return "\n".join(lines) + "\n"


def deep_yaml(depth=10000):
    return "a: " + "[" * depth + "]" * depth + "\n"


def alias_bomb():
    lines = ['a: &a ["x","x","x","x","x","x","x","x","x"]']
    prev = "a"
    for k in "bcdefghijk":
        lines.append(f"{k}: &{k} [" + ",".join([f"*{prev}"] * 9) + "]")
        prev = k
    return "\n".join(lines) + "\n"


def big_line(d: Path, name: str, size=1 << 30):
    """A 1 GB text file of one line (made once, hard-linked into each case)."""
    src = CACHE / "big_line.txt"
    if not src.exists():
        part = CACHE / "big_line.part"
        with open(part, "wb") as f:
            f.write(b"1700000000.0 1 2 3 0 0 0 1 ")
            block = b"1234567 " * (1 << 17)
            for _ in range(size // len(block)):
                f.write(block)
        os.replace(part, src)
    p = d / name
    os.link(src, p)
    return p


def base(d: Path):
    """An output folder of a short noisy scene (and its poses as TUM) to feed the analysis commands."""
    src = CACHE / "base"
    shutil.copytree(src, d / "base", symlinks=True)


CACHE = Path()
IMU_CSV = "base/imu0/data.csv"  # set by make_cache: the layout of the output folder
GT_CSV = "base/state_groundtruth_estimate0/data.csv"


def make_cache(root: Path, py: str, env: dict):
    global CACHE, IMU_CSV, GT_CSV
    CACHE = root / "cache"
    CACHE.mkdir(parents=True, exist_ok=True)
    if not (CACHE / "base" / "report.json").exists():
        subprocess.run([py, "-m", "splineimu", "scene", "ellipse", "--duration", "8", "--imu", "adis16448",
                        "--seed", "1", "-o", str(CACHE / "base"), "--tum", str(CACHE / "base.tum"), "--force"],
                       env=env, check=True, capture_output=True)
        shutil.move(str(CACHE / "base.tum"), str(CACHE / "base" / "poses.tum"))
    big_line(root, "big_probe.txt")
    found = sorted(str(p.relative_to(CACHE)) for p in (CACHE / "base").rglob("imu0/data.csv"))
    IMU_CSV = found[0]
    GT_CSV = IMU_CSV.replace("imu0/data.csv", "state_groundtruth_estimate0/data.csv")


# ------------------------------------------------------------------ checks


def no_file(*names):
    def check(d, proc):
        for n in names:
            if (d / n).exists():
                return f"{n} exists"
    return check


def file_has(name, pattern):
    def check(d, proc):
        p = d / name
        if not p.exists():
            return f"{name} missing"
        if not re.search(pattern, p.read_text(errors="replace")):
            return f"{name} lacks {pattern!r}"
    return check


def out_has(pattern):
    def check(d, proc):
        if not re.search(pattern, proc.stdout + proc.stderr):
            return f"output lacks {pattern!r}"
    return check


def same_folders(a, b):
    def check(d, proc):
        pa, pb = d / a, d / b
        fa = {p.relative_to(pa): p for p in pa.rglob("*") if p.is_file()}
        fb = {p.relative_to(pb): p for p in pb.rglob("*") if p.is_file()}
        if set(fa) != set(fb):
            return "different file sets"
        for k in fa:
            if fa[k].read_bytes() != fb[k].read_bytes():
                return f"{k} differs"
    return check


# ------------------------------------------------------------------ the cases


def cases() -> list:
    C = []

    def add(cat, name, argv, **kw):
        C.append(Case(cat, name, argv, **kw))

    good_tum = lambda d: _w(d, "p.tum", tum_text())  # noqa: E731

    def tum_with(lines_fn):
        def s(d):
            _w(d, "p.tum", lines_fn())
        return s

    # ---------------------------------------------------- malformed inputs and options
    add("input", "from-tum: missing file", ["from-tum", "nope.tum", "-o", "out"], words=(r"nope\.tum",))
    add("input", "from-tum: a folder", ["from-tum", "dir", "-o", "out"], setup=lambda d: (d / "dir").mkdir())
    add("input", "from-tum: empty file", ["from-tum", "p.tum", "-o", "out"], setup=tum_with(lambda: ""))
    add("input", "from-tum: comments only", ["from-tum", "p.tum", "-o", "out"], setup=tum_with(lambda: "# a\n# b\n"))
    add("input", "from-tum: random bytes", ["from-tum", "p.tum", "-o", "out"],
        setup=lambda d: _w(d, "p.tum", bytes(range(256)) * 40))
    add("input", "from-tum: non-UTF-8 line", ["from-tum", "p.tum", "-o", "out"],
        setup=lambda d: _w(d, "p.tum", tum_text().encode() + b"1700000010.0 1 2 \xff\xfe 0 0 0 1\n"))
    add("input", "from-tum: 7 columns", ["from-tum", "p.tum", "-o", "out"],
        setup=tum_with(lambda: "\n".join(" ".join(ln.split()[:7]) for ln in tum_text().splitlines()[1:])))
    add("input", "from-tum: NaN position", ["from-tum", "p.tum", "-o", "out"],
        setup=tum_with(lambda: tum_text().replace(" 1.0 0 0 ", " nan 0 0 ", 1)), words=(r":\d+:",))
    add("input", "from-tum: inf quaternion", ["from-tum", "p.tum", "-o", "out"],
        setup=tum_with(lambda: tum_text()[:-1].rsplit(" ", 1)[0] + " inf\n"), words=(r":\d+:",))
    add("input", "from-tum: zero quaternion", ["from-tum", "p.tum", "-o", "out"],
        setup=tum_with(lambda: tum_text() + "1700000009.0 0 0 0 0 0 0 0\n"), words=(r":\d+:",))
    add("input", "from-tum: stamps go back", ["from-tum", "p.tum", "-o", "out"],
        setup=tum_with(lambda: tum_text() + "1700000000.5 0 0 0 0 0 0 1\n"), words=(r":\d+:",))
    add("input", "from-tum: text in a number", ["from-tum", "p.tum", "-o", "out"],
        setup=tum_with(lambda: tum_text().replace(" 1.0 0 0 ", " one 0 0 ", 1)), words=(r":\d+:",))
    add("input", "from-tum: one pose", ["from-tum", "p.tum", "-o", "out"],
        setup=tum_with(lambda: "\n".join(tum_text().splitlines()[:2]) + "\n"))
    add("input", "from-tum: comma separated", ["from-tum", "p.tum", "-o", "out"], expect="any",
        setup=tum_with(lambda: tum_text().replace(" ", ",")))
    for flag, val in [("--rate", "0"), ("--rate", "-5"), ("--rate", "nan"), ("--rate", "inf"), ("--order", "9"),
                      ("--order", "abc"), ("--knot-spacing", "-1"), ("--knot-spacing", "nan"),
                      ("--smoothness", "-1"), ("--smoothness", "nan"), ("--seed", "-1"),
                      ("--gravity", "nan")]:
        argv = ["from-tum", "p.tum", "-o", "out", flag, val] + (["0", "0"] if flag == "--gravity" else [])
        add("input", f"from-tum: {flag} {val}", argv, setup=good_tum, words=(re.escape(flag) + "|seed",))
    add("input", "from-tum: --imu missing file", ["from-tum", "p.tum", "-o", "out", "--imu", "nope.yaml"],
        setup=good_tum, words=("nope",))
    add("input", "from-tum: --imu yaml syntax error", ["from-tum", "p.tum", "-o", "out", "--imu", "i.yaml"],
        setup=lambda d: (good_tum(d), _w(d, "i.yaml", "a: [1, 2\nb: }\n")), words=(r"i\.yaml",))
    add("input", "from-tum: --imu negative density", ["from-tum", "p.tum", "-o", "out", "--imu", "i.yaml"],
        setup=lambda d: (good_tum(d), _w(d, "i.yaml", "gyroscope_noise_density: -1\naccelerometer_noise_density: 1"
                                                   "\ngyroscope_random_walk: 0\naccelerometer_random_walk: 0\n")),
        words=(r"i\.yaml",))
    add("input", "from-tum: --imu non-UTF-8", ["from-tum", "p.tum", "-o", "out", "--imu", "i.yaml"],
        setup=lambda d: (good_tum(d), _w(d, "i.yaml", b"gyroscope_noise_density: 0.1 # \xff\xfe\n")),
        words=(r"i\.yaml",))
    add("input", "from-tum: --imu 10000-deep nesting", ["from-tum", "p.tum", "-o", "out", "--imu", "i.yaml"],
        setup=lambda d: (good_tum(d), _w(d, "i.yaml", deep_yaml())), words=(r"i\.yaml",))
    add("input", "from-tum: --imu alias bomb", ["from-tum", "p.tum", "-o", "out", "--imu", "i.yaml"],
        setup=lambda d: (good_tum(d), _w(d, "i.yaml", alias_bomb())), words=(r"i\.yaml",), timeout=60)
    add("input", "from-tum: --imu unknown preset", ["from-tum", "p.tum", "-o", "out", "--imu", "adis99999"],
        setup=good_tum)
    add("input", "from-tum: --extrinsic not a rotation", ["from-tum", "p.tum", "-o", "out", "--extrinsic", "e.yaml"],
        setup=lambda d: (good_tum(d), _w(d, "e.yaml", "T_BS: [[2,0,0,0],[0,1,0,0],[0,0,1,0],[0,0,0,1]]\n")),
        words=(r"e\.yaml",))
    add("input", "from-tum: --extrinsic deep nesting", ["from-tum", "p.tum", "-o", "out", "--extrinsic", "e.yaml"],
        setup=lambda d: (good_tum(d), _w(d, "e.yaml", deep_yaml())), words=(r"e\.yaml",))
    add("input", "from-tum: --extrinsic no transform", ["from-tum", "p.tum", "-o", "out", "--extrinsic", "e.yaml"],
        setup=lambda d: (good_tum(d), _w(d, "e.yaml", "foo: 1\n")), words=(r"e\.yaml",))
    add("input", "from-tum: --timestamps empty", ["from-tum", "p.tum", "-o", "out", "--timestamps", "s.csv"],
        setup=lambda d: (good_tum(d), _w(d, "s.csv", "")), words=(r"s\.csv",))
    add("input", "from-tum: --timestamps garbage", ["from-tum", "p.tum", "-o", "out", "--timestamps", "s.csv"],
        setup=lambda d: (good_tum(d), _w(d, "s.csv", "hello\nworld\n")), words=(r"s\.csv",))
    add("input", "from-euroc: 5 columns", ["from-euroc", "g.csv", "-o", "out"],
        setup=lambda d: _w(d, "g.csv", "\n".join(",".join(ln.split(",")[:5]) for ln in euroc_gt_text().splitlines())))
    add("input", "from-euroc: NaN", ["from-euroc", "g.csv", "-o", "out"],
        setup=lambda d: _w(d, "g.csv", euroc_gt_text().replace(",1.0,", ",nan,", 1)), words=(r":\d+:",))
    add("input", "from-euroc: random bytes", ["from-euroc", "g.csv", "-o", "out"],
        setup=lambda d: _w(d, "g.csv", os.urandom(3000)))

    def scene_file(text):
        return lambda d: _w(d, "s.yaml", text)

    good_motion = "motion: {scene: static, duration_s: 2}\nimu: {rate_hz: 100}\n"
    add("input", "run: missing scene file", ["run", "nope.yaml"], words=("nope",))
    add("input", "run: a list, not a mapping", ["run", "s.yaml"], setup=scene_file("- 1\n- 2\n"), words=(r"s\.yaml",))
    add("input", "run: unknown top-level key", ["run", "s.yaml"],
        setup=scene_file(good_motion + "output: {dir: out}\nsede: 1\n"), words=(r"s\.yaml:\d+",))
    add("input", "run: unknown motion key", ["run", "s.yaml"],
        setup=scene_file("motion: {scene: static, duraton_s: 2}\noutput: {dir: out}\n"), words=(r"s\.yaml:\d+",))
    add("input", "run: no motion", ["run", "s.yaml"], setup=scene_file("output: {dir: out}\n"), words=(r"s\.yaml",))
    add("input", "run: unknown scene", ["run", "s.yaml"],
        setup=scene_file("motion: {scene: nosuch}\noutput: {dir: out}\n"), words=(r"s\.yaml",))
    add("input", "run: deep nesting", ["run", "s.yaml"], setup=scene_file(deep_yaml()), words=(r"s\.yaml",))
    add("input", "run: alias bomb", ["run", "s.yaml"], setup=scene_file(alias_bomb()), words=(r"s\.yaml",),
        timeout=60)
    add("input", "run: non-UTF-8", ["run", "s.yaml"],
        setup=lambda d: _w(d, "s.yaml", b"motion: {scene: static}\n# \xff\xfe\n"), words=(r"s\.yaml",))
    add("input", "run: rate_hz text", ["run", "s.yaml"],
        setup=scene_file("motion: {scene: static}\nimu: {rate_hz: fast}\noutput: {dir: out}\n"),
        words=(r"s\.yaml:\d+",))
    add("input", "run: rate_hz negative", ["run", "s.yaml"],
        setup=scene_file("motion: {scene: static}\nimu: {rate_hz: -5}\noutput: {dir: out}\n"),
        words=(r"s\.yaml:\d+",))
    add("input", "run: random bytes", ["run", "s.yaml"], setup=lambda d: _w(d, "s.yaml", os.urandom(2000)))
    add("input", "scene: unknown name", ["scene", "nosuch", "-o", "out"])
    add("input", "scene: no name", ["scene", "-o", "out"])
    add("input", "scene: --duration -1", ["scene", "static", "--duration", "-1", "-o", "out"], words=("duration",))
    add("input", "scene: --duration nan", ["scene", "static", "--duration", "nan", "-o", "out"], words=("duration",))
    add("input", "scene: --param unknown", ["scene", "ellipse", "--param", "bogus=1", "-o", "out"], words=("bogus",))
    add("input", "scene: --param not a number", ["scene", "ellipse", "--param", "k1=abc", "-o", "out"],
        words=("k1",))
    add("input", "scene: --t0-ns negative", ["scene", "static", "--t0-ns", "-5", "--duration", "1", "-o", "out"],
        expect="any")

    add("input", "integrate: missing csv", ["integrate", "nope.csv", "-o", "t.tum"], words=("nope",))
    add("input", "integrate: 4 columns", ["integrate", "i.csv", "-o", "t.tum"],
        setup=lambda d: _w(d, "i.csv", "\n".join(",".join(ln.split(",")[:4]) for ln in imu_csv_text().splitlines())))
    add("input", "integrate: NaN sample", ["integrate", IMU_CSV, "-o", "t.tum"],
        setup=lambda d: (base(d), _nan_row(d / IMU_CSV)), words=(r":\d+:",))
    add("input", "integrate: --init missing", ["integrate", IMU_CSV, "--init", "nope.csv", "-o", "t.tum"],
        setup=base, words=("nope",))
    add("input", "integrate: random bytes", ["integrate", "i.csv", "-o", "t.tum"],
        setup=lambda d: _w(d, "i.csv", os.urandom(3000)))
    add("input", "preintegrate: missing folder", ["preintegrate", "nope"], words=("nope",))
    add("input", "preintegrate: --every 0", ["preintegrate", "base", "--every", "0"], setup=base, words=("every",))
    add("input", "preintegrate: --every -3", ["preintegrate", "base", "--every", "-3"], setup=base, words=("every",))
    add("input", "preintegrate: --stamps garbage", ["preintegrate", "base", "--stamps", "s.csv"],
        setup=lambda d: (base(d), _w(d, "s.csv", "a\nb\n")), words=(r"s\.csv",))
    add("input", "allan: empty csv", ["allan", "i.csv"], setup=lambda d: _w(d, "i.csv", ""))
    add("input", "allan: 10 samples", ["allan", "i.csv"], setup=lambda d: _w(d, "i.csv", imu_csv_text(10)))
    add("input", "allan: --points-per-decade 0", ["allan", IMU_CSV, "--points-per-decade", "0"],
        setup=base, words=("points-per-decade",))
    add("input", "allan: --rate -1", ["allan", IMU_CSV, "--rate", "-1"], setup=base, words=("rate",))
    add("input", "allan: .rda garbage", ["allan", "x.rda"], setup=lambda d: _w(d, "x.rda", os.urandom(500)))
    add("input", "compare: missing est", ["compare", "nope.tum", "base/poses.tum"], setup=base, words=("nope",))
    add("input", "compare: no common stamps", ["compare", "a.tum", "b.tum"],
        setup=lambda d: (_w(d, "a.tum", tum_text()), _w(d, "b.tum", tum_text(t0=1800000000.0))))
    add("input", "compare: random bytes", ["compare", "a.tum", "b.tum"],
        setup=lambda d: (_w(d, "a.tum", os.urandom(2000)), _w(d, "b.tum", tum_text())))
    add("input", "compare: --t-max-diff -1", ["compare", "a.tum", "a.tum", "--t-max-diff", "-1"],
        setup=lambda d: _w(d, "a.tum", tum_text()), words=("t.max.diff",))
    add("input", "calibrate: random bytes", ["calibrate", "accel", "i.csv"],
        setup=lambda d: _w(d, "i.csv", os.urandom(3000)))
    add("input", "calibrate: moving data", ["calibrate", "accel", IMU_CSV], setup=base)
    add("input", "calibrate: --window 0", ["calibrate", "accel", IMU_CSV, "--window", "0"],
        setup=base, words=("window",))
    add("input", "calibrate: no sensor", ["calibrate"], expect="error")

    # ---------------------------------------------------- resources under a 3 GB cap
    add("resource", "scene static 500000 s at 1000 Hz", ["scene", "static", "--duration", "500000", "--rate", "1000",
                                                          "-o", "out"], words=("GB|MB|samples",), timeout=120)
    add("resource", "scene static 500000 s at 1000 Hz --bag", ["scene", "static", "--duration", "500000", "--rate",
                                                                "1000", "--bag", "ros2", "-o", "out"], timeout=120)
    add("resource", "from-tum --rate 1e9", ["from-tum", "p.tum", "-o", "out", "--rate", "1e9"], setup=good_tum,
        timeout=120)
    add("resource", "1 GB single-line TUM", ["from-tum", "p.tum", "-o", "out"],
        setup=lambda d: big_line(d, "p.tum"), words=("line",), timeout=120)
    add("resource", "1 GB single-line --timestamps", ["scene", "static", "--duration", "2", "--timestamps", "s.csv",
                                                       "-o", "out"], setup=lambda d: big_line(d, "s.csv"),
        words=("line",), timeout=120)
    add("resource", "1 GB single-line imu csv (integrate)", ["integrate", "i.csv", "-o", "t.tum"],
        setup=lambda d: big_line(d, "i.csv"), words=("line",), timeout=120)
    add("resource", "1 GB single-line imu csv (allan)", ["allan", "i.csv"],
        setup=lambda d: big_line(d, "i.csv"), words=("line",), timeout=120)
    add("resource", "1 GB single-line scene file", ["run", "s.yaml"],
        setup=lambda d: big_line(d, "s.yaml"), timeout=120)
    add("resource", "scene --tum 500000 s at 1000 Hz", ["scene", "static", "--duration", "500000", "--rate", "1000",
                                                         "--tum", "p.tum"], timeout=120)
    add("resource", "scene --plot 50000 s at 1000 Hz", ["scene", "static", "--duration", "50000", "--rate", "1000",
                                                         "--plot", "-o", "out"], timeout=120)

    # ---------------------------------------------------- output faults and signals
    def existing(name, text="precious\n"):
        return lambda d: _w(d, name, text)

    add("output", "read-only folder", ["scene", "static", "--duration", "1", "-o", "/sys/splineimu_out"],
        words=("splineimu_out",))
    add("output", "-o under a file", ["scene", "static", "--duration", "1", "-o", "f.txt/out"],
        setup=existing("f.txt"), words=(r"f\.txt",))
    add("output", "-o name too long", ["scene", "static", "--duration", "1", "-o", "x" * 300], words=("xxxx",))
    add("output", "-o empty string", ["scene", "static", "--duration", "1", "-o", ""])
    add("output", "existing folder, no --force", ["scene", "static", "--duration", "1", "-o", "out"],
        setup=existing("out/keep.txt"), words=("force",))
    add("output", "integrate -o existing file", ["integrate", IMU_CSV, "-o", "t.tum"],
        setup=lambda d: (base(d), existing("t.tum")(d)), words=("force",))
    add("output", "preintegrate -o existing file", ["preintegrate", "base", "-o", "w.csv"],
        setup=lambda d: (base(d), existing("w.csv")(d)), words=("force",))
    add("output", "scene --tum existing file", ["scene", "static", "--duration", "1", "--tum", "p.tum"],
        setup=existing("p.tum"), words=("force",))
    add("output", "compare --plot existing file", ["compare", "base/poses.tum", "base/poses.tum", "--plot", "c.png"],
        setup=lambda d: (base(d), existing("c.png")(d)), words=("force",))
    add("output", "allan -o existing allan.yaml", ["allan", IMU_CSV, "-o", "al"],
        setup=lambda d: (base(d), existing("al/allan.yaml")(d)), words=("force",))
    add("output", "integrate -o its input --force", ["integrate", IMU_CSV, "-o", IMU_CSV,
                                                      "--force"], setup=base, words=("input",))
    add("output", "from-tum -o its input --force", ["from-tum", "p.tum", "-o", "p.tum", "--force"], setup=good_tum,
        words=("input",))
    add("output", "integrate -o symlink", ["integrate", IMU_CSV, "-o", "link.tum", "--force"],
        setup=lambda d: (base(d), existing("victim.tum")(d), os.symlink("victim.tum", d / "link.tum")),
        words=("symlink|link",))
    add("output", "scene -o symlink to a folder", ["scene", "static", "--duration", "1", "-o", "link", "--force"],
        setup=lambda d: (existing("victim/keep.txt")(d), os.symlink("victim", d / "link")), words=("link",))
    add("output", "from-tum -o the folder holding the input --force", ["from-tum", "in/p.tum", "-o", "in", "--force"],
        setup=lambda d: _w(d, "in/p.tum", tum_text()), words=("input",))
    add("output", "preintegrate -o its ground truth --force",
        ["preintegrate", "base", "-o", GT_CSV, "--force"], setup=base,
        words=("input",))
    add("output", "calibrate -o holding a symlinked calibration.yaml", ["calibrate", "accel", IMU_CSV,
                                                                         "-o", "cal"],
        setup=lambda d: (base(d), existing("victim.yaml")(d), (d / "cal").mkdir(),
                         os.symlink("../victim.yaml", d / "cal" / "calibration.yaml")), words=("link",))
    add("output", "scene --bag ros2 with stamps past 2038", ["scene", "static", "--duration", "1", "--t0-ns",
                                                             "4500000000000000000", "--bag", "ros2", "-o", "out"],
        words=("2038|2\\*\\*31",))
    add("output", "scene --bag ros1 with stamps past 2106", ["scene", "static", "--duration", "1", "--t0-ns",
                                                             "4500000000000000000", "--bag", "ros1", "-o", "out"],
        words=("2\\*\\*32",))
    long_scene = ["scene", "static", "--duration", "30000", "--imu", "adis16448", "--seed", "1", "-o", "X"]
    add("output", "SIGTERM during a long write", long_scene, sig=(signal.SIGTERM, ".X.tmp-*/**/imu0/data.csv", 0.3),
        check=no_file("X"))
    add("output", "SIGINT during a long write", long_scene, sig=(signal.SIGINT, ".X.tmp-*/**/imu0/data.csv", 0.3),
        check=no_file("X"))
    add("output", "SIGTERM during --force replace", long_scene + ["--force"],
        setup=existing("X/keep.txt"), sig=(signal.SIGTERM, ".X.tmp-*/**/imu0/data.csv", 0.3))
    add("output", "SIGTERM during scene --tum", ["scene", "static", "--duration", "3000", "--rate", "1000",
                                                 "--tum", "p.tum"], sig=(signal.SIGTERM, ".p.tum.tmp-*", 0.1),
        check=no_file("p.tum"))
    # ---------------------------------------------------- semantic traps
    add("semantic", "EuRoC imu stamps in integer seconds", ["integrate", "i.csv", "--init", "g.csv", "-o", "t.tum"],
        setup=lambda d: (_w(d, "i.csv", imu_csv_text(stamp=lambda i: str(1000 + i))),
                         _w(d, "g.csv", euroc_gt_text())), words=("second",))
    add("semantic", "EuRoC ground truth in decimal seconds (read as s)", ["from-euroc", "g.csv", "-o", "out"],
        setup=lambda d: _w(d, "g.csv", euroc_gt_text(stamp=lambda i: f"{1400000000 + i * 0.01:.2f}")),
        expect="ok", check=file_has("out/report.json", r'"last_ns": 14000000029900000'))
    add("semantic", "EuRoC ground truth in integer seconds", ["from-euroc", "g.csv", "-o", "out"],
        setup=lambda d: _w(d, "g.csv", euroc_gt_text(stamp=lambda i: str(1400000000 + i))), words=("second",))
    add("semantic", "TUM stamps in milliseconds", ["from-tum", "p.tum", "-o", "out"],
        setup=tum_with(lambda: tum_text(scale=1000.0, fmt="{:.3f}")), words=("millisecond",))
    add("semantic", "TUM stamps in nanoseconds", ["from-tum", "p.tum", "-o", "out"],
        setup=tum_with(lambda: tum_text(scale=1e9, fmt="{:.0f}")), words=("nanosecond",))
    add("semantic", "TUM file given to from-euroc", ["from-euroc", "p.tum", "-o", "out"], setup=good_tum,
        words=("TUM",))
    add("semantic", "EuRoC imu csv given as poses", ["from-tum", IMU_CSV, "-o", "out"], setup=base,
        words=("IMU|imu",))
    add("semantic", "EuRoC imu csv given to from-euroc", ["from-euroc", IMU_CSV, "-o", "out"],
        setup=base, words=("IMU|imu",))
    add("semantic", "EuRoC ground truth given to from-tum", ["from-tum", "g.csv", "-o", "out"],
        setup=lambda d: _w(d, "g.csv", euroc_gt_text()), words=("EuRoC|from-euroc",))
    add("semantic", "compare with NaN", ["compare", "a.tum", "b.tum"],
        setup=lambda d: (_w(d, "a.tum", tum_text().replace(" 1.0 0 0 ", " nan 0 0 ", 3)), _w(d, "b.tum", tum_text())),
        words=(r"a\.tum:\d+",))
    add("semantic", "scene file output dir null", ["run", "s.yaml"],
        setup=scene_file(good_motion + "output: {dir: null}\n"), check=no_file("None"), words=(r"s\.yaml:\d+",))
    add("semantic", "scene file seed: abc", ["run", "s.yaml"],
        setup=scene_file(good_motion + "seed: abc\noutput: {dir: out}\n"), words=(r"s\.yaml:\d+",))
    add("semantic", "scene file seed: 1.5", ["run", "s.yaml"],
        setup=scene_file(good_motion + "seed: 1.5\noutput: {dir: out}\n"), words=(r"s\.yaml:\d+",))
    add("semantic", "scene file seed: -3", ["run", "s.yaml"],
        setup=scene_file(good_motion + "seed: -3\noutput: {dir: out}\n"), words=(r"s\.yaml:\d+",))
    add("semantic", "--max-gap 0", ["from-tum", "p.tum", "-o", "out", "--max-gap", "0"], setup=good_tum,
        words=("max-gap",))
    add("semantic", "--max-gap -1", ["from-tum", "p.tum", "-o", "out", "--max-gap", "-1"], setup=good_tum,
        words=("max-gap",))
    add("semantic", "too few poses for the knot choice (3)", ["from-tum", "p.tum", "-o", "out"],
        setup=tum_with(lambda: tum_text(3)), expect="any")
    add("semantic", "too few poses, order 6 (5 poses)", ["from-tum", "p.tum", "-o", "out", "--order", "6"],
        setup=tum_with(lambda: tum_text(5)), expect="any")
    add("semantic", "--timestamps seconds in a ns column", ["scene", "static", "--duration", "5", "--timestamps",
                                                            "s.csv", "-o", "out"],
        setup=lambda d: _w(d, "s.csv", "\n".join(str(i) for i in range(5)) + "\n"), words=("second",))
    add("semantic", "compare a trajectory with itself: zero error", ["compare", "base/poses.tum", "base/poses.tum"],
        setup=base, expect="ok", check=out_has(r"rmse\s+0(\.0+)?\s"))
    add("semantic", "scene file error names the file and line", ["run", "s.yaml"],
        setup=scene_file("motion: {scene: static}\nimu:\n  rate_hz: 200\n  sampling: average\noutput: {dir: out}\n"),
        words=(r"s\.yaml:4",))
    add("semantic", "same command twice: same bytes", ["scene", "ellipse", "--duration", "2", "--imu", "adis16448",
                                                       "--seed", "3", "-o", "b"],
        setup=lambda d: subprocess.run([sys.executable, "-m", "splineimu", "scene", "ellipse", "--duration", "2",
                                        "--imu", "adis16448", "--seed", "3", "-o", str(d / "a")],
                                       env=_env(), capture_output=True, cwd=d),
        expect="ok", check=same_folders("a", "b"))
    add("semantic", "from-tum twice: same bytes", ["from-tum", "p.tum", "--imu", "adis16448", "--seed", "3", "-o", "b"],
        setup=lambda d: (good_tum(d), subprocess.run([sys.executable, "-m", "splineimu", "from-tum", "p.tum", "--imu",
                                                      "adis16448", "--seed", "3", "-o", str(d / "a")],
                                                     env=_env(), capture_output=True, cwd=d)),
        expect="ok", check=same_folders("a", "b"))
    return C


def _nan_row(p: Path):
    lines = p.read_text().splitlines()
    parts = lines[5].split(",")
    parts[3] = "nan"
    lines[5] = ",".join(parts)
    p.write_text("\n".join(lines) + "\n")


# ------------------------------------------------------------------ running


def _env():
    env = dict(os.environ)
    env["PYTHONPATH"] = str(REPO)
    env.setdefault("NUMBA_CACHE_DIR", str(Path(tempfile.gettempdir()) / "splineimu_audit_numba"))
    return env


def _snapshot(d: Path) -> dict:
    out = {}
    for p in d.rglob("*"):
        if p.is_symlink():
            out[str(p.relative_to(d))] = "link:" + os.readlink(p)
        elif p.is_file():
            out[str(p.relative_to(d))] = hashlib.sha1(p.read_bytes()).hexdigest() if p.stat().st_size < 1 << 28 \
                else f"size:{p.stat().st_size}"
        elif p.is_dir():
            out[str(p.relative_to(d)) + "/"] = "dir"
    return out


TEMP_RE = re.compile(r"^\..*\.(tmp|old)-[0-9a-f]{8}$")


def _temporaries(d: Path):
    return [str(p.relative_to(d)) for p in d.rglob(".*") if TEMP_RE.match(p.name)]


def _preexec(user):
    def f():
        os.setsid()
        resource.setrlimit(resource.RLIMIT_AS, (MEM_CAP, MEM_CAP))
        if user:
            import pwd

            pw = pwd.getpwnam(user)
            os.setgid(pw.pw_gid)
            os.setuid(pw.pw_uid)
    return f


def run_case(case: Case, root: Path) -> Outcome:
    d = Path(tempfile.mkdtemp(prefix="case-", dir=root))
    os.chmod(d, 0o777)
    try:
        if case.setup:
            case.setup(d)
        if case.user:
            for p in [d, *d.rglob("*")]:
                if not p.is_symlink() and p.name != "ro":
                    os.chmod(p, 0o777 if p.is_dir() else 0o666)
        before = _snapshot(d)
        cmd = [sys.executable, "-m", "splineimu", *case.argv]
        t0 = time.monotonic()
        user = case.user if os.geteuid() == 0 else None
        proc = subprocess.Popen(cmd, cwd=d, env=_env(), stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                                errors="replace", preexec_fn=_preexec(user))
        if case.sig:
            sig, pattern, delay = case.sig
            deadline = time.monotonic() + case.timeout
            while pattern and not list(d.glob(pattern)) and proc.poll() is None and time.monotonic() < deadline:
                time.sleep(0.05)
            time.sleep(delay)
            if proc.poll() is None:
                os.kill(proc.pid, sig)
        try:
            out, err = proc.communicate(timeout=case.timeout)
        except subprocess.TimeoutExpired:
            os.killpg(proc.pid, signal.SIGKILL)
            out, err = proc.communicate()
            return Outcome(case, False, f"timeout after {case.timeout:g} s", None, time.monotonic() - t0, err)
        secs = time.monotonic() - t0
        proc.stdout, proc.stderr = out, err
        rc = proc.returncode
        why = _judge(case, d, proc, before)
        return Outcome(case, not why, why or "", rc, secs, err)
    except Exception as exc:  # the audit itself failed: count as not held, say why
        return Outcome(case, False, f"audit error: {type(exc).__name__}: {exc}")
    finally:
        shutil.rmtree(d, ignore_errors=True)


def _judge(case, d, proc, before) -> str | None:
    rc, err = proc.returncode, proc.stderr
    if "Traceback" in err:
        last = [ln for ln in err.strip().splitlines() if ln.strip()][-1:]
        return "traceback: " + (last[0][:100] if last else "")
    if rc is not None and rc < 0:
        return f"killed by signal {-rc}"
    temps = _temporaries(d)
    if temps:
        return f"temporaries left: {temps[:3]}"
    after = _snapshot(d)
    for k, v in before.items():
        if k not in case.may_change and after.get(k) != v and not k.endswith("/"):
            return f"pre-existing {k} changed"
    expect = "error" if case.sig and case.expect == "error" else case.expect
    lines = [ln for ln in err.strip().splitlines() if ln.strip() and not ln.startswith("note:")]
    if expect == "error" or (expect == "any" and rc != 0):
        if rc == 0:
            return "exit 0 (expected an error)"
        if case.sig is None and len(lines) > 4:
            return f"{len(lines)} lines on stderr"
        new = set(after) - set(before)
        new = [k for k in new if "__pycache__" not in k]
        if new and case.sig is None:
            return f"left new files: {sorted(new)[:3]}"
        for w in case.words if expect == "error" else ():
            if not re.search(w, err, re.I):
                return f"message lacks /{w}/: {lines[-1][:90] if lines else ''}"
    elif expect == "ok" and rc != 0:
        return f"exit {rc}: {lines[-1][:90] if lines else ''}"
    if case.check:
        return case.check(d, proc)
    return None


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--jobs", type=int, default=2)
    ap.add_argument("--only", metavar="REGEX", help="run the cases whose name matches")
    ap.add_argument("--verbose", action="store_true", help="print stderr of cases not held")
    args = ap.parse_args(argv)
    root = Path(tempfile.mkdtemp(prefix="splineimu-audit-"))
    os.chmod(root, 0o777)
    try:
        make_cache(root, sys.executable, _env())
        todo = [c for c in cases() if not args.only or re.search(args.only, c.name)]
        with cf.ThreadPoolExecutor(args.jobs) as ex:
            outcomes = list(ex.map(lambda c: run_case(c, root), todo))
    finally:
        shutil.rmtree(root, ignore_errors=True)
    width = max(len(o.case.name) for o in outcomes)
    print(f"{'category':9s} {'case':{width}s} {'expect':6s} {'held':4s} {'s':>6s}  why")
    for o in outcomes:
        print(f"{o.case.cat:9s} {o.case.name:{width}s} {o.case.expect:6s} {'yes' if o.held else 'NO':4s} "
              f"{o.seconds:6.1f}  {o.why}")
        if args.verbose and not o.held and o.stderr:
            print("    | " + "\n    | ".join(o.stderr.strip().splitlines()[-6:]))
    print()
    total = 0
    for cat, label in CATEGORIES.items():
        mine = [o for o in outcomes if o.case.cat == cat]
        held = sum(o.held for o in mine)
        total += held
        if mine:
            print(f"{label:32s} {held}/{len(mine)}")
    print(f"{'all':32s} {total}/{len(outcomes)}")
    return 0 if total == len(outcomes) else 1


if __name__ == "__main__":
    sys.exit(main())
