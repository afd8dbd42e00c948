"""``features.csv``: one row per landmark observation, ``timestamp_ns,landmark_id,u,v``.

The header line starts with ``#`` (as EuRoC's csv files); stamps are the frame stamps on the
camera clock in integer nanoseconds; ``u, v`` are written with Python's shortest round-trip
``repr``, so reading them back gives the same doubles bit for bit. The writer is
:func:`splineimu.io.camera.write_features_csv`.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ..errors import InputError

__all__ = ["features_csv_text", "read_features_csv", "FEATURES_HEADER"]

FEATURES_HEADER = "#timestamp_ns,landmark_id,u,v"


def features_csv_text(observations) -> str:
    """The text of a ``features.csv`` (written by :func:`splineimu.io.camera.write_features_csv`):
    the header and one row per observation of ``observations`` (``t_ns``, ``landmark_id``, ``u``, ``v``)."""
    t = np.asarray(observations.t_ns, dtype=np.int64).tolist()
    ids = np.asarray(observations.landmark_id, dtype=np.int64).tolist()
    u = np.asarray(observations.u, dtype=np.float64).tolist()
    v = np.asarray(observations.v, dtype=np.float64).tolist()
    body = "".join([f"{a},{b},{c!r},{d!r}\n" for a, b, c, d in zip(t, ids, u, v)])
    return FEATURES_HEADER + "\n" + body


def read_features_csv(path) -> dict:
    """Read a ``features.csv`` into arrays ``t_ns`` (int64), ``landmark_id`` (int64), ``u``, ``v``.

    Raises
    ------
    InputError
        Unreadable file or a row that is not ``int,int,float,float`` (with its line number).

    Examples
    --------
    >>> import tempfile, pathlib
    >>> p = pathlib.Path(tempfile.mkdtemp()) / "features.csv"
    >>> _ = p.write_text("#timestamp_ns,landmark_id,u,v\\n5,1,2.5,3.5\\n")
    >>> {k: a.tolist() for k, a in read_features_csv(p).items()}
    {'t_ns': [5], 'landmark_id': [1], 'u': [2.5], 'v': [3.5]}
    """
    path = Path(path)
    try:
        lines = path.read_text(encoding="utf-8").splitlines()
    except OSError as exc:
        raise InputError(f"cannot read features: {exc.strerror or exc}", path=path) from None
    t, ids, u, v = [], [], [], []
    for lineno, line in enumerate(lines, start=1):
        if not line.strip() or line.startswith("#"):
            continue
        parts = line.split(",")
        try:
            if len(parts) != 4:
                raise ValueError
            t.append(int(parts[0]))
            ids.append(int(parts[1]))
            u.append(float(parts[2]))
            v.append(float(parts[3]))
        except ValueError:
            raise InputError(f"expected timestamp_ns,landmark_id,u,v, got {line!r}", path=path, line=lineno) from None
    return {"t_ns": np.array(t, dtype=np.int64), "landmark_id": np.array(ids, dtype=np.int64),
            "u": np.array(u, dtype=np.float64), "v": np.array(v, dtype=np.float64)}
